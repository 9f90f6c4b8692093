"""Side-on: where every view looks along one line, the joints that would turn the limbs
toward or away from the cameras become hinges about that line, as the paper tracks a body
seen by one camera, and the root turns only about it (``FrameFit.hold_turn_in_depth``).
The footage shows such a turn only as foreshortening, the same for either sign; in the
image plane, the body follows what the footage shows and what it does not is held. Views
that look different ways leave the body as it is."""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from . import se3
from .camera import Camera
from .linearize import Kinematics
from .pose import BodyPose
from .search import SIDE_ON
from .skeleton import HINGE, Skeleton

ONE_LINE_OF_SIGHT = np.cos(np.radians(15))  # views this close in direction see no depth
# how far the body may turn toward or away from the camera before the side-on hinges no
# longer turn in the image plane: the angle the limb search allows a hinge axis off the view
OUT_OF_SIDE_ON_DEG = float(np.degrees(np.arccos(SIDE_ON)))
BODY, TURNED = "body", "turned"  # the flag of a frame whose body turned out of side-on
# a bone seen shorter than this share of its length points nearly along the line of sight:
# its image angle is then anyone's, and a hinge whose range passes there is left free
FORESHORTENED = 0.2


def line_of_sight(pose: BodyPose, cameras: Sequence[Camera] | None = None) -> np.ndarray:
    """The line (a unit world direction) side-on's hinges turn about: the first view's at
    ``pose``, or, where that view's camera moves (``cameras``: it on every frame tracked),
    its mean over them. A body seen by a camera panning with it has one set of hinges for
    every frame; about the mean line each frame's own is at most half the pan off (a camera
    panning 46 degrees with a walker: the best fit of one view 13.0 degrees about the first
    frame's line, 5.6 about the mean, 5.5 for a still camera). A camera circling the body so far
    that the lines' mean cosine to their mean is under a half (a steady sweep of about 220
    degrees) has no such line; its first frame's is taken."""
    first = pose.views[0].orientation[2]
    if not cameras:
        return first
    mean = np.mean([c.orientation[2] for c in cameras], axis=0)
    norm = np.linalg.norm(mean)  # the lines' mean cosine to it
    return mean / norm if norm > 0.5 else first


def depth_blind_joints(skeleton: Skeleton, pose: BodyPose,
                       sight: np.ndarray | None = None) -> list[str]:
    """Names of the tracked joints that turn their limbs toward or away from the cameras
    when every view looks along one line (one view, or views within 15 degrees of it): the
    footage shows such a turn only as foreshortening, the same for either sign. A ball joint
    is always one; a hinge is not when its axis at ``pose`` lies within 25 degrees of the
    line of sight (``sight``, a world direction: the first view's at ``pose`` unless given;
    it turns in the image plane). Empty when the views look different ways."""
    lines = [v.orientation[2] for v in pose.views]
    if any(abs(lines[0] @ d) < ONE_LINE_OF_SIGHT for d in lines[1:]):
        return []
    sight = line_of_sight(pose) if sight is None else sight
    frames = Kinematics(skeleton, pose).frames
    blind = []
    for name in skeleton.tracked_joint_names():
        j = skeleton.index(name)
        if (skeleton.kinds[j] != HINGE
                or abs(sight @ frames[j, :3, :3] @ skeleton.axes[j]) < SIDE_ON):
            blind.append(name)
    return blind


def side_on_skeleton(skeleton: Skeleton, pose: BodyPose,
                     sight: np.ndarray | None = None) -> Skeleton:
    """``skeleton`` with every joint ``depth_blind_joints`` names at ``pose`` a hinge about
    the line of sight (``sight``, a unit world direction: the first view's at ``pose`` unless
    given; its axis in the joint's frame, its angle 0 at ``pose``): the paper's body for one
    camera. A limited hinge so remade keeps the image-plane angles its own range reaches
    from ``pose`` (``image_range``): an elbow seen obliquely still does not bend backward.
    ``skeleton`` itself when the views look different ways."""
    sight = line_of_sight(pose) if sight is None else sight
    blind = [skeleton.index(n) for n in depth_blind_joints(skeleton, pose, sight)]
    if not blind:
        return skeleton
    frames = Kinematics(skeleton, pose).frames
    kinds, axes, limits = list(skeleton.kinds), skeleton.axes.copy(), skeleton.limits.copy()
    zero = skeleton.hinge_zero.copy()
    for j in blind:
        limits[j] = (image_range(skeleton, j, frames, pose.rotations[j], sight)
                     if skeleton.limited_hinge(j)
                     else (-np.inf, np.inf))
        kinds[j] = HINGE
        axes[j] = frames[j, :3, :3].T @ sight
        zero[j] = pose.rotations[j]
    out = Skeleton(skeleton.names, skeleton.parents, skeleton.offsets, kinds, axes,
                   skeleton.end_sites, limits=limits, hinge_zero=zero)
    out.blobs = skeleton.blobs
    return out


def image_range(skeleton: Skeleton, j: int, frames: np.ndarray, rotation: np.ndarray,
                sight: np.ndarray) -> tuple[float, float]:
    """The turns (radians) about the line of sight ``sight`` (3,) that limited hinge j's
    bone, seen along it, makes as the hinge sweeps its range from ``rotation`` (joints'
    world ``frames`` (J, 4, 4) at that pose): (-inf, inf) where the sweep passes near the
    line of sight, whose image angle then takes any value."""
    children = np.flatnonzero(skeleton.parents == j)
    if len(children):
        bone = skeleton.offsets[children].mean(axis=0)
    elif skeleton.end_sites[j]:
        bone = np.asarray(skeleton.end_sites[j][0], float)
    else:
        return -np.inf, np.inf
    turns = np.linspace(*skeleton.hinge_turns(j, rotation), 181)  # a degree apart or less
    axis = np.asarray(skeleton.axes[j], float)
    dirs = np.array([frames[j, :3, :3] @ se3.exp_so3(axis * t) @ bone for t in turns])
    across = dirs - np.outer(dirs @ sight, sight)
    if np.min(np.linalg.norm(across, axis=1)) < FORESHORTENED * np.linalg.norm(bone):
        return -np.inf, np.inf
    k = np.argmin(np.abs(turns))  # the bone at ``rotation``
    angle = np.unwrap(np.arctan2(np.cross(across[k], across) @ sight, across @ across[k]))
    angle -= angle[k]
    return float(angle.min()), float(angle.max())


def out_of_side_on(turned: float | None) -> bool:
    """Whether a frame's body, ``turned`` degrees (``turned_from``; None where the views
    look different ways) from its key, is past ``OUT_OF_SIDE_ON_DEG``: a frame to check."""
    return turned is not None and turned > OUT_OF_SIDE_ON_DEG


def turned_from(key: BodyPose, pose: BodyPose, sight: np.ndarray | None = None) -> float:
    """Degrees the first view's line of sight at ``pose`` lies off the line the side-on
    hinges turn about (``sight`` at ``key``, the view's own there unless given), as the
    root's frame sees them (0 for a turn about the line of sight, which the image shows; a
    body turned half round is seen side-on again; the turn's sign left out): how far the
    body has turned toward or away from the camera since ``key``, and a moving camera
    round it."""
    hinge = key.rotations[0].T @ (line_of_sight(key) if sight is None else sight)
    now = pose.rotations[0].T @ pose.views[0].orientation[2]
    return float(np.degrees(np.arccos(np.clip(abs(hinge @ now), 0.0, 1.0))))

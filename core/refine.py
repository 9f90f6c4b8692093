"""The skeleton learned from the footage (paper section 2.7): joint centres and hinge axes
refined from a tracked sequence.

For one joint and each pair of consecutive frames, the motion of the segments the joint
moves, relative to its parent's, is the joint's tracked step plus the free rigid corrections
(6-vector twists, least squares over each group's pixels at the tracked pose of the later
frame) those segments ask for beyond it, less the parent's: what the current skeleton cannot
do shows. Written in the joint's frame before its rotation (the parent's axes, at the joint),
a hinge's twists over time are one twist scaled by its angular velocity: the 6 x T matrix of
them has rank 1, and its first singular vector, scaled so that its rotation part is a unit
vector, is the hinge's twist (v, w) = (p x w, w): its axis w and the point p on it nearest
the old centre (each step's spin about the bone, which a round blob barely sees, taken out
first, and steps that stray from the rank-1 twist discounted). A ball joint turns about
varying axes through one centre p, so v(t) = p x w(t) gives p by least squares. The
refined joints are moved there (its children's offsets compensate, so the body at rest is
unchanged), and the footage is tracked again, until no joint moves.

Calibrated views (one world frame). Planar mode, for a body seen side-on by one view: the
twists are kept in the image plane (translation along the image axes, rotation about the view
direction), and a hinge's axis stays along the view direction.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import least_squares

from . import se3
from .blas import one_blas_thread
from .errors import InputError
from .linearize import Kinematics, rows
from .pose import CALIBRATED, BodyPose
from .settings import TrackerSettings
from .skeleton import BALL, HINGE, Skeleton
from .solver import NormalEquations, solve
from .tracker import Tracker, track

REFINE_ITERATIONS = 4  # Gauss-Newton iterations a level, at least, on the tracks it reads
SETTLED_SHIFT = 1e-3  # world units: a round that moves no joint more is settled ...
SETTLED_TURN = 0.5  # ... if it turns no hinge's axis more degrees either


class RefineError(InputError):
    """A refinement that cannot be made; the message says why."""


def segment_twists(tracker: Tracker, poses: Sequence[BodyPose], frames: Sequence[int],
                   joint: int, planar: bool = False) -> np.ndarray:
    """Per step between consecutive tracked frames, the twist (6,) = (v, w) of the segments
    ``joint`` moves (its tracked step and the free correction the pixels ask for), in the
    joint's frame before its rotation; (6, T - 1)."""
    sk = tracker.skeleton
    moved = sk.moved_by()[:, joint]
    parent = sk.parents[joint]
    basis = np.eye(6)
    if planar:  # translation along the image axes, rotation about the view direction
        R = poses[0].views[0].orientation
        basis = np.zeros((6, 3))
        basis[:3, 0], basis[:3, 1], basis[3:, 2] = R[0], R[1], R[2]
    own = np.zeros(sk.n_joints, dtype=bool)  # the parent's own segment
    own[parent] = True
    out = []
    for t in range(1, len(poses)):
        kin = Kinematics(sk, poses[t])
        pixels = tracker.frame_pixels(poses[t - 1], frames[t - 1], poses[t], frames[t])
        # the tracked step turns the segments about the joint's centre; what the pixels of
        # the joint's segments ask for beyond it, less what its parent's ask for, is what the
        # skeleton could not do
        tracked = se3.log_so3(poses[t].rotations[joint] @ poses[t - 1].rotations[joint].T)
        out.append(np.concatenate([np.zeros(3), tracked])
                   + _free_twist(kin, pixels, moved, basis, joint)
                   - _free_twist(kin, pixels, own, basis, joint))
    return np.array(out).T


def _free_twist(kin: Kinematics, pixels: list, segments: np.ndarray, basis: np.ndarray,
                joint: int) -> np.ndarray:
    """The rigid motion (6,) the pixels of ``segments`` ask for (one least-squares step, in
    the span of ``basis``), as a twist in ``joint``'s frame before its rotation."""
    ne = NormalEquations.zeros(basis.shape[1])
    for view, seg, world, grad, r, w in pixels:
        keep = segments[seg]
        if keep.any():
            A = rows(kin, view, CALIBRATED, seg[keep], world[keep], grad[keep])[:, :6]
            ne.add(A @ basis, r[keep], w[keep])
    step = basis @ solve(ne, 1e-3)
    v_c, w = step[:3], step[3:]  # a world twist about the root's position c
    M = kin.frames
    c, RF, pF = M[0, :3, 3], M[kin.skeleton.parents[joint], :3, :3], M[joint, :3, 3]
    return np.concatenate([RF.T @ (v_c + np.cross(w, pF - c)), RF.T @ w])


def hinge_from_twists(W: np.ndarray, old_axis: np.ndarray, rounds: int = 10
                      ) -> tuple[np.ndarray, np.ndarray]:
    """Axis (3,) and the point (3,) on it nearest the frame's origin of the rank-1 twist
    matrix W (6, T): its first left singular vector, scaled to a unit rotation part and
    turned to agree with ``old_axis``. Steps that stray from the rank-1 twist (a segment
    mostly hidden in some view reads a wrong one) are discounted: the factorisation is
    repeated ``rounds`` times with Cauchy weights on each step's distance from the twist,
    at twice the distances' robust spread."""
    weights = np.ones(W.shape[1])
    for r in range(rounds):
        u = np.linalg.svd(W * weights, full_matrices=False)[0][:, 0]
        xi = u / np.linalg.norm(u[3:])
        miss = np.linalg.norm(W - np.outer(xi, W.T @ xi / (xi @ xi)), axis=0)
        spread = 1.4826 * np.median(miss)
        if r == rounds - 1 or spread <= 0:
            break
        weights = 1 / np.sqrt(1 + (miss / (2 * spread)) ** 2)
    if xi[3:] @ old_axis < 0:
        xi = -xi
    return xi[3:], np.cross(xi[3:], xi[:3])


def without_spin(W: np.ndarray, poses: Sequence[BodyPose], sk: Skeleton, joint: int
                 ) -> np.ndarray:
    """The twists W (6, T - 1) of ``segment_twists`` with each step's turn about the
    joint's bone (toward its child, at the later pose) taken out. A segment's blob is round
    about its bone, so its pixels say little of how it spins there, and what they say drew
    a hinge's axis off by 2 degrees when tracked from the capture's own poses; a hinge's
    axis lies across its bone, so no signal of it is lost."""
    bone = sk.bone_frame(joint)[0]
    b = np.array([p.rotations[joint] @ bone for p in poses[1:]])  # (T - 1, 3)
    out = W.copy()
    out[3:] -= (b * np.sum(W[3:].T * b, axis=1, keepdims=True)).T
    return out


def centre_from_twists(W: np.ndarray, rcond: float = 0.1) -> np.ndarray:
    """The point p (3,) all twists W (6, T) turn about: v(t) = p x w(t), least squares. A
    ball that turned about one axis only (a knee kept as a ball) does not show where along
    that axis its centre is: directions whose singular value is under ``rcond`` times the
    largest are left where they were (minimum-norm solution)."""
    A = np.concatenate([-se3.hat3(w) for w in W[3:].T])
    return np.linalg.lstsq(A, np.concatenate(list(W[:3].T)), rcond=rcond)[0]


def joint_from_track(tracker: Tracker, poses: Sequence[BodyPose], frames: Sequence[int],
                     joint: int, planar: bool = False) -> tuple[np.ndarray, np.ndarray | None]:
    """What the footage says of ``joint`` at the tracked ``poses`` of ``frames``: its centre's
    shift (3,) and, for a hinge, its axis (3,; None for a ball, whose centre alone is
    learned), both in the joint's rest frame, as ``moved_joint`` takes them."""
    sk = tracker.skeleton
    with one_blas_thread():  # the same sums in the same order on any machine
        W = segment_twists(tracker, poses, frames, joint, planar)
    if sk.kinds[joint] != HINGE:
        return centre_from_twists(W), None
    # a hinge turns about R_j a in the frame before its rotation (R_j = R_j(0) exp(theta
    # a)), so the axis found there is taken back through R_j(0)
    R0 = poses[0].rotations[joint]
    axis, point = hinge_from_twists(without_spin(W, poses, sk, joint), R0 @ sk.axes[joint])
    axis = R0.T @ axis
    if planar:  # the axis stays along the view; the centre moves across it
        axis = sk.axes[joint]
        point = point - (R0 @ axis) * (point @ (R0 @ axis))
    return point, axis


def moved_joint(sk: Skeleton, joint: int, shift: np.ndarray, axis: np.ndarray | None = None
                ) -> Skeleton:
    """The skeleton with ``joint``'s centre moved by ``shift`` (its local frame, which is the
    rest frame) and, for a hinge, the new axis; the body at rest stays where it was (its
    children's offsets and end sites take the shift back; blobs are in the rest frame)."""
    offsets = sk.offsets.copy()
    offsets[joint] += shift
    for c in sk.children(joint):
        offsets[c] -= shift
    ends = [list(e) for e in sk.end_sites]
    ends[joint] = [e - shift for e in ends[joint]]
    axes = sk.axes.copy()
    if axis is not None:
        axes[joint] = axis / np.linalg.norm(axis)
    return Skeleton(list(sk.names), sk.parents.copy(), offsets, list(sk.kinds), axes, ends,
                    sk.blobs, sk.limits.copy(), sk.hinge_zero.copy())


def carried_pose(old: Skeleton, new: Skeleton, pose: BodyPose) -> BodyPose:
    """``pose`` of ``old`` as a pose of ``new`` that places the segments where they were:
    each joint's rotation refitted, parents first, so that its segment's blobs (their axes'
    ends) and its children's joints land where ``old`` put them."""
    R = pose.rotations.copy()
    g_old = old.segment_motions(old.joint_frames(pose.rotations, pose.root_position))
    for j in range(1, new.n_joints):
        if np.allclose(new.offsets[j], old.offsets[j]) and np.allclose(
                new.rest_positions[j], old.rest_positions[j]):
            continue
        pts = [b.centre + b.Q[:, k] * b.radii[k] * sgn for b in new.blobs if b.joint == j
               for k in range(3) for sgn in (-1, 1)] + [new.rest_positions[c]
                                                       for c in new.children(j)]
        if not pts:
            continue
        X = np.array(pts)
        want = X @ g_old[j, :3, :3].T + g_old[j, :3, 3]
        fit = least_squares(_placement_error, np.zeros(3), args=(new, R, pose, j, X, want))
        R[j] = pose.rotations[j] @ se3.exp_so3(fit.x)
    return BodyPose(R, pose.root_position.copy(), [v.copy() for v in pose.views])


def _placement_error(x, sk: Skeleton, R: np.ndarray, pose: BodyPose, j: int, X: np.ndarray,
                     want: np.ndarray) -> np.ndarray:
    """Where segment j puts its points X with its rotation turned by x, less ``want``."""
    Rj = R.copy()
    Rj[j] = pose.rotations[j] @ se3.exp_so3(x)
    g = sk.segment_motions(sk.joint_frames(Rj, pose.root_position))[j]
    return (X @ g[:3, :3].T + g[:3, 3] - want).ravel()


@dataclass
class Refinement:
    skeleton: Skeleton
    initial: BodyPose  # the initial pose carried onto the refined skeleton
    shifts: list[dict[str, float]] = field(default_factory=list)  # per round: joint -> m
    turns: list[dict[str, float]] = field(default_factory=list)  # per round: hinge -> deg

    def settled(self, tolerance: float = SETTLED_SHIFT, turn_tolerance: float = SETTLED_TURN
                ) -> bool:
        """Whether the last round moved no joint more than ``tolerance`` (world units) and
        turned no hinge's axis more than ``turn_tolerance`` degrees."""
        return bool(self.shifts) and (max(self.shifts[-1].values(), default=0.0) < tolerance
                                      and max(self.turns[-1].values(), default=0.0)
                                      < turn_tolerance)


def refine(skeleton: Skeleton, images: Sequence[Sequence], initial: BodyPose,
           joints: Sequence[str], settings: TrackerSettings | None = None,
           planar: bool = False, rounds: int = 10, tolerance: float = SETTLED_SHIFT,
           turn_tolerance: float = SETTLED_TURN) -> Refinement:
    """Track ``images`` (calibrated views) from ``initial``, refine the centres (and hinge
    axes) of ``joints``, track again, until a round moves no joint more than ``tolerance``
    (world units) and turns no hinge's axis more than ``turn_tolerance`` degrees, or
    ``rounds`` are done. A turned axis comes back over several rounds (the tracker's
    parent joint takes part of the turn each time): on the rendered walk, 14 degrees took
    nine."""
    sk, pose = skeleton, initial
    # tracked without the limb search: fitting each limb's outline to the wrong joint, it
    # soaked up the mismatch the refinement reads (a knee 4 cm off stayed 3.9 cm off, 1.4
    # without it, in the add-on's test); and with REFINE_ITERATIONS a level at least, since
    # the refinement reads what converged steps leave (with three, the planar chain's test
    # diverged at its last frame); and with the joints as given, which side-on tracking
    # would change (``planar`` is the refinement for a body seen side-on); and with every
    # limb's pixels of the frame before, which the steps it reads are made of (leaving a
    # doubted limb's backdrop pixels out, the add-on test's knee came back 2.3 cm off after
    # two rounds, against 1.4, and 2.4 after ten, against 1.8)
    settings = settings or TrackerSettings()
    settings = dataclasses.replace(settings, limb_search=0.0, side_on=False,
                                   release_lost_limbs=False,
                                   iterations=max(settings.iterations, REFINE_ITERATIONS))
    idx = []
    for name in joints:
        if name not in sk.names:
            raise RefineError(f"no joint named '{name}' to refine")
        j = sk.index(name)
        if sk.kinds[j] not in (HINGE, BALL) or j == 0:
            raise RefineError(f"'{name}' is not a hinge or ball joint: nothing to refine")
        idx.append(j)
    if planar and len(initial.views) != 1:
        raise RefineError("planar refinement is for one view seeing the body side-on")
    out = Refinement(sk, pose)
    n = min(len(v) for v in images)
    if n < 3:
        raise RefineError(f"{n} frames are too few to refine a skeleton from (at least 3)")
    frames = list(range(n))
    for _ in range(rounds):
        tracker = Tracker(sk, images, CALIBRATED, settings)
        result = track(tracker, pose, frames)
        if result.diverged_frames or len(result.frames) < n:
            where = result.diverged_frames[0] if result.diverged_frames else len(result.frames)
            raise RefineError(f"tracking diverged at frame {where} of the range: refine over "
                              "a stretch that tracks")
        poses = [f.pose for f in result.frames]
        shifts, turns, new = {}, {}, sk
        for j in idx:
            point, axis = joint_from_track(tracker, poses, frames, j, planar)
            if axis is not None:
                turns[sk.names[j]] = float(np.degrees(se3.angle_between_vectors(axis,
                                                                             sk.axes[j])))
            new = moved_joint(new, j, point, axis)
            shifts[sk.names[j]] = float(np.linalg.norm(point))
        pose = carried_pose(sk, new, pose)
        sk = new
        out.shifts.append(shifts)
        out.turns.append(turns)
        if out.settled(tolerance, turn_tolerance):
            break
    out.skeleton, out.initial = sk, pose
    return out

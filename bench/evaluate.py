"""Tracking quality against ground truth: limb directions, joint positions, local rotations.

Limb-direction error: the angle between tracked and true world directions of a bone (its
joint to its child joint or end site) -- axial twist, which no camera sees well, does not
enter it. Joint-position error: distance between tracked and true joint positions after
both are taken relative to their root, in millimetres for a skeleton in metres.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from core import se3
from core.bvh import BvhFile
from core.skeleton import HINGE, Skeleton, twist_about

UP = np.array([0.0, 1.0, 0.0])  # the captures' vertical (``suite_footage``'s stage)

# (label, from, to): a joint name, or "<joint>/end" for that joint's first end site
LIMBS = [
    ("left thigh", "LeftHip", "LeftKnee"), ("right thigh", "RightHip", "RightKnee"),
    ("left shank", "LeftKnee", "LeftAnkle"), ("right shank", "RightKnee", "RightAnkle"),
    ("left upper arm", "LeftShoulder", "LeftElbow"),
    ("right upper arm", "RightShoulder", "RightElbow"),
    ("left forearm", "LeftElbow", "LeftWrist"), ("right forearm", "RightElbow", "RightWrist"),
    ("neck-head", "Neck", "Head/end"),
]
HEADLINE = [label for label, _, _ in LIMBS[:8]]  # the eight limb bones


def world_points(sk: Skeleton, rotations: np.ndarray, roots: np.ndarray) -> np.ndarray:
    """World joint positions (F, J, 3) for rotations (F, J, 3, 3) and root positions (F, 3)."""
    return np.array([sk.world_positions(R, p) for R, p in zip(rotations, roots)])


def named_point(sk: Skeleton, frames: np.ndarray, name: str) -> np.ndarray:
    """World position of a joint, or of "<joint>/end", its first end site, given its frames."""
    joint, _, end = name.partition("/")
    M = frames[sk.index(joint)]
    return M[:3, :3] @ sk.end_sites[sk.index(joint)][0] + M[:3, 3] if end else M[:3, 3]


def limb_ends(sk: Skeleton, rotations, roots, limbs=LIMBS) -> dict[str, np.ndarray]:
    """World positions (F, 3) of every limb end named in ``limbs`` ((label, from, to), the
    eight limb bones first; by default the CMU walk's ``LIMBS``)."""
    frames = [sk.joint_frames(R, p) for R, p in zip(rotations, roots)]
    names = {name for _, a, b in limbs for name in (a, b)}
    return {name: np.array([named_point(sk, M, name) for M in frames]) for name in sorted(names)}


def limb_vectors(sk: Skeleton, rotations, roots, limbs=LIMBS) -> dict[str, np.ndarray]:
    """World direction vectors (F, 3) of each limb."""
    ends = limb_ends(sk, rotations, roots, limbs)
    return {label: ends[b] - ends[a] for label, a, b in limbs}


@dataclass
class Scores:
    limb_deg: dict[str, float]  # mean over frames, per limb
    limb_mean_deg: float  # mean over the eight limb bones
    position_mm: float  # mean root-relative joint-position error
    local_deg: dict[str, float]  # mean local-rotation error per tracked joint
    per_frame_limb_deg: np.ndarray  # (F,) mean over the eight limbs


def limb_errors_deg(sk: Skeleton, est: tuple, truth: tuple, limbs=LIMBS) -> dict[str, np.ndarray]:
    """Per limb, the angle (F,) in degrees between its estimated and true directions on each
    of the frames both (rotations, roots) hold."""
    ve, vt = limb_vectors(sk, *est, limbs), limb_vectors(sk, *truth, limbs)
    return {k: np.degrees(se3.angle_between_vectors(ve[k], vt[k])) for k in ve}


def score(sk: Skeleton, tracked_joints: list[str], est: tuple, truth: tuple,
          unit_mm: float = 1000.0, limbs=LIMBS) -> Scores:
    """Compare (rotations, roots) of an estimate with the truth over the same frames."""
    F = min(len(est[0]), len(truth[0]))
    est = (est[0][:F], est[1][:F])
    truth = (truth[0][:F], truth[1][:F])
    per = limb_errors_deg(sk, est, truth, limbs)
    pe, pt = world_points(sk, *est), world_points(sk, *truth)
    rel = (pe - pe[:, :1]) - (pt - pt[:, :1])
    local = {}
    for n in tracked_joints:
        j = sk.index(n)
        angle = se3.rotation_angle_between(est[0][:, j], truth[0][:, j])
        local[n] = float(np.degrees(angle).mean())
    per_frame = np.mean([per[label] for label, _, _ in limbs[:8]], axis=0)
    return Scores({k: float(v.mean()) for k, v in per.items()}, float(per_frame.mean()),
                  float(np.linalg.norm(rel, axis=-1).mean() * unit_mm), local, per_frame)


def swing_twist(R: np.ndarray, axis: np.ndarray) -> tuple[float, float]:
    """A rotation R (3, 3) split as R = swing @ twist, the twist about the unit ``axis`` and
    the swing about an axis across it: (swing, twist) in degrees, the twist signed about
    ``axis`` in (-180, 180], the swing in [0, 180] (the angle R turns ``axis`` by)."""
    twist = np.degrees(twist_about(R, axis))  # in [-180, 180]
    twist = twist + 360 if twist <= -180 else twist
    swing = np.degrees(float(se3.angle_between_vectors(axis, R @ axis)))
    return swing, float(twist)


def heading_errors_deg(est: np.ndarray, ref: np.ndarray, up: np.ndarray = UP) -> np.ndarray:
    """Per frame, how far the root rotations ``est`` (F, 3, 3) are turned about the world's
    ``up`` beyond ``ref`` (F, 3, 3): the twist about ``up`` of est ref^T (its rotation split
    as a swing across ``up`` after a twist about it: ``swing_twist``), signed, in
    (-180, 180] degrees (F,)."""
    return np.array([swing_twist(e @ r.T, up)[1] for e, r in zip(est, ref)])


def motion(bvh: BvhFile) -> tuple[np.ndarray, np.ndarray]:
    return bvh.poses()


def image_error_px(sk: Skeleton, est: tuple, truth: tuple, views: list, limbs=LIMBS) -> float:
    """Mean distance (pixels) between tracked and true limb ends (the joints of ``limbs``)
    as each of ``views`` (a ``core.camera`` camera, or one per frame for a camera that
    moves) shows them: how far the tracked body's overlay strays from the body in the
    footage, which even one view sees."""
    F = min(len(est[0]), len(truth[0]))
    pe, pt = (np.stack(list(limb_ends(sk, R[:F], p[:F], limbs).values()), 1)
              for R, p in (est, truth))  # (F, ends, 3)
    per_view = []
    for v in views:
        cams = v if isinstance(v, (list, tuple)) else [v] * F
        per_view.append(np.mean([np.linalg.norm(c.project(a) - c.project(b), axis=1)
                                 for c, a, b in zip(cams, pe, pt)]))
    return float(np.mean(per_view))


def _across(v: np.ndarray, sight: np.ndarray) -> np.ndarray:
    """Vectors (F, 3) with their parts along the unit ``sight`` taken out: laid into the
    image plane of a view looking along it."""
    return v - np.outer(v @ sight, sight)


def _read_errors(truth: dict[str, np.ndarray], read: dict[str, np.ndarray]) -> dict[str, float]:
    """Mean angle (degrees) between each limb's true and read direction vectors (F, 3) over
    the frames, and ``"mean"``, over the eight limb bones."""
    per = {k: np.degrees(se3.angle_between_vectors(truth[k], read[k])) for k in read}
    out = {k: float(v.mean()) for k, v in per.items()}
    out["mean"] = float(np.mean([per[k] for k in HEADLINE]))
    return out


def in_the_image_plane(sk: Skeleton, truth: tuple, sight: np.ndarray) -> dict[str, float]:
    """Mean limb-direction error (degrees) of limbs read exactly in the image of one view
    looking along ``sight`` (a world direction) with nothing read in depth: each true limb
    laid into the image plane. What a single view leaves to be inferred about depth."""
    vt = limb_vectors(sk, *truth)
    sight = np.asarray(sight, dtype=float) / np.linalg.norm(sight)
    return _read_errors(vt, {k: _across(v, sight) for k, v in vt.items()})


def _steadiest_signs(flat: np.ndarray, depth: np.ndarray, first: float) -> np.ndarray:
    """Signs (F,) for the depths (F,) beside the image-plane parts ``flat`` (F, 3) that make
    the limb's path ``flat + sign * depth * sight`` the steadiest (least summed second
    difference, the constant-velocity prediction's measure), the first sign given: a choice
    between the two mirror images of each frame (Viterbi over the signs of two frames;
    ``sight`` is any unit vector orthogonal to ``flat``, so it is not needed)."""
    if len(depth) < 2:
        return np.full(len(depth), first)
    signs = np.array([-1.0, 1.0])
    # cost[a, b]: the steadiest path whose frames f-1 and f have signs a and b; the limb at
    # rest before the first frame (as the tracker starts), so the first step counts whole
    cost = np.full((2, 2), np.inf)
    cost[signs == first] = np.hypot(np.linalg.norm(flat[1] - flat[0]),
                                    signs * depth[1] - first * depth[0])
    back = []
    for f in range(2, len(depth)):
        bend = np.linalg.norm(flat[f] - 2 * flat[f - 1] + flat[f - 2])
        dz = (signs[None, None, :] * depth[f] - 2 * signs[None, :, None] * depth[f - 1]
              + signs[:, None, None] * depth[f - 2])  # [a, b, c]: signs at f-2, f-1, f
        total = cost[:, :, None] + np.hypot(bend, dz)
        back.append(total.argmin(axis=0))  # [b, c] -> the best a
        cost = total.min(axis=0)
    b, c = np.unravel_index(np.argmin(cost), cost.shape)
    path = [int(c), int(b)]
    for best_a in reversed(back):
        path.append(int(best_a[path[-1], path[-2]]))
    return signs[path[::-1]]


def lifted_from_the_image(sk: Skeleton, truth: tuple, sight: np.ndarray, noise: float = 0.0,
                          seed: int = 0) -> dict[str, float]:
    """Mean limb-direction error (degrees) of limbs read in the image of one view looking
    along ``sight`` (a world direction) and lifted into depth as that view allows: each
    limb's depth from its known length (its image shortens by its tilt), its sign (toward
    or away from the camera, which an orthographic image does not show) the first frame's
    and then the steadiest path's from rest. With ``noise`` (world units; pixels over the view's
    scale) every limb end is read that far off in the image, at random (normal, per image
    axis). With no noise: what a one-view tracker that guesses depth signs from motion alone
    gets from perfect pixels."""
    sight = np.asarray(sight, dtype=float) / np.linalg.norm(sight)
    rng = np.random.default_rng(seed)
    ends = limb_ends(sk, *truth)
    # each end read off at random (its part along the sight goes with the depth below)
    seen = {name: e + rng.normal(0.0, noise, e.shape) for name, e in ends.items()}
    true, read = {}, {}
    for label, a, b in LIMBS:
        v = true[label] = ends[b] - ends[a]
        flat = _across(seen[b] - seen[a], sight)
        depth = np.sqrt(np.maximum(np.sum(v * v, axis=1) - np.sum(flat * flat, axis=1), 0.0))
        signs = _steadiest_signs(flat, depth, 1.0 if v[0] @ sight >= 0 else -1.0)
        read[label] = flat + np.outer(signs * depth, sight)
    return _read_errors(true, read)


def held_still(truth: tuple) -> tuple:
    """The first frame's pose repeated over every frame, root included."""
    R, p = truth
    return np.repeat(R[:1], len(R), 0), np.repeat(p[:1], len(p), 0)


def best_fit(sk: Skeleton, truth: tuple, root_axis: np.ndarray | None = None) -> tuple:
    """The pose with the skeleton's tracked degrees of freedom (and a free root) that best fits
    the true 3-D joint positions, frame by frame; untracked joints keep the first frame's
    rotation, hinges turn about their axis from the first frame's rotation. With
    ``root_axis`` (a world direction) the root turns about it alone, as a body tracked
    side-on turns about the line of sight."""
    R_true, p_true = truth
    dof_joint, dof_axis = sk.dof_joints_and_axes()
    base = R_true[0].copy()
    target = world_points(sk, R_true, p_true)
    turn = 3 if root_axis is None else 1  # the root's turn parameters, after its position
    axis = None if root_axis is None else np.asarray(root_axis, float) / np.linalg.norm(root_axis)

    def pose_of(x):
        R = base.copy()
        R[0] = se3.exp_so3(x[3:6] if axis is None else axis * x[3]) @ base[0]
        k = 3 + turn
        for j in sorted(set(dof_joint.tolist())):
            if sk.kinds[j] == HINGE:
                R[j] = base[j] @ se3.exp_so3(dof_axis[k - 3 - turn] * x[k])
                k += 1
            else:
                R[j] = base[j] @ se3.exp_so3(x[k:k + 3])
                k += 3
        return R, x[:3]

    # parameters per DOF in the skeleton's order, which groups each joint's DOFs together
    n = 3 + turn + len(dof_joint)
    x = np.zeros(n)
    x[:3] = p_true[0]
    out_R, out_p = [], []
    for f in range(len(R_true)):
        def resid(x, f=f):
            R, p = pose_of(x)
            return (sk.world_positions(R, p) - target[f]).ravel()
        # MINPACK's lm stops on a small step short of the minimum here (a thigh swung 30
        # degrees out of the image plane kept 3 cm of joint error, a body turned in depth
        # 0.5 degrees, even at tolerances of 1e-12). Trust-region steps reach both; scaled by
        # the Jacobian's columns they did on one machine and stopped 0.4-0.6 degrees short on
        # another, where the unscaled ones reached every test's truth to 1e-12 degrees, and
        # sooner
        x = least_squares(resid, x, method="trf", ftol=1e-12, xtol=1e-12, gtol=1e-12).x
        R, p = pose_of(x)
        out_R.append(R)
        out_p.append(p)
    return np.array(out_R), np.array(out_p)

"""The first frame's pose, and the body's proportions, from joints clicked in each view.

Unknowns: the root's pose (one world pose when the cameras are calibrated; otherwise each view's
scale, rotation and image translation, paper section 2.6) and every tracked joint's rotation,
both stepped as the tracker steps them (``core.pose.apply_update``), and one length factor per
bone, shared by the left and right bones of a pair and by bones in line that meet at no
click. Residuals: each clicked joint's projection minus its click, in pixels, with a robust
(soft-L1) loss, plus weak priors that keep unconstrained unknowns at the guess. Solved by
``scipy.optimize.least_squares`` with length factors bounded to [0.5, 2].

How precisely the clicks pin the result: the fit's information matrix J^T J at the solution
(J the residuals' Jacobian, clicks in pixels) inverted is the unknowns' covariance for one
pixel of click error in each coordinate, the Cramer-Rao bound of this model. It is carried
to each turned bone's direction; errors scale with the click error.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from .errors import InputError
from .pose import CALIBRATED, BodyPose, apply_update, n_root_params
from .skeleton import BALL, Skeleton

PRIOR_ANGLE = 0.02  # weight (pixels per radian) holding unconstrained rotations at the guess
PRIOR_LENGTH = 0.5  # weight (pixels per unit of log length) holding lengths at the guess
PRIOR_SHIFT = 0.02  # weight (pixels per pixel the views would see it move) holding the root
# where it was guessed along what no view sees: the line of sight of orthographic views, down
# which the fit otherwise slid a body kilometres in one step (its Jacobian column is zero)


class FitError(InputError):
    """Clicks that cannot determine a pose; the message says what to add."""


@dataclass
class FitResult:
    skeleton: Skeleton  # with the fitted offsets
    pose: BodyPose
    residual_px: float  # RMS distance of the clicked joints from their clicks
    lengths: dict[str, float]  # fitted length factor of each bone (1: as guessed)
    # RMS error of each turned bone's direction in degrees per pixel of click error in x and
    # y, the bone named by the joint it turns at; 180: the clicks do not determine it
    direction_uncertainty: dict[str, float]


def symmetry_key(name: str) -> str:
    """Left and right bones share a key: LeftKnee, RightKnee -> *Knee; LHipJoint -> *HipJoint."""
    key = re.sub(r"(Left|Right|left|right)", "*", name)
    return re.sub(r"^[LR](?=[A-Z])", "*", key)


def _check(sk: Skeleton, clicks: list[dict], n_unknowns: int) -> None:
    """Refuse clicks that cannot determine the fit, saying what to add."""
    for c, view_clicks in enumerate(clicks):
        pts = np.array(list(view_clicks.values()), dtype=float).reshape(-1, 2)
        if len(pts) >= 2 and np.linalg.matrix_rank(pts - pts.mean(0), tol=1.0) < 2:
            raise FitError(f"view {c + 1}: the {len(pts)} clicks lie on one line; click joints "
                           "off that line (a hand, a foot, the head)")
    n = 2 * sum(len(v) for v in clicks)
    if n < n_unknowns:
        raise FitError(f"{n // 2} clicks give {n} numbers but the fit has {n_unknowns} "
                       f"unknowns: click at least {(n_unknowns - n + 1) // 2} more joints")


def fit_pose(sk: Skeleton, guess: BodyPose, clicks: list[dict], mode: str,
             fit_lengths: bool = True) -> FitResult:
    """Fit pose (and lengths) to ``clicks`` (per view: point name -> (x, y) pixels; a point
    is a joint, or ``"<joint>/end"``, the tip of that joint's first end site: a foot or a
    hoof that ends a limb, whose length the fit keeps). A hinge the clicks leave bent
    against its limits under its parent twisted half a turn comes back as the same body
    within them (``Skeleton.untwisted``)."""
    if len(clicks) != len(guess.views):
        raise FitError(f"clicks for {len(clicks)} views, but {len(guess.views)} views")
    points = []  # per view, each click's (joint, whether at its end site)
    for c, view_clicks in enumerate(clicks):
        try:
            points.append([clicked_point(sk, name) for name in view_clicks])
        except FitError as e:
            raise FitError(f"view {c + 1}: {e}") from None
    dof_joint, dof_axis = sk.dof_joints_and_axes()
    joints = sorted(set(dof_joint.tolist()))
    # a bone on the way from the root to a clicked joint gets its own length (shared with
    # its mirror twin): even an unclicked trunk bone decides where the clicked shoulders can
    # be (one common factor for them left the upper arms 2 degrees off with exact clicks);
    # bones below every click scale with one common factor, so that they do not soak up noise
    clicked = {j for v in points for j, _ in v}  # a clicked end counts as its joint here
    on_path = {a for c in clicked for a in sk.ancestors(c)}  # clicked joints and above

    def chain_start(j: int) -> int:
        """The first joint of the unbranched run of bones that ends at j: bones meeting at a
        joint that is neither clicked nor a branch can only be fitted as one (two spine bones
        in line trade length freely), so they share a factor."""
        p = int(sk.parents[j])
        while p > 0 and p not in clicked and len(sk.children(p)) == 1:
            j, p = p, int(sk.parents[p])
        return j

    def group_key(j: int) -> str:
        return symmetry_key(sk.names[chain_start(j)]) if j in on_path else "*body"

    bones = [j for j in range(1, sk.n_joints) if np.linalg.norm(sk.offsets[j]) > 1e-9]
    groups = sorted({group_key(j) for j in bones})
    group_of = [groups.index(group_key(j)) if j in bones else -1 for j in range(sk.n_joints)]
    n_root = n_root_params(mode, len(guess.views))
    n_dof = len(dof_joint)
    n_len = len(groups) if fit_lengths else 0
    # what clicked joint positions can pin down: the root, and per joint with a clicked joint
    # below it its swing (a ball's twist about its bone moves no joint on the bone); lengths
    # lean on their prior and bounds
    above_click = {a for v in points for j, end in v for a in sk.ancestors(j)[0 if end else 1:]}
    swings = sum(2 if sk.kinds[j] == BALL else 1 for j in joints if j in above_click)
    _check(sk, clicks, n_root + swings)
    if fit_lengths and len(clicks) == 1:
        raise FitError("one view cannot tell a longer bone from one turned out of the image "
                       "plane: fit the pose with the lengths as they are, or click the "
                       "joints in a second view")

    def unpack(x):
        pose = apply_update(sk, guess, x[:n_root + n_dof], mode)
        factors = np.exp(x[n_root + n_dof:]) if fit_lengths else np.ones(0)
        scale = np.array([factors[g] if g >= 0 and fit_lengths else 1.0 for g in group_of])
        return pose.rotations, pose.root_position, sk.offsets * scale[:, None], pose.views, \
            factors

    # per view, the clicked points (joint, tip in its frame: zero for the joint itself) and
    # their clicks (n, 2)
    tip = [np.asarray(sk.end_sites[j][0], float) if sk.end_sites[j] else np.zeros(3)
           for j in range(sk.n_joints)]
    clicked_at = [(np.array([j for j, _ in v], dtype=int),
                   np.array([tip[j] if end else np.zeros(3) for j, end in v]).reshape(-1, 3),
                   np.array(list(c.values()), dtype=float).reshape(-1, 2))
                  for v, c in zip(points, clicks)]

    # the calibrated root's move, weighted by the pixels a unit of it spans in the views
    # (independent views move their own roots, which their clicks pin)
    shift_weight = PRIOR_SHIFT * np.mean([v.scale_at(guess.root_position)
                                          for v in guess.views])
    held = slice(0, 3 if mode == CALIBRATED else 0)

    def residuals(x):
        R, root, offsets, views, factors = unpack(x)
        M = sk.joint_frames(R, root, offsets)
        res = [(v.project(np.einsum("nab,nb->na", M[idx, :3, :3], ref) + M[idx, :3, 3])
                - pts).ravel() for v, (idx, ref, pts) in zip(views, clicked_at)]
        res += [shift_weight * x[held], PRIOR_ANGLE * x[n_root:n_root + n_dof],
                PRIOR_LENGTH * x[n_root + n_dof:]]
        return np.concatenate(res)

    x0 = np.zeros(n_root + n_dof + n_len)
    lo = np.full_like(x0, -np.inf)
    hi = np.full_like(x0, np.inf)
    lo[n_root + n_dof:], hi[n_root + n_dof:] = np.log(0.5), np.log(2.0)
    # stop when a step lowers the cost by under a millionth: one view's depth-ambiguous
    # limbs leave flat valleys where the default (1e-8) crawled on for 2 500 evaluations
    # (a minute) and lowered the cost by a thousandth of a square pixel
    sol = least_squares(residuals, x0, bounds=(lo, hi), loss="soft_l1", f_scale=3.0,
                        x_scale="jac", ftol=1e-6)

    def bone_points(x):
        """Every joint's position, in the world (calibrated) or the first view's camera
        frame (independent views: only there is the body's turn fixed)."""
        R, root, offsets, views, _ = unpack(x)
        X = sk.world_positions(R, root, offsets)
        return X if mode == CALIBRATED else X @ views[0].pose.R.T

    # the unknowns' covariance per square pixel of click error (the priors' rows keep the
    # directions no click sees finite)
    cov = np.linalg.pinv(sol.jac.T @ sol.jac)
    bones_turned = _turned_bones(sk, joints)
    R, root, offsets, views, factors = unpack(sol.x)
    fitted = Skeleton(sk.names, sk.parents, offsets, sk.kinds, sk.axes, sk.end_sites,
                      limits=sk.limits, hinge_zero=sk.hinge_zero)
    fitted.blobs = fitted.default_blobs()
    R = sk.untwisted(R)  # a hinge bent against its limits under a parent twisted half a turn
    n_clicks = sum(len(v) for v in clicks)
    rms = float(np.sqrt(np.sum(sol.fun[:2 * n_clicks] ** 2) / max(n_clicks, 1)))
    return FitResult(fitted, BodyPose(R, root, [v.copy() for v in views]), rms,
                     {sk.names[j]: float(factors[group_of[j]]) for j in range(sk.n_joints)
                      if group_of[j] >= 0 and fit_lengths},
                     {sk.names[j]: a for (j, _), a in zip(
                         bones_turned, _direction_sd(bone_points, sol.x, cov, bones_turned))})


def least_certain(uncertainty: dict[str, float], n: int = 3, views: int = 2) -> str:
    """For a message: the ``n`` bones whose directions the clicks pin least, then those they
    do not pin at all, e.g. 'LeftElbow +-1.8, Neck +-1.6 degrees per pixel of click error;
    not pinned: LeftKnee (...)'. With one view, what is not pinned is a turn toward or away
    from the camera, which its clicks show only as foreshortening."""
    free = sorted(name for name, sd in uncertainty.items() if sd >= 180)
    pinned = sorted(((k, v) for k, v in uncertainty.items() if v < 180), key=lambda kv: -kv[1])
    parts = []
    if pinned:
        parts.append(", ".join(f"{k} +-{v:.1f}" for k, v in pinned[:n])
                     + " degrees per pixel of click error")
    if free:
        why = ("its turn toward or away from the camera: one view shows it only as "
               "foreshortening" if views == 1 else "click the joints below it in a view")
        parts.append(f"not pinned: {', '.join(free)} ({why})")
    return "; ".join(parts) or "none turned"


def clicked_point(sk: Skeleton, name: str) -> tuple[int, bool]:
    """The joint a click names and whether it is at the joint's end site (``"Knee/end"``);
    FitError for a name the skeleton lacks."""
    joint, slash, end = name.partition("/")
    if joint not in sk.names or (slash and end != "end"):
        raise FitError(f"no joint named '{name}' (a joint's name, or '<joint>/end' for the "
                       "tip of its end site)")
    j = sk.index(joint)
    if slash and not sk.end_sites[j]:
        raise FitError(f"'{joint}' has no end site to click ('{name}'): click a joint, or "
                       "the end of a bone that ends a limb")
    return j, bool(slash)


def _turned_bones(sk: Skeleton, joints: list[int]) -> list[tuple[int, int]]:
    """(joint, child) for each turned joint with one child: the bone it turns."""
    out = []
    for j in joints:
        kids = [c for c in sk.children(j) if np.linalg.norm(sk.offsets[c]) > 1e-9]
        if len(kids) == 1:
            out.append((j, kids[0]))
    return out


def _direction_sd(points, x: np.ndarray, cov: np.ndarray,
                  bones: list[tuple[int, int]], step: float = 1e-6) -> list[float]:
    """RMS angle (degrees) of each bone's direction under the unknowns' covariance ``cov``,
    the directions' derivatives taken by central differences of ``points(x)`` (J, 3)."""
    if not bones:
        return []
    head, tail = (np.array(i, dtype=int) for i in zip(*bones))

    def directions(x):
        d = points(x)
        d = d[tail] - d[head]
        return d / np.linalg.norm(d, axis=1, keepdims=True)

    G = np.empty((len(bones), 3, len(x)))
    for k in range(len(x)):
        dx = np.zeros_like(x)
        dx[k] = step
        G[:, :, k] = (directions(x + dx) - directions(x - dx)) / (2 * step)
    var = np.einsum("bik,kl,bil->b", G, cov, G)
    return [min(float(np.degrees(np.sqrt(max(v, 0.0)))), 180.0) for v in var]

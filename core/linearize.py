"""The per-pixel rows [H | J] of the linear motion model, one view at a time.

A body point X (world) with image gradient g = (Ix, Iy) at its pixel gives one
brightness-constancy row A_i with  I_t + A_i . delta = 0  (paper eqs. 18, 28, 33). The camera
carries g back to the world through its projection's Jacobian: m = J^T g (``pullback``), so
that a world displacement dX of the point changes the brightness by m . dX. Then:

* Calibrated mode, the shared world root (a translation and a rotation about the root's world
  position c):  [m, (X - c) x m].
* Independent mode (scaled orthographic views only), this view's root block about the root's
  image point q_r, with q the point's scaled camera coordinate and d = q - q_r:
  [g.d, Ix, Iy, (d x g)] with g = (Ix, Iy, 0)  -- paper eq. 18 with the pivot moved to q_r.
* One column per joint degree of freedom, a turn about the world axis a through the point o:
  m . (a x (X - o)) = a . ((X - c) x m) - m . (a x (o - c)) (paper eq. 26 carried to the
  world), zero on pixels whose segment that joint does not move (eq. 30).

Everything is vectorised over pixels; the joint block is two (N, 3) x (3, D) products.
"""

from __future__ import annotations

import numpy as np

from .pose import CALIBRATED, ROOT_PARAMS, ROOT_TURN, BodyPose, n_root_params
from .skeleton import Skeleton


class Kinematics:
    """What every view's rows need from one pose: joint frames, segment motions, and the
    degrees of freedom as world axes through world points."""

    def __init__(self, skeleton: Skeleton, pose: BodyPose):
        self.skeleton = skeleton
        self.pose = pose
        self.frames = skeleton.joint_frames(pose.rotations, pose.root_position)
        self.segments = skeleton.segment_motions(self.frames)
        self.dof_joint, dof_axis = skeleton.dof_joints_and_axes()
        R = self.frames[self.dof_joint, :3, :3]
        self.dof_axis_world = np.einsum("dab,db->da", R, dof_axis)
        self.dof_point_world = self.frames[self.dof_joint, :3, 3]
        self.moves = skeleton.moved_by()[:, self.dof_joint]  # (J, D)

    def world_points(self, seg_joint: np.ndarray, ref_points: np.ndarray) -> np.ndarray:
        """World positions (N, 3) of reference-frame points on the segments of ``seg_joint``."""
        g = self.segments.take(seg_joint, 0)
        return np.einsum("nab,nb->na", g[:, :3, :3], ref_points) + g[:, :3, 3]


def _cross_g(q: np.ndarray, grad: np.ndarray) -> np.ndarray:
    """q x (Ix, Iy, 0) for q (N, 3), grad (N, 2)."""
    gx, gy = grad[:, 0], grad[:, 1]
    return np.stack([-q[:, 2] * gy, q[:, 2] * gx, q[:, 0] * gy - q[:, 1] * gx], 1)


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Row-wise a x b for (N, 3) arrays (np.cross costs more than the product on few rows)."""
    return np.stack([a[:, 1] * b[:, 2] - a[:, 2] * b[:, 1], a[:, 2] * b[:, 0] - a[:, 0] * b[:, 2],
                     a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]], 1)


def rows(
    kin: Kinematics,
    view_index: int,
    mode: str,
    seg_joint: np.ndarray,
    X: np.ndarray,
    grad: np.ndarray,
) -> np.ndarray:
    """Rows (N, P) of one view for points on segments ``seg_joint`` (N,) at world positions
    X (N, 3) with image gradients ``grad`` (N, 2) per full-resolution pixel."""
    view = kin.pose.views[view_index]
    n_views = len(kin.pose.views)
    nr = n_root_params(mode, n_views)
    D = len(kin.dof_joint)
    N = len(X)
    A = np.zeros((N, nr + D))
    m = view.pullback(X, grad)
    c = kin.frames[0, :3, 3]  # the root: lever arms from it keep the products small
    xm = _cross(X - c, m)
    if mode == CALIBRATED:
        A[:, 0:3] = m
        A[:, ROOT_TURN] = xm
    else:
        o = ROOT_PARAMS * view_index
        d = view.scaled(X) - view.scaled(c)  # from the root's image point
        A[:, o] = grad[:, 0] * d[:, 0] + grad[:, 1] * d[:, 1]
        A[:, o + 1 : o + 3] = grad
        A[:, o:][:, ROOT_TURN] = _cross_g(d, grad)
    if D:
        a = kin.dof_axis_world
        J = A[:, nr:]  # written in place
        np.subtract(xm @ a.T, m @ _cross(a, kin.dof_point_world - c).T, out=J)
        J *= kin.moves.take(seg_joint, 0)
    return A

"""The tracked state of one frame, its parameter layout and its update.

A ``BodyPose`` holds the local rotations of every joint, the root's world position and one
camera per view (``core.camera``). Two modes share it:

* ``calibrated``: the cameras are known and fixed; the unknowns are the root's world motion,
  6 numbers (dvx, dvy, dvz, dwx, dwy, dwz): a world translation and a world rotation vector
  about the root joint's current position.
* ``independent`` (the paper's, scaled orthographic views only): each view carries its own
  scaled pose of the body; the root stays at its initial world pose and each view's camera
  moves instead. Per view 6 numbers (ds, dv1, dv2, dwx, dwy, dwz), a similarity acting on
  the left in scaled camera coordinates about the root's image point q_r:
  q -> q_r + (1 + ds) e^{[dw]} (q - q_r) + (dv1, dv2, 0) (paper eqs. 13-15; depth
  translation is invisible and not a parameter).

Joint degrees of freedom follow, in the skeleton's ``dof_joints_and_axes`` order:
R_j <- R_j e^{d [a]} for the axis a of the degree of freedom in joint j's local frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from . import se3
from .bvh import BvhFile
from .camera import Camera, View
from .skeleton import Skeleton

CALIBRATED, INDEPENDENT = "calibrated", "independent"
ROOT_PARAMS = 6
# where each root block (the shared root, or one view's) holds its turn: after the
# translation, or after the scale and the image shift
ROOT_TURN = slice(3, 6)


@dataclass
class BodyPose:
    rotations: np.ndarray  # (J, 3, 3) local rotations; rotations[0] is the root's world rotation
    root_position: np.ndarray  # (3,) world position of the root joint
    views: list[Camera]

    def copy(self) -> BodyPose:
        return BodyPose(
            self.rotations.copy(), self.root_position.copy(), [v.copy() for v in self.views]
        )


def pose_from_bvh(bvh: BvhFile, frame: int, cameras: list[Camera]) -> BodyPose:
    """The pose of a BVH file's frame (0-based), seen through copies of ``cameras``."""
    R, root = bvh.frame_pose(frame)
    return BodyPose(R, root, [c.copy() for c in cameras])


def n_root_params(mode: str, n_views: int) -> int:
    """Number of root parameters: 6 for the shared world root, 6 per view otherwise."""
    return ROOT_PARAMS if mode == CALIBRATED else ROOT_PARAMS * n_views


def apply_update(
    skeleton: Skeleton, pose: BodyPose, delta: np.ndarray, mode: str
) -> BodyPose:
    """The pose moved by the parameter step ``delta`` (root block(s) then joint DOFs)."""
    new = pose.copy()
    nr = n_root_params(mode, len(pose.views))
    if mode == CALIBRATED:
        dv, dw = delta[:3], delta[ROOT_TURN]
        E = se3.exp_so3(dw)
        new.rotations[0] = E @ pose.rotations[0]
        new.root_position = pose.root_position + dv  # rotation is about the root itself
    else:
        for c, view in enumerate(pose.views):
            block = delta[ROOT_PARAMS * c : ROOT_PARAMS * (c + 1)]  # this view's root
            ds, dv1, dv2 = block[:3]
            E = se3.exp_so3(block[ROOT_TURN])
            P = view.pose
            q_r = P.apply(np.asarray(pose.root_position, dtype=float))
            s_new = P.s * (1 + ds)
            R_new = E @ P.R
            t_new = E @ P.t + (q_r + np.array([dv1, dv2, 0.0]) - (1 + ds) * (E @ q_r)) / s_new
            new.views[c] = View(se3.Similarity(s_new, R_new, t_new), view.center.copy())
    dof_joint, dof_axis = skeleton.dof_joints_and_axes()
    for k, (j, a) in enumerate(zip(dof_joint, dof_axis)):
        new.rotations[j] = new.rotations[j] @ se3.exp_so3(a * delta[nr + k])
    return new


def extrapolate(prev: BodyPose, cur: BodyPose, gain: float = 1.0) -> BodyPose:
    """Constant-velocity prediction: cur moved again by ``gain`` times the step prev -> cur."""
    out = cur.copy()
    for j in range(len(cur.rotations)):
        step = se3.log_so3(prev.rotations[j].T @ cur.rotations[j])
        out.rotations[j] = cur.rotations[j] @ se3.exp_so3(gain * step)
    out.root_position = cur.root_position + gain * (cur.root_position - prev.root_position)
    out.views = [vc.extrapolated(vp, gain) for vp, vc in zip(prev.views, cur.views)]
    return out


def world_pose(mode: str, first_camera: View, pose: BodyPose) -> tuple[np.ndarray, np.ndarray]:
    """The joints' local rotations (J, 3, 3), the root's among them in the world, and the
    root's world position (3,) of a tracked pose: what keyframes and BVH files hold. In
    independent mode the root is read through the first view: its given camera
    ``first_camera`` undoes that view's tracked pose."""
    R = pose.rotations.copy()
    if mode == CALIBRATED:
        return R, pose.root_position.copy()
    cam, eff = first_camera.pose, pose.views[0].pose
    R[0] = cam.R.T @ eff.R @ pose.rotations[0]
    q = eff.apply(pose.root_position)
    return R, cam.R.T @ (q / cam.s - cam.t)

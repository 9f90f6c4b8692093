"""The analytic rows [H | J] against finite differences of the projection."""

import numpy as np
import pytest

from core import se3
from core.linearize import Kinematics, rows
from core.pose import CALIBRATED, INDEPENDENT, BodyPose, apply_update, n_root_params
from core.skeleton import human_template
from support.synthetic import side_pinhole, side_view


def _pose(seed=0, pinhole=False):
    sk = human_template()
    rng = np.random.default_rng(seed)
    R = np.array([se3.exp_so3(rng.normal(0, 0.4, 3)) for _ in range(sk.n_joints)])
    camera = side_pinhole if pinhole else side_view
    views = [camera(yaw_deg=90), camera(yaw_deg=30, scale=140.0)]
    return sk, BodyPose(R, sk.rest_positions[0] + 0.1, views)


@pytest.mark.parametrize("mode, pinhole", [(CALIBRATED, False), (INDEPENDENT, False),
                                           (CALIBRATED, True)])
@pytest.mark.parametrize("view", [0, 1])
def test_rows_match_finite_differences(mode, pinhole, view):
    sk, pose = _pose(pinhole=pinhole)
    kin = Kinematics(sk, pose)
    P = n_root_params(mode, 2) + len(kin.dof_joint)
    # one point on every blob: the root's segment and joints deep in the chain (elbows, knees)
    seg = np.array([b.joint for b in sk.blobs])
    ref = np.array([b.centre for b in sk.blobs]) + 0.02
    X = kin.world_points(seg, ref)
    # grad = e_x and e_y read off the x and y pixel motion separately
    A = np.stack([rows(kin, view, mode, seg, X, np.tile(e, (len(X), 1))) for e in np.eye(2)], 1)
    num = np.zeros_like(A)
    h = 1e-6
    for k in range(P):
        d = np.zeros(P)
        d[k] = h
        plus, minus = apply_update(sk, pose, d, mode), apply_update(sk, pose, -d, mode)
        xp = plus.views[view].project(Kinematics(sk, plus).world_points(seg, ref))
        xm = minus.views[view].project(Kinematics(sk, minus).world_points(seg, ref))
        num[:, :, k] = (xp - xm) / (2 * h)
    np.testing.assert_allclose(A, num, atol=1e-5 * np.abs(num).max())
    # a joint's column is zero exactly on segments it does not move
    knee = list(kin.dof_joint).index(sk.index("LeftKnee"))
    col = A[:, :, n_root_params(mode, 2) + knee]
    moved = np.isin(seg, [sk.index("LeftKnee")])
    assert np.all(col[~moved] == 0) and np.all(np.abs(col[moved]).sum(1) > 0)


def test_independent_root_rows_are_the_papers_eq_18():
    sk, pose = _pose(1)
    kin = Kinematics(sk, pose)
    q = np.array([[3.0, -4.0, 7.0]])
    g = np.array([[0.5, -2.0]])
    P = pose.views[0].pose
    X = P.R.T @ (q[0] / P.s - P.t)  # the world point at q
    A = rows(kin, 0, INDEPENDENT, np.array([0]), X[None], g)
    d = q[0] - pose.views[0].scaled(kin.frames[0, :3, 3])  # pivot at the root's image point
    Ix, Iy = g[0]
    x, y, z = d
    np.testing.assert_allclose(A[0, :6], [Ix * x + Iy * y, Ix, Iy, -Iy * z, Ix * z,
                                          -Ix * y + Iy * x])
    assert np.all(A[0, 12:] == 0)  # the second view's root block

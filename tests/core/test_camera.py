"""The pinhole camera against OpenCV's projection and against its own derivatives."""

import cv2
import numpy as np

from core import se3
from core.camera import Pinhole, View, turn_homography, turns_in_place

CAM = Pinhole(np.array([[900.0, 0, 330], [0, 880, 250], [0, 0, 1]]),
              se3.exp_so3(np.array([0.3, -1.1, 0.2])), np.array([0.2, -0.4, 3.5]))


def _points(n=40, seed=0):
    return np.random.default_rng(seed).uniform(-0.8, 0.8, (n, 3))


def test_projection_is_opencvs():
    X = _points()
    ref, _ = cv2.projectPoints(X, cv2.Rodrigues(CAM.R)[0], CAM.t, CAM.K, None)
    np.testing.assert_allclose(CAM.project(X), ref[:, 0], atol=1e-9)


def test_pullback_is_the_projections_jacobian_and_scale_its_local_magnification():
    X = _points(seed=1)
    h = 1e-6
    J = np.stack([(CAM.project(X + h * e) - CAM.project(X - h * e)) / (2 * h)
                  for e in np.eye(3)], -1)  # (N, 2, 3)
    grad = np.random.default_rng(2).normal(size=(len(X), 2))
    np.testing.assert_allclose(CAM.pullback(X, grad), np.einsum("na,nab->nb", grad, J),
                               rtol=1e-6, atol=1e-6)
    # a small step across the line of sight moves the pixel by scale_at times its length
    step = 1e-4 * CAM.R[0]
    moved = np.linalg.norm(CAM.project(X[0] + step) - CAM.project(X[0]))
    assert abs(moved / 1e-4 - CAM.scale_at(X[0])) < 0.02 * CAM.scale_at(X[0])


def test_rays_start_at_the_centre_and_pass_through_their_pixels_on_every_level():
    pix = np.array([[10.0, 20.0], [330.0, 250.0], [600.0, 470.0]])
    for level in (0, 2):
        cam = CAM.at_level(level)
        origin, d = cam.ray(pix)
        np.testing.assert_allclose(origin, np.tile(CAM.centre, (3, 1)), atol=1e-12)
        np.testing.assert_allclose(np.linalg.norm(d, axis=1), 1.0)
        np.testing.assert_allclose(cam.project(origin + 2.5 * d), pix, atol=1e-9)
        assert np.all(cam.camera_points(origin + 2.5 * d)[:, 2] > 0)  # away from the camera
    X = _points(seed=3)
    np.testing.assert_allclose(CAM.at_level(2).project(X) * 4, CAM.project(X), atol=1e-9)


def test_a_turn_about_the_centre_moves_every_depth_by_one_homography():
    turned = Pinhole(np.array([[700.0, 0, 300], [0, 720, 260], [0, 0, 1]]),
                     se3.exp_so3(np.array([0.05, 0.3, -0.02])) @ CAM.R, np.zeros(3))
    turned.t = -turned.R @ CAM.centre  # the same centre
    # points straight ahead of both cameras, near and far
    X = CAM.centre + np.random.default_rng(4).uniform(2, 40, (30, 1)) * (
        CAM.R[2] + turned.R[2] + np.random.default_rng(5).uniform(-0.2, 0.2, (30, 3)))
    H = turn_homography(CAM, turned)
    p = np.c_[CAM.project(X), np.ones(len(X))] @ H.T
    np.testing.assert_allclose(p[:, :2] / p[:, 2:], turned.project(X), atol=1e-8)
    near = X[np.argmin(np.linalg.norm(X - CAM.centre, axis=1))]
    assert turns_in_place([CAM, turned], near)
    # its centre moved: parallax of a pixel at the nearest point is too much
    shift = 1.5 / CAM.scale_at(near)
    moved = Pinhole(turned.K, turned.R, turned.t - turned.R @ (shift * CAM.R[0]))
    assert not turns_in_place([CAM, moved], near)
    assert turns_in_place([CAM, moved], CAM.centre + 10 * (near - CAM.centre))  # far off
    ortho = View(se3.Similarity(100.0, CAM.R, np.zeros(3)), np.zeros(2))
    assert not turns_in_place([ortho, ortho], near)

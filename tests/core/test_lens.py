"""Lens distortion: points both ways against OpenCV's projection, footage undistorted."""

import cv2
import numpy as np

from core.lens import Undistorted, distort_points, undistort_points

K = np.array([[420.0, 0, 170], [0, 410, 140], [0, 0, 1]])
DIST = np.array([-0.3, 0.1, 0.002, -0.003, 0.0])


def test_points_are_distorted_as_opencv_projects_them_and_undistorted_back():
    rng = np.random.default_rng(0)
    X = np.column_stack([rng.uniform(-0.4, 0.4, (50, 2)), np.full(50, 1.0)])  # camera frame
    ideal = X[:, :2] @ K[:2, :2].T + K[:2, 2]
    filmed, _ = cv2.projectPoints(X, np.zeros(3), np.zeros(3), K, DIST)
    np.testing.assert_allclose(distort_points(ideal, K, DIST), filmed[:, 0], atol=1e-9)
    np.testing.assert_allclose(undistort_points(filmed[:, 0], K, DIST), ideal, atol=1e-6)
    assert np.max(np.linalg.norm(filmed[:, 0] - ideal, axis=1)) > 5  # the lens does move them


def test_footage_is_read_as_the_ideal_pinhole_sees_it(tmp_path):
    """Bright dots drawn where the lens puts known points come out, undistorted, at the
    points themselves."""
    ideal = np.array([[60.0, 50.0], [290.0, 60.0], [170.0, 140.0], [70.0, 230.0],
                      [280.0, 240.0]])
    filmed = distort_points(ideal, K, DIST)
    img = np.zeros((280, 340), np.uint8)
    for x, y in filmed:
        cv2.circle(img, (int(round(x * 16)), int(round(y * 16))), 4 * 16, 255, -1,
                   cv2.LINE_AA, shift=4)
    cv2.imwrite(str(tmp_path / "f.png"), img)
    frames = Undistorted([str(tmp_path / "f.png")] * 2, K, DIST)
    assert len(frames) == 2
    out = frames[1]
    assert out.shape == img.shape and out.dtype == np.float32
    for x, y in ideal:
        x0, y0 = int(x) - 10, int(y) - 10
        patch = out[y0:y0 + 21, x0:x0 + 21].astype(float)
        yy, xx = np.mgrid[0:21, 0:21]
        centroid = np.array([np.sum(xx * patch), np.sum(yy * patch)]) / patch.sum() + (x0, y0)
        assert np.linalg.norm(centroid - (x, y)) < 0.35

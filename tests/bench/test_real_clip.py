"""The real clip's floor: every frame fitted to its own landmarks."""

import sys
from pathlib import Path

import numpy as np

from core import se3
from core.calibration import read_calibration
from core.pose import CALIBRATED
from core.skeleton import human_template

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

import real_clip  # noqa: E402


def _landmarks(sk, poses, cams, swapped_view: int) -> tuple[np.ndarray, np.ndarray]:
    """MediaPipe-shaped landmarks (views, frames, 33, 2) and visibility of the scored points
    of ``poses``, seen through the calibration's lenses, one view's sides swapped."""
    xy = np.zeros((len(cams), len(poses), 33, 2))
    vis = np.zeros((len(cams), len(poses), 33))
    for f, (R, root) in enumerate(poses):
        pts = real_clip.point_positions(sk, R, root)
        for c, cam in enumerate(cams):
            for name, i in real_clip.POINTS.items():
                seen_as = real_clip.SWAP[name] if c == swapped_view else name
                xy[c, f, real_clip.POINTS[seen_as]] = real_clip.distort_points(
                    cam.camera.project(pts[name]), cam.camera.K, cam.dist)
                vis[c, f, i] = 1.0
    return xy, vis


def test_each_frame_fitted_to_its_landmarks_finds_the_pose_they_came_from():
    sk = human_template(lower_back=True)
    cams = read_calibration(real_clip.DATA / "Calib.qca.txt")
    views = [c.camera for c in cams]
    # the clip's first frame's hips and shoulders place the body among the cameras
    lm = np.load(real_clip.DATA / "mediapipe_landmarks.npz")
    ideal = real_clip.ideal_points(cams, lm["xy"].astype(float), 0)
    R0, root0 = real_clip.guess_pose(sk, views, ideal)
    rng = np.random.default_rng(3)
    truth, start = [], []
    for _ in range(2):
        R = R0.copy()
        for name in ("LeftShoulder", "RightElbow", "LeftHip", "RightKnee"):
            R[sk.index(name)] = se3.exp_so3(rng.normal(0, 0.4, 3))
        truth.append((R, root0 + rng.normal(0, 0.05, 3)))
        start.append((R0, root0))  # the fit starts from the tracked pose; here a far one
    xy, vis = _landmarks(sk, truth, cams, swapped_view=1)
    fitted = real_clip.fitted_each_frame(sk, start, cams, views, CALIBRATED, xy, vis)
    errors = real_clip.errors_pct(sk, fitted, cams, xy, vis)
    assert np.all(errors < 0.05), errors
    assert np.all(real_clip.errors_pct(sk, start, cams, xy, vis) > 1.0)

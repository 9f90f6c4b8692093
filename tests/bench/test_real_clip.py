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


def test_each_point_reads_its_own_distance_and_the_points_average_to_the_frames_score():
    sk = human_template(lower_back=True)
    cams = read_calibration(real_clip.DATA / "Calib.qca.txt")
    lm = np.load(real_clip.DATA / "mediapipe_landmarks.npz")
    R, root = real_clip.guess_pose(sk, [c.camera for c in cams],
                                   real_clip.ideal_points(cams, lm["xy"].astype(float), 0))
    poses = [(R, root)] * 2
    xy, vis = _landmarks(sk, poses, cams, swapped_view=1)
    knee = list(real_clip.POINTS).index("LeftKnee")
    xy[2, 1, real_clip.POINTS["LeftKnee"]] += (6.0, 8.0)  # 10 px off, frame 1, view 3
    vis[3, 0, real_clip.POINTS["RightElbow"]] = 0.0  # not seen there
    per_point = real_clip.point_errors_pct(sk, poses, cams, xy, vis)
    height = sk.height() * cams[2].camera.scale_at(root)
    assert abs(per_point[1, 2, knee] - 1000 / height) < 1e-6
    per_point[1, 2, knee] = 0.0
    assert np.isnan(per_point[0, 3, list(real_clip.POINTS).index("RightElbow")])
    assert np.nanmax(per_point) < 1e-6  # the swapped view too: its sides matched back
    np.testing.assert_allclose(np.nanmean(real_clip.point_errors_pct(sk, poses, cams, xy, vis),
                                          axis=2),
                               real_clip.errors_pct(sk, poses, cams, xy, vis), atol=1e-9)


def test_the_starts_line_reads_each_starts_drift_as_its_own_last_five_over_its_first():
    # two starts: one holding (2 -> 3, 1.5x), one drifting (1 -> 4, 4x); the ratio of the
    # starts' means (3.5 / 1.5) would hide the one that drifts
    line = real_clip._spread([2.5, 2.5], [2.0, 1.0], [3.0, 4.0])
    assert "first five 1.5 (1.0-2.0)" in line
    assert "last five 3.5 (3.0-4.0)" in line
    assert "last five over first five 2.75 (1.50-4.00)x" in line


def test_the_flags_are_read_against_each_frames_landmark_fit_limb_by_limb():
    # three frames; the fit's left forearm 30 degrees off the track on frames 1 and 2, its
    # right thigh 5 degrees off on frame 2; the report flags the left elbow's segment on
    # frame 1 (right) and the right hip's on frame 2 (a flag on a limb near the fit)
    sk = human_template(lower_back=True)
    rest = (np.tile(np.eye(3), (sk.n_joints, 1, 1)), np.zeros(3))
    tracked = [(rest[0].copy(), rest[1]) for _ in range(3)]
    floor = [(R.copy(), p) for R, p in tracked]
    elbow, hip = sk.index("LeftElbow"), sk.index("RightHip")
    for f in (1, 2):
        floor[f][0][elbow] = se3.exp_so3(np.radians(30.0) * np.array([1.0, 0, 0]))
    floor[2][0][hip] = se3.exp_so3(np.radians(5.0) * np.array([1.0, 0, 0]))
    names = ["Spine", "Neck", "LeftShoulder", "LeftElbow", "RightShoulder", "RightElbow",
             "LeftHip", "LeftKnee", "RightHip", "RightKnee"]
    flags = {1: "LeftElbow", 2: "RightHip"}
    rep = {"frames": [{"frame": 0, "limbs": None}] + [
        {"frame": f, "limbs": {n: {"flag": "unsure" if flags[f] == n else ""} for n in names}}
        for f in (1, 2)]}
    line = real_clip.flag_line(sk, rep, tracked, floor)
    assert "50 % of the 2 limbs over 20° off that fit flagged" in line
    assert "50 % of the 2 flags on such limbs" in line

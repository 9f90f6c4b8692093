"""The job file and the command line, end to end on footage written to disk."""

import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from core import se3
from core.bvh import read_bvh, write_bvh
from core.job import JobError, load_job, parse_camera
from core.lens import undistort_points
from core.pose import BodyPose
from support.synthetic import EXACT, render

ROOT = Path(__file__).resolve().parents[2]
JOINTS = {"LeftHip": "ball", "RightHip": "ball",
          "LeftKnee": {"kind": "hinge", "axis": [0.94, 0.34, 0]},
          "RightKnee": {"kind": "hinge", "axis": [0.94, -0.34, 0]}}
CAMERA = {"model": "scaled_orthographic", "R": [[0, 0, 1], [0, -1, 0], [1, 0, 0]],
          "t": [0.55, 0.85, 5.0], "scale": 150, "center": [160, 150]}
FRONT = {"model": "scaled_orthographic", "R": [[1, 0, 0], [0, -1, 0], [0, 0, -1]],
         "t": [-0.25, 0.85, 5.0], "scale": 150, "center": [160, 150]}
_R60 = se3.exp_so3(np.radians([0, -30, 0])) @ np.array(CAMERA["R"], float).T
OBLIQUE = dict(CAMERA, R=(_R60.T).tolist())

LEGS = [("LeftHip", "LeftKnee"), ("LeftKnee", "LeftAnkle"), ("RightHip", "RightKnee"),
        ("RightKnee", "RightAnkle")]


def _leg_errors(sk, got: tuple, true: tuple) -> np.ndarray:
    """(frames, 4): degrees between each tracked and true thigh and shank."""
    out = []
    for R_g, p_g, R_t, p_t in zip(*got, *true):
        X, Y = sk.world_positions(R_g, p_g), sk.world_positions(R_t, p_t)
        out.append([np.degrees(se3.angle_between_vectors(X[sk.index(b)] - X[sk.index(a)],
                                                         Y[sk.index(b)] - Y[sk.index(a)]))
                    for a, b in LEGS])
    return np.array(out)


@pytest.fixture(scope="module")
def footage(tmp_path_factory, cmu_walk):
    """Three frames of the CMU walk's own blobs in three views, as PNG files."""
    folder = tmp_path_factory.mktemp("job")
    b = read_bvh(cmu_walk)
    b.motion = b.motion[600:612:4]
    write_bvh(b, folder / "walk.bvh")
    job = {"skeleton": {"bvh": "walk.bvh", "joints": JOINTS},
           "initial": {"bvh": "walk.bvh", "frame": 0},
           "views": [{"images": "side/*.png", "camera": CAMERA},
                     {"images": "front/*.png", "camera": FRONT},
                     {"images": "oblique/*.png", "camera": OBLIQUE}],
           "mode": "calibrated", "settings": {"levels": 2, "iterations": 20, **EXACT}}
    (folder / "job.json").write_text(json.dumps(job))
    views = ["side", "front", "oblique"]
    for v in views:  # placeholders, so that the job loads and gives its skeleton's blobs
        (folder / v).mkdir()
        for f in range(3):
            cv2.imwrite(str(folder / v / f"{f:03d}.png"), np.zeros((4, 4), np.uint8))
    loaded = load_job(folder / "job.json")
    R, p = b.poses()
    for c, v in enumerate(views):
        for f in range(3):
            pose = BodyPose(R[f], p[f], loaded.cameras)
            img = render(loaded.skeleton, pose, c, shape=(300, 320), noise=0.01, seed=f)
            cv2.imwrite(str(folder / v / f"{f:03d}.png"), (img * 255).astype(np.uint8))
    return folder, job


def _run(*args):
    return subprocess.run([sys.executable, "-m", "core", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True)


@pytest.mark.parametrize("mode", ["calibrated", "independent"])
def test_command_line_tracks_and_writes_bvh_and_report(footage, tmp_path, mode):
    folder, job = footage
    job_path = folder / f"job_{mode}.json"
    job_path.write_text(json.dumps(dict(job, mode=mode)))
    out, rep = tmp_path / "out.bvh", tmp_path / "report.json"
    proc = _run("track", job_path, "--out", out, "--report", rep)
    assert proc.returncode == 0, proc.stderr
    src, got = read_bvh(folder / "walk.bvh"), read_bvh(out)
    assert got.names == src.names
    assert [j.channels for j in got.joints] == [j.channels for j in src.joints]
    assert len(got.motion) == 3
    R_true, p_true = src.poses()
    R_got, p_got = got.poses()
    sk = load_job(folder / "job.json").skeleton
    assert np.all(_leg_errors(sk, (R_got, p_got), (R_true, p_true)) < 2.0)
    for f in range(3):
        # independent mode reads the root through the first camera, which cannot see depth
        seen = np.array(CAMERA["R"], float)[:2] if mode == "independent" else np.eye(3)
        assert np.linalg.norm(seen @ (p_got[f] - p_true[f])) < 0.005
    untracked = src.names.index("LeftShoulder")  # keeps the initial rotation
    np.testing.assert_allclose(R_got[:, untracked], np.repeat(R_true[:1, untracked], 3, 0),
                               atol=1e-5)
    report = json.loads(rep.read_text())
    assert report["frames_tracked"] == report["frames_total"] == 2  # after the first
    assert report["diverged_frames"] == []
    assert {"frame", "residual", "iterations", "converged", "seconds"} <= set(report["frames"][1])
    assert report["frames"][0]["limbs"] == {}  # the given pose is not judged
    for fr in report["frames"][1:]:  # every tracked joint's confidence, per view too
        assert set(fr["limbs"]) == set(sk.tracked_joint_names())
        for check in fr["limbs"].values():
            assert 0 <= check["confidence"] <= 1 and len(check["views"]) == 3
            assert check["flag"] in ("", "unsure", "unseen")
    flagged = [fr["frame"] for fr in report["frames"] if any(
        c["flag"] for c in fr["limbs"].values())]
    assert report["frames_to_check"] == flagged
    begun = [b["frame"] for b in report["doubts_begin"]]  # where each run of flags starts
    assert begun[:1] == flagged[:1] and set(begun) <= set(flagged)
    assert ("check " in proc.stderr) == bool(flagged)


@pytest.mark.parametrize("flag", ["--out", "--report"])
def test_an_output_folder_that_does_not_exist_stops_the_run_before_it_starts(footage,
                                                                           tmp_path, flag):
    folder, _ = footage
    paths = {"--out": tmp_path / "out.bvh", "--report": tmp_path / "report.json"}
    paths[flag] = tmp_path / "missing" / paths[flag].name
    proc = _run("track", folder / "job.json", "--out", paths["--out"], "--report",
                paths["--report"])
    assert proc.returncode == 2
    assert f"({tmp_path / 'missing'}) does not exist" in proc.stderr
    assert "frame" not in proc.stderr and not any(tmp_path.iterdir())  # nothing tracked


def test_the_report_is_strict_json_with_limb_checks_and_its_bvh_ends_before_a_divergence(
        footage, tmp_path):
    from core.confidence import LimbCheck
    from core.frame_fit import FrameResult
    from core.run import report, result_bvh, write_report
    from core.tracker import TrackResult

    folder, _ = footage
    job = load_job(folder / "job.json")
    result = TrackResult([
        FrameResult(frame=0, pose=job.initial, residual=0.0, iterations=0, converged=True,
                    given=True),
        FrameResult(frame=1, pose=job.initial, residual=0.01, iterations=3, converged=True,
                    limbs={"LeftKnee": LimbCheck(0.2, (0.2, None, 0.9)),
                           "RightKnee": LimbCheck(0.8, (0.8, 0.9, 0.9))},
                    searched=["LeftHip"]),
        FrameResult(frame=2, pose=job.initial, residual=float("nan"), iterations=0,
                    converged=False, diverged=True, reason="the body left the image")])
    write_report(tmp_path / "report.json", report(job, result, 1.0))
    rep = json.loads((tmp_path / "report.json").read_text(),
                     parse_constant=lambda c: pytest.fail(f"{c} is not JSON"))
    assert rep["frames"][2]["residual"] is None and rep["diverged_frames"] == [2]
    assert (rep["frames_tracked"], rep["frames_total"]) == (1, 2)
    assert len(result_bvh(job, result).motion) == 2
    assert rep["frames_to_check"] == [1]
    assert [f["searched"] for f in rep["frames"]] == [[], ["LeftHip"], []]
    assert rep["frames"][1]["limbs"] == {
        "LeftKnee": {"confidence": 0.2, "flag": "unsure", "views": [0.2, None, 0.9],
                     "unexplained": None},
        "RightKnee": {"confidence": 0.8, "flag": "", "views": [0.8, 0.9, 0.9],
                      "unexplained": None}}


def test_an_image_that_cannot_be_read_is_named_before_any_frame_is_tracked(footage, tmp_path):
    folder, job = footage
    broken = folder / "broken"
    broken.mkdir(exist_ok=True)
    for f in range(3):
        data = (folder / "side" / f"{f:03d}.png").read_bytes()
        (broken / f"{f:03d}.png").write_bytes(data if f < 2 else data[:200])  # cut short
    job_path = folder / "job_broken.json"
    views = [dict(job["views"][0], images="broken/*.png")] + job["views"][1:]
    job_path.write_text(json.dumps(dict(job, views=views)))
    out = tmp_path / "out.bvh"
    proc = _run("track", job_path, "--out", out, "--report", tmp_path / "r.json")
    assert proc.returncode == 2, proc.stderr
    assert proc.stderr.startswith("error: ")  # the decoder's own words are not shown
    assert "002.png: cannot read this image (view 1's footage; cut short" in proc.stderr
    assert "frame" not in proc.stderr.split("error")[0] and not out.exists()


def test_images_of_one_view_in_two_sizes_are_refused_before_tracking(footage, tmp_path):
    folder, job = footage
    mixed = folder / "mixed"
    mixed.mkdir(exist_ok=True)
    for f in range(3):
        img = cv2.imread(str(folder / "side" / f"{f:03d}.png"))
        cv2.imwrite(str(mixed / f"{f:03d}.png"), img if f != 1 else img[:-3])
    job_path = folder / "job_mixed.json"
    job_path.write_text(json.dumps(dict(job, views=[dict(job["views"][0], images="mixed/*.png")]
                                        + job["views"][1:])))
    proc = _run("track", job_path, "--out", tmp_path / "out.bvh")
    assert proc.returncode == 2, proc.stderr
    assert ("view 1's footage: its images differ in size (000.png is 320x300, 001.png 320x297)"
            ": crop or pad them to one size") in proc.stderr


def test_a_first_pose_outside_a_view_is_refused_before_tracking(footage, tmp_path):
    """The body must stand more than wholly inside the images (min_inside 1.5): no first
    pose can, and the run says so instead of reporting a divergence on the next frame."""
    folder, job = footage
    job_path = folder / "job_outside.json"
    job_path.write_text(json.dumps(dict(job, settings={"min_inside": 1.5})))
    proc = _run("track", job_path, "--out", tmp_path / "out.bvh")
    assert proc.returncode == 2, proc.stderr
    assert "on the first frame only 100% of the body is inside view 1's image" in proc.stderr
    assert not (tmp_path / "out.bvh").exists()


def test_the_command_line_says_what_it_does_and_runs_from_any_folder(tmp_path):
    proc = subprocess.run([sys.executable, "-m", "core", "--help"], cwd=tmp_path,
                          capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "footage of a moving body in, a BVH out" in proc.stdout
    assert "JOB_FORMAT.md" in proc.stdout and "track" in proc.stdout and "fit" in proc.stdout


def test_a_corrected_frame_takes_its_given_pose_and_the_others_are_tracked(footage, tmp_path):
    """The job corrects frame 2 to the walk's first pose (as if the user had set it there):
    the output holds that pose on frame 2 and frame 1 tracked as before."""
    folder, job = footage
    job_path = folder / "job_corrected.json"
    job_path.write_text(json.dumps(dict(job, corrections=[
        {"image": 2, "bvh": "walk.bvh", "frame": 0}])))
    assert set(load_job(job_path).corrections) == {2}
    plain, corrected = tmp_path / "plain.bvh", tmp_path / "corrected.bvh"
    assert _run("track", folder / "job.json", "--out", plain).returncode == 0
    report = tmp_path / "report.json"
    proc = _run("track", job_path, "--out", corrected, "--report", report)
    assert proc.returncode == 0, proc.stderr
    frames = json.loads(report.read_text())["frames"]
    assert [f["given"] for f in frames] == [True, False, True]
    src = read_bvh(folder / "walk.bvh")
    np.testing.assert_allclose(read_bvh(corrected).motion[2], src.motion[0], atol=1e-4)
    assert np.abs(read_bvh(plain).motion[2] - src.motion[0]).max() > 1.0  # it moved
    np.testing.assert_allclose(read_bvh(corrected).motion[1], read_bvh(plain).motion[1])


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda j: j.pop("views"), "job.json: missing field 'views'"),
        (lambda j: j["views"][0]["camera"].update(R=[[1, 0, 0], [0, 2, 0], [0, 0, 1]]),
         r"job.json.views\[0\].camera.R: expected a 3x3 rotation matrix"),
        (lambda j: j["views"][0]["camera"].update(model="perspective"),
         "expected 'pinhole' or 'scaled_orthographic', got 'perspective'"),
        (lambda j: j["skeleton"]["joints"].update(Tail="ball"),
         "job.json.skeleton.joints.Tail: no such joint"),
        (lambda j: j["skeleton"]["joints"].update(LeftKnee={"kind": "hinge"}),
         "a hinge needs an 'axis'"),
        (lambda j: j["skeleton"]["joints"].update(
            LeftKnee={"kind": "hinge", "axis": [1, 0, 0], "limits": [90, 0]}),
         r"skeleton.joints.LeftKnee.limits: expected \[lowest, highest\] angle in degrees"),
        (lambda j: j["settings"].update(speed=3), "job.json.settings.speed: unknown setting"),
        (lambda j: j["settings"].update(levels="many"), "settings.levels: expected a int"),
        (lambda j: j["views"][0].update(images="nowhere/*.png"),
         r"views\[0\].images: the pattern 'nowhere/\*.png' matches no file"),
        (lambda j: j["views"].append({"images": ["side/000.png"], "camera": CAMERA}),
         "every view needs the same number of frames, got 3, 3, 3, 1"),
        (lambda j: j.update(mode="both"), "job.json.mode: expected 'calibrated' or"),
        (lambda j: j["initial"].update(frame=7), r"initial.frame: 7 is outside 0..2"),
        (lambda j: j.update(corrections=[{"image": 0, "bvh": "walk.bvh"}]),
         r"corrections\[0\].image: 0 is outside 1..2 \(frame 0 is the initial pose's\)"),
        (lambda j: j.update(corrections=[{"image": 2, "bvh": "walk.bvh", "frame": 9}]),
         r"corrections\[0\].frame: 9 is outside 0..2"),
        (lambda j: j.update(corrections=[{"image": 1, "bvh": "walk.bvh"}] * 2),
         r"corrections\[1\].image: frame 1 is corrected twice"),
        (lambda j: j.update(corrections={"image": 1}), "job.json.corrections: expected a list"),
        (lambda j: j["views"][0].update(backdrop="empty.png"),
         r"views\[0\].backdrop: expected the path of an image of the scene without the body"),
    ],
)
def test_malformed_jobs_get_one_clear_error(footage, tmp_path, change, message):
    folder, job = footage
    bad = json.loads(json.dumps(job))
    change(bad)
    broken = folder / "job.json"  # the name the messages carry
    good = broken.read_text()
    broken.write_text(json.dumps(bad))
    try:
        with pytest.raises(JobError, match=message):
            load_job(broken)
        proc = _run("track", broken, "--out", tmp_path / "x.bvh")
    finally:
        broken.write_text(good)
    assert proc.returncode == 2 and proc.stderr.startswith("error: job.json")
    assert not (tmp_path / "x.bvh").exists()


def test_clean_plates_are_the_backdrops_and_one_of_another_size_is_named(footage, tmp_path):
    """Each view given its scene without the body (the renderer's plain background): the
    run tracks as well; a plate cropped to another size stops it before any frame."""
    folder, job = footage
    with_plates = json.loads(json.dumps(job))
    for v in with_plates["views"]:
        name = v["images"].split("/")[0] + "_plate.png"
        cv2.imwrite(str(folder / name), np.full((300, 320), round(0.3 * 255), np.uint8))
        v["backdrop"] = name
    job_path = folder / "job_plates.json"
    job_path.write_text(json.dumps(with_plates))
    out = tmp_path / "out.bvh"
    proc = _run("track", job_path, "--out", out)
    assert proc.returncode == 0, proc.stderr
    R_true, p_true = read_bvh(folder / "walk.bvh").poses()
    sk = load_job(job_path).skeleton
    assert np.all(_leg_errors(sk, read_bvh(out).poses(), (R_true, p_true)) < 2.0)
    plate = folder / with_plates["views"][1]["backdrop"]
    cv2.imwrite(str(plate), np.full((300, 300), 77, np.uint8))
    proc = _run("track", job_path, "--out", tmp_path / "x.bvh")
    assert proc.returncode == 2
    assert f"{plate}: view 2's clean plate is 300x300, its footage 320x300" in proc.stderr
    assert not (tmp_path / "x.bvh").exists()


def test_a_tracked_joint_with_nothing_away_from_it_is_refused(footage, tmp_path):
    """The left toe's end site moved onto the toe joint: its bone has no length, so no pixel
    can show the toe turn; tracking it is an error naming the joint."""
    folder, job = footage
    bvh = read_bvh(folder / "walk.bvh")
    toe = bvh.names.index("LeftToe")
    bvh.joints[toe].end_sites = [np.zeros(3)]
    write_bvh(bvh, tmp_path / "flat_toe.bvh")
    spec = json.loads(json.dumps(job))
    spec["skeleton"] = {"bvh": str(tmp_path / "flat_toe.bvh"),
                        "joints": dict(job["skeleton"]["joints"], LeftToe="ball")}
    (tmp_path / "job.json").write_text(json.dumps(spec))
    with pytest.raises(JobError, match="joints.LeftToe: every bone below this joint has zero "
                                       "length in the BVH, so no pixel can show it turn"):
        load_job(tmp_path / "job.json")


def test_camera_parsing_maps_world_points_as_documented():
    (view,), dist = parse_camera(CAMERA, "cam")
    assert dist is None
    X = np.array([0.2, 1.0, -0.4])
    R, t = np.array(CAMERA["R"], float), np.array(CAMERA["t"])
    expect = 150 * (R @ X + t)[:2] + np.array(CAMERA["center"])
    np.testing.assert_allclose(view.project(X), expect)


def test_a_movie_is_footage_like_its_frames(footage, tmp_path):
    folder, job = footage
    frames = sorted((folder / "side").glob("*.png"))
    movie = folder / "side.avi"  # Motion-JPEG: lossy, so compared within a few grey levels
    first = cv2.imread(str(frames[0]))
    writer = cv2.VideoWriter(str(movie), cv2.VideoWriter_fourcc(*"MJPG"), 30,
                             (first.shape[1], first.shape[0]))
    for f in frames:
        writer.write(cv2.imread(str(f)))
    writer.release()
    from core.video import VideoFrames

    video = VideoFrames(movie)
    assert len(video) == 3
    for i in (2, 0, 1):  # a seek back, then forward
        diff = np.abs(video[i].astype(int) - cv2.imread(str(frames[i])).astype(int))
        assert diff.mean() < 3
    bad = dict(job, views=[dict(job["views"][0], images="side.avi"),
                           dict(job["views"][1], images="nowhere.mp4")])
    path = folder / "job_movie.json"
    path.write_text(json.dumps(bad))
    with pytest.raises(JobError, match=r"views\[1\].images: the movie 'nowhere.mp4' is not"):
        load_job(path)
    ok = dict(job, views=job["views"][:1], settings={"levels": 2})
    ok["views"] = [dict(job["views"][0], images="side.avi")]
    path.write_text(json.dumps(ok))
    out = tmp_path / "movie.bvh"
    proc = _run("track", path, "--out", out, "--quiet")
    assert proc.returncode == 0, proc.stderr
    assert len(read_bvh(out).motion) == 3


def test_hinge_limits_are_read_in_degrees(footage, tmp_path):
    folder, job = footage
    limited = json.loads(json.dumps(job))
    limited["skeleton"]["joints"]["LeftKnee"]["limits"] = [-5, 150]
    path = folder / "job_limited.json"
    path.write_text(json.dumps(limited))
    sk = load_job(path).skeleton
    np.testing.assert_allclose(np.degrees(sk.limits[sk.index("LeftKnee")]), [-5, 150])
    assert np.all(np.isinf(sk.limits[sk.index("RightKnee")]))  # none given: free


def _pinhole(camera: dict, dist=None) -> dict:
    """The pinhole twin of a scaled orthographic test camera: 3 units from the body, with
    the focal length that shows it as large."""
    f = camera["scale"] * 3.0
    out = {"model": "pinhole", "K": [[f, 0, camera["center"][0]], [0, f, camera["center"][1]],
                                     [0, 0, 1]],
           "R": camera["R"], "t": camera["t"][:2] + [3.0]}
    return out if dist is None else dict(out, dist=dist)


LENS = [-0.25, 0.08, 0.002, -0.001, 0.0]  # a wide lens's barrel distortion, OpenCV's model


@pytest.fixture(scope="module")
def pinhole_footage(tmp_path_factory, footage):
    """The walk of ``footage`` filmed through three pinhole cameras 3 units away; the first
    view's lens distorts (its frames as filmed, the job gives ``dist``)."""
    src_folder, src_job = footage
    folder = tmp_path_factory.mktemp("pinhole_job")
    (folder / "walk.bvh").write_bytes((src_folder / "walk.bvh").read_bytes())
    cams = [_pinhole(CAMERA, LENS), _pinhole(FRONT), _pinhole(OBLIQUE)]
    job = dict(src_job, views=[dict(v, camera=c) for v, c in zip(src_job["views"], cams)])
    job.pop("mode")  # pinhole cameras are calibrated
    (folder / "job.json").write_text(json.dumps(job))
    for v in ("side", "front", "oblique"):
        (folder / v).mkdir()
        for f in range(3):
            cv2.imwrite(str(folder / v / f"{f:03d}.png"), np.zeros((4, 4), np.uint8))
    loaded = load_job(folder / "job.json")
    assert loaded.mode == "calibrated"
    b = read_bvh(folder / "walk.bvh")
    R, p = b.poses()
    H, W = 300, 320
    ys, xs = np.mgrid[0:H, 0:W].astype(np.float32)
    K = np.array(cams[0]["K"], float)
    ideal = undistort_points(np.stack([xs.ravel(), ys.ravel()], 1), K, np.array(LENS))
    for c, v in enumerate(["side", "front", "oblique"]):
        for f in range(3):
            img = render(loaded.skeleton, BodyPose(R[f], p[f], loaded.cameras), c,
                         shape=(H, W), noise=0.01, seed=f)
            if c == 0:  # as the lens shows it: each filmed pixel sees its ideal point
                maps = ideal.reshape(H, W, 2).astype(np.float32)
                img = cv2.remap(img.astype(np.float32), maps[..., 0], maps[..., 1],
                                cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)
            cv2.imwrite(str(folder / v / f"{f:03d}.png"), (img * 255).astype(np.uint8))
    return folder, job


def test_pinhole_views_with_a_distorting_lens_track_as_the_orthographic_ones(pinhole_footage,
                                                                              tmp_path):
    folder, job = pinhole_footage
    out = tmp_path / "out.bvh"
    proc = _run("track", folder / "job.json", "--out", out)
    assert proc.returncode == 0, proc.stderr
    src, got = read_bvh(folder / "walk.bvh"), read_bvh(out)
    R_true, p_true = src.poses()
    R_got, p_got = got.poses()
    sk = load_job(folder / "job.json").skeleton
    assert np.all(_leg_errors(sk, (R_got, p_got), (R_true, p_true)) < 2.0)
    assert np.all(np.linalg.norm(p_got - p_true, axis=1) < 0.01)  # depth too: a pinhole sees it


@pytest.mark.parametrize(
    "change, message",
    [
        (lambda c: c["K"][1].__setitem__(0, 5.0), r"camera.K: expected an upper triangular"),
        (lambda c: c["K"][0].__setitem__(0, -450.0),
         r"camera.K: the focal lengths fx = -450, fy = 450 \(pixels\) must be > 0"),
        (lambda c: c.update(t=c["t"][:2] + [-3.0]),
         r"job.json.initial: the joint '\w+' lies behind view 1's camera"),
        (lambda c: c.update(dist=[0.1, 0.2]), r"camera.dist: expected OpenCV's distortion"),
    ],
)
def test_malformed_pinhole_cameras_get_one_clear_error(pinhole_footage, change, message):
    folder, job = pinhole_footage
    bad = json.loads(json.dumps(job))
    change(bad["views"][0]["camera"])
    path = folder / "job.json"
    good = path.read_text()
    path.write_text(json.dumps(bad))
    try:
        with pytest.raises(JobError, match=message):
            load_job(path)
        path.write_text(json.dumps(dict(job, mode="independent")))
        with pytest.raises(JobError, match="view 1's camera is a pinhole.*'calibrated'"):
            load_job(path)
    finally:
        path.write_text(good)


def test_a_camera_that_pans_is_followed_frame_by_frame(pinhole_footage, tmp_path):
    """The first view's camera pans 4 degrees a frame about its own vertical axis: given its
    R and t on every frame the walk tracks as from still cameras; the same footage told the
    camera stood still does not."""
    src_folder, src_job = pinhole_footage
    folder = tmp_path / "pan"
    folder.mkdir()
    (folder / "walk.bvh").write_bytes((src_folder / "walk.bvh").read_bytes())
    still = _pinhole(CAMERA)
    R0, t0 = np.array(still["R"], float), np.array(still["t"], float)
    centre = -R0.T @ t0
    Rs = [se3.exp_so3(np.radians([0, 4.0 * f, 0])) @ R0 for f in range(3)]
    pan = dict(still, R=[R.tolist() for R in Rs], t=[(-R @ centre).tolist() for R in Rs])
    views = [dict(v, camera=c) for v, c in zip(src_job["views"], [pan, _pinhole(FRONT),
                                                                   _pinhole(OBLIQUE)])]
    job = dict(src_job, views=views)
    for v in ("side", "front", "oblique"):
        (folder / v).mkdir()
        for f in range(3):
            cv2.imwrite(str(folder / v / f"{f:03d}.png"), np.zeros((4, 4), np.uint8))
    (folder / "job.json").write_text(json.dumps(job))
    loaded = load_job(folder / "job.json")
    assert loaded.moving[0] is not None and loaded.moving[1] is None
    R, p = read_bvh(folder / "walk.bvh").poses()
    for c, v in enumerate(["side", "front", "oblique"]):
        for f in range(3):
            cams = [loaded.moving[0][f]] + loaded.cameras[1:]
            img = render(loaded.skeleton, BodyPose(R[f], p[f], cams), c, shape=(300, 320),
                         noise=0.01, seed=f)
            cv2.imwrite(str(folder / v / f"{f:03d}.png"), (img * 255).astype(np.uint8))
    errors = {}
    for name, cam in (("panning", pan), ("told_still", dict(pan, R=pan["R"][0], t=pan["t"][0]))):
        (folder / f"{name}.json").write_text(json.dumps(dict(job, views=[
            dict(views[0], camera=cam)] + views[1:])))
        out, report = tmp_path / f"{name}.bvh", tmp_path / f"{name}.report.json"
        proc = _run("track", folder / f"{name}.json", "--out", out, "--report", report)
        assert proc.returncode in (0, 3), proc.stderr
        notes = json.loads(report.read_text())["notes"]
        # the camera turns about its centre: its backdrop is turned with it, not left out
        assert not any(n.startswith("view 1: its camera moves") for n in notes), notes
        R_got, p_got = read_bvh(out).poses()
        n = len(R_got)
        legs = _leg_errors(loaded.skeleton, (R_got, p_got), (R[:n], p[:n]))
        root_cm = 100 * np.linalg.norm(p_got - p[:n], axis=1)
        errors[name] = max(legs.max(), root_cm.max())  # 1 cm counted as 1 degree
    assert errors["panning"] < 2.0
    assert errors["told_still"] > 2 * errors["panning"] + 2.0, errors
    ortho_pan = dict(CAMERA, R=[R.tolist() for R in Rs], t=[CAMERA["t"]] * 3)
    bad = dict(job, mode="independent", views=[dict(views[0], camera=ortho_pan)] + [
        dict(v, camera=c) for v, c in zip(views[1:], (FRONT, OBLIQUE))])
    (folder / "bad.json").write_text(json.dumps(bad))
    with pytest.raises(JobError, match=r"views\[0\].camera: a camera that moves needs"):
        load_job(folder / "bad.json")
    short = dict(job, views=[dict(views[0], camera=dict(pan, R=pan["R"][:2], t=pan["t"][:2]))]
                 + views[1:])
    (folder / "short.json").write_text(json.dumps(short))
    with pytest.raises(JobError, match="given on 2 frames, its footage has 3"):
        load_job(folder / "short.json")

"""The suite's captures of other namings, its cameras and its jobs from later starting frames,
against what each file says; its scores over several starts."""

import json
import sys
from pathlib import Path

import numpy as np
import pytest

from core import se3
from core.bvh import read_bvh
from core.skeleton import skeleton_from_bvh

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

from captures import CMU_UNIT, Parts, normalized  # noqa: E402
from suite_footage import turned_backdrop, view_rotations  # noqa: E402

# a small body in Bandai Namco's layout: a still joint_Root, Hips carrying the motion, and
# position channels on every joint that repeat its offset (centimetres)
_BN = """HIERARCHY
ROOT joint_Root
{
  OFFSET 0 0 0
  CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
  JOINT Hips
  {
    OFFSET 1 90 -400
    CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
    JOINT UpperLeg_L
    {
      OFFSET 10 0 0
      CHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
      End Site
      {
        OFFSET 40 0 0
      }
    }
  }
}
MOTION
Frames: 2
Frame Time: 0.0333333
0 0 0 0 0 0 1 90 -400 0 0 0 10 0 0 0 0 0
0 0 0 0 0 0 3 91 -395 10 20 30 10 0 0 -30 15 45
"""


def test_a_bandai_namco_capture_becomes_one_moving_root_in_metres(tmp_path):
    path = tmp_path / "bn.bvh"
    path.write_text(_BN)
    raw = read_bvh(path)
    out = normalized(path)
    assert out.names == ["Hips", "UpperLeg_L"] and len(out.motion) == 2
    assert out.joints[1].channels == ["Zrotation", "Yrotation", "Xrotation"]
    R_raw, _ = raw.poses()
    R, root = out.poses()
    np.testing.assert_allclose(root, [[0.01, 0.90, -4.00], [0.03, 0.91, -3.95]])
    np.testing.assert_allclose(R, R_raw[:, 1:], atol=1e-9)
    # the leg's end, worked out by hand from the file: Hips' position, its rotation applied
    # to the leg's offset, the leg's rotation to its end site
    sk = skeleton_from_bvh(out)
    end = sk.joint_frames(R[1], root[1])[1]
    tip = end[:3, :3] @ sk.end_sites[1][0] + end[:3, 3]
    expect = (np.array([3, 91, -395]) + R_raw[1, 1] @ (np.array([10, 0, 0])
                                                       + R_raw[1, 2] @ [40, 0, 0])) / 100
    np.testing.assert_allclose(tip, expect, atol=1e-9)


def test_a_motionbuilder_capture_is_read_in_metres():
    out = normalized(ROOT / "bench" / "data" / "cmu05_01_walk.bvh")
    raw = read_bvh(ROOT / "bench" / "data" / "cmu05_01_walk.bvh")
    assert len(out.motion) == len(raw.motion) == 241
    np.testing.assert_allclose(out.poses()[1], raw.poses()[1] * CMU_UNIT, atol=1e-9)
    height = skeleton_from_bvh(out).height()
    assert 1.4 < height < 2.0, height  # a person, in metres


def test_each_hinge_is_about_the_axis_its_joint_turns_about_most():
    """Knee turns about a known axis by 0..90 degrees with a little wobble: the hinge found
    is that axis, signed so that the bend is positive."""
    out = normalized(ROOT / "bench" / "data" / "cmu05_01_walk.bvh")
    sk = skeleton_from_bvh(out)
    parts = Parts.of(sk.names)
    rng = np.random.default_rng(3)
    axis = np.array([0.9, -0.3, 0.2]) / np.linalg.norm([0.9, -0.3, 0.2])
    R = np.tile(np.eye(3), (40, sk.n_joints, 1, 1))
    knee = sk.index(parts.roles["shank.L"])
    for f, a in enumerate(np.radians(np.linspace(0, 90, 40))):
        R[f, knee] = se3.exp_so3(-axis * a + rng.normal(0, 0.01, 3))
    joints = parts.tracked_joints(sk, R, lower_back=False)
    got = np.array(joints[parts.roles["shank.L"]]["axis"])
    assert got @ -axis > 0.999
    assert joints[parts.roles["thigh.L"]] == "ball"
    assert parts.roles["lower_back"] not in joints


@pytest.mark.parametrize("yaw", [0.0, 37.0, 200.0])
def test_views_look_across_the_body_at_its_front_and_between(yaw):
    lateral = se3.exp_so3([0, np.radians(yaw), 0]) @ [1.0, 0, 0]
    rots = view_rotations(lateral)
    forward = np.cross(lateral, [0, 1, 0])
    for R in rots.values():
        np.testing.assert_allclose(R @ R.T, np.eye(3), atol=1e-12)
        assert np.linalg.det(R) == pytest.approx(1.0)
        assert R[1] @ [0, 1, 0] == pytest.approx(-1.0)  # image y down is world down
    assert rots["lateral"][2] @ lateral == pytest.approx(1.0)
    assert rots["endon"][2] @ forward == pytest.approx(-1.0)  # it walks toward the camera
    assert rots["oblique60"][2] @ lateral == pytest.approx(0.5)


def test_a_close_lens_shows_the_stage_centre_as_large_and_a_pan_keeps_the_root_centred(
        tmp_path):
    """The perspective looks' cameras: each pinhole shows the stage's centre where and as
    large as its orthographic twin does; the panning lateral camera turns with the root,
    keeping it on the image's middle column while its centre stays put."""
    from suite import CLIPS
    from suite_footage import HEIGHT, LOOKS, PIXELS_PER_METRE, WIDTH, look_cameras, stage

    from core.job import parse_camera

    clip_dir = tmp_path / "clip"
    stage(CLIPS[0], clip_dir)
    ortho = look_cameras(clip_dir, LOOKS["muybridge"])
    close = look_cameras(clip_dir, LOOKS["close lens"])
    pan = look_cameras(clip_dir, LOOKS["panning"])
    root = read_bvh(clip_dir / "truth.bvh").poses()[1]
    for v in ortho:
        (o,), _ = parse_camera(ortho[v], v)
        (p,), _ = parse_camera(close[v], v)
        centre = -o.pose.R.T @ o.pose.t
        np.testing.assert_allclose(p.project(centre), [WIDTH / 2 - 0.5, HEIGHT / 2 - 0.5])
        assert p.scale_at(centre) == pytest.approx(PIXELS_PER_METRE)
        np.testing.assert_allclose(p.orientation, o.orientation)
    path, _ = parse_camera(pan["lateral"], "lateral")
    assert len(path) == len(root)
    x = [cam.project(r)[0] for cam, r in zip(path, root)]
    np.testing.assert_allclose(x, WIDTH / 2 - 0.5, atol=1e-6)
    np.testing.assert_allclose([c.centre for c in path], np.repeat(path[:1][0].centre[None],
                                                                    len(path), 0), atol=1e-9)
    turned = np.degrees(se3.angle_between_vectors(path[0].R[2], path[-1].R[2]))
    assert turned > 5  # the walker crosses the view: the camera follows


def test_a_panning_cameras_backdrop_turns_with_it_as_any_still_scene_would():
    """Rendered footage of a camera that turns on its tripod: each backdrop pixel goes where
    the homography K R R0^T K^-1 takes it (a still point at any depth), the wall repeating
    beyond its edges; not turned, the backdrop is as drawn."""
    yy, xx = np.mgrid[:360, :480]
    wave = 128 + 60 * np.sin(2 * np.pi * xx / 60) + 60 * np.cos(2 * np.pi * yy / 45)
    back = np.repeat(wave[..., None], 3, axis=2).astype(np.float32)  # repeats across
    K = np.array([[437.5, 0, 239.5], [0, 437.5, 179.5], [0, 0, 1]])
    R0 = se3.exp_so3([0.0, 0.3, 0.0])
    np.testing.assert_array_equal(turned_backdrop(back, K, R0, R0), back)
    R = se3.exp_so3([0.0, 0.5, 0.0])
    turned = turned_backdrop(back, K, R0, R)
    H = K @ R @ R0.T @ np.linalg.inv(K)
    seen = 0
    for x, y in [(40.0, 30.0), (240.0, 180.0), (460.0, 330.0), (300.0, 20.0)]:
        q = H @ [x, y, 1.0]
        u, v = q[:2] / q[2]
        if 0 <= u < 479 and 0 <= v < 359:  # where the turned camera still shows it
            got = turned[int(round(v)), int(round(u))]
            np.testing.assert_allclose(got, back[int(y), int(x)], atol=8)
            seen += 1
    assert seen >= 2
    assert abs(turned[180, 240] - back[180, 240]).max() > 0  # it did turn


def test_a_run_from_a_later_frame_is_posed_there_and_takes_every_step_th_frame_from_it(
        tmp_path):
    """``write_job``'s starting frame: the capture's pose there, the run's frames from it
    on, and a moving camera's poses on those same frames."""
    from suite import CLIPS, write_job
    from suite_footage import LOOKS, look_cameras, stage

    clip_dir = tmp_path / "clip"
    stage(CLIPS[0], clip_dir)
    n = len(read_bvh(clip_dir / "truth.bvh").poses()[0])
    first = json.loads(write_job(clip_dir, "panning", "1 lateral view 15 fps", {}).read_text())
    later = write_job(clip_dir, "panning", "1 lateral view 15 fps", {}, start=3)
    assert later.name.endswith("__from_3.json")
    job = json.loads(later.read_text())
    assert first["initial"]["frame"] == 0 and job["initial"]["frame"] == 3
    frames = [int(Path(p).stem) for p in job["views"][0]["images"]]
    assert frames == list(range(3, n, 2))
    full = look_cameras(clip_dir, LOOKS["panning"])["lateral"]
    np.testing.assert_allclose(job["views"][0]["camera"]["R"], np.array(full["R"])[3::2])
    np.testing.assert_allclose(job["views"][0]["camera"]["t"], np.array(full["t"])[3::2])


@pytest.mark.parametrize("look", ["muybridge", "panning"])
def test_a_halved_job_shows_every_point_at_half_its_pixel_on_footage_half_the_size(
        tmp_path, look):
    """``halve_job``: the images averaged 2 x 2 into the look's half folder, and each
    camera (orthographic, or a pinhole that turns) putting any world point at (p + 0.5) / 2
    - 0.5 where the original put it at p, so that a pixel's content stays under it."""
    import cv2
    from suite import CLIPS, write_job
    from suite_footage import halve_job, stage

    from core.job import load_job

    clip_dir = tmp_path / "clip"
    stage(CLIPS[0], clip_dir)
    full = write_job(clip_dir, look, "3 views 15 fps", {}, start=1)
    rng = np.random.default_rng(0)
    for view in json.loads(full.read_text())["views"]:
        for image in view["images"]:
            (clip_dir / image).parent.mkdir(parents=True, exist_ok=True)
            cv2.imwrite(str(clip_dir / image), rng.integers(0, 256, (360, 480, 3), np.uint8))
    half = halve_job(full)
    assert half.name == f"{look}_half__3_views_15_fps__from_1.json"
    a, b = load_job(full), load_job(half)
    X = rng.normal([0, 1, 0], 0.5, (20, 3))
    for c in range(3):
        big = cv2.imread(str(clip_dir / json.loads(full.read_text())["views"][c]["images"][1]))
        img = cv2.imread(str(clip_dir / json.loads(half.read_text())["views"][c]["images"][1]))
        assert img.shape == (180, 240, 3)
        np.testing.assert_allclose(img[3, 5], big[6:8, 10:12].reshape(4, 3).mean(0), atol=1)
        cams = [(a.moving[c] or a.cameras)[1 if a.moving[c] else c],
                (b.moving[c] or b.cameras)[1 if b.moving[c] else c]]
        p, q = cams[0].project(X), cams[1].project(X)
        np.testing.assert_allclose(q, (p + 0.5) / 2 - 0.5, atol=1e-9)


def test_a_drifting_job_shows_each_frame_times_its_capture_frames_gain(tmp_path):
    """``drift_job``: each image (named by its capture frame) times ``drift_gain`` of that
    frame, clipped, in the look's drift folder; the cameras and everything else as they
    were."""
    import cv2
    from suite import CLIPS, write_job
    from suite_footage import drift_gain, drift_job, stage

    clip_dir = tmp_path / "clip"
    stage(CLIPS[0], clip_dir)
    full = write_job(clip_dir, "muybridge", "1 lateral view 15 fps", {})
    img = np.full((36, 48, 3), 100, np.uint8)
    img[:, :8] = 250  # clipped where the gain is over 1.02
    for view in json.loads(full.read_text())["views"]:
        for image in view["images"]:
            (clip_dir / image).parent.mkdir(parents=True, exist_ok=True)
            cv2.imwrite(str(clip_dir / image), img)
    drifted = drift_job(full)
    assert drifted.name == "muybridge_drift__1_lateral_view_15_fps.json"
    a, b = json.loads(full.read_text()), json.loads(drifted.read_text())
    assert b["views"][0]["camera"] == a["views"][0]["camera"]
    gains = []
    for image in b["views"][0]["images"]:
        assert image.startswith("muybridge_drift/")
        out = cv2.imread(str(clip_dir / image))
        gain = drift_gain(int(Path(image).stem))
        assert out[0, 20, 0] == round(100 * gain)
        assert out[0, 0, 0] == min(255, round(250 * gain))
        gains.append(gain)
    assert min(gains) < 0.75 and max(gains) > 1.25  # the run sees the whole swing


def test_a_run_with_settings_is_named_apart_from_the_defaults_and_from_other_settings(
        tmp_path):
    """``write_job``'s name: the defaults' plain, each setting's its own (whatever the keys'
    order), the start after it; the job holds the settings it was named by."""
    from suite import CLIPS, write_job
    from suite_footage import stage

    clip_dir = tmp_path / "clip"
    stage(CLIPS[0], clip_dir)
    run = "3 views 15 fps"
    plain = write_job(clip_dir, "muybridge", run, {})
    a = write_job(clip_dir, "muybridge", run, {"max_step": 10, "rim_width": 0.6}, start=2)
    same = write_job(clip_dir, "muybridge", run, {"rim_width": 0.6, "max_step": 10}, start=2)
    other = write_job(clip_dir, "muybridge", run, {"max_step": 25}, start=2)
    assert plain.name == "muybridge__3_views_15_fps.json"
    assert a == same and a.name.endswith("__from_2.json") and "__settings_" in a.name
    assert len({plain, a, other}) == 3
    assert json.loads(a.read_text())["settings"] == {"max_step": 10, "rim_width": 0.6}
    assert json.loads(plain.read_text())["settings"] == {}


def test_a_look_counts_as_rendered_only_whole_and_as_the_look_is_now(tmp_path, monkeypatch):
    """``look_rendered``: every view's last frame there under the look's own stamp; a view
    short of its last frame, or a stamp of the look as it was, asks for it again. Looks
    already rendered start no renderer."""
    import suite
    from suite import CLIPS, render_missing, slug
    from suite_footage import LOOKS, VIEWS, _look_stamp, look_rendered, stage

    monkeypatch.setattr(suite, "CACHE", tmp_path)
    clip_dir = tmp_path / slug(CLIPS[0].name)
    stage(CLIPS[0], clip_dir)
    out = clip_dir / slug("park video")
    n = len(read_bvh(clip_dir / "truth.bvh").motion)
    assert LOOKS["park video"].jpeg
    for v in VIEWS:
        (out / v).mkdir(parents=True)
        (out / v / f"{n - 1:04d}.jpg").write_bytes(b"")
    stamp = _look_stamp(clip_dir, "park video")
    (out / "look.json").write_text(json.dumps(stamp))
    assert look_rendered(clip_dir, "park video", out)

    def no_renderer(*args, **kwargs):
        raise AssertionError("a renderer was started for footage already rendered")

    monkeypatch.setattr(suite, "ProcessPoolExecutor", no_renderer)
    render_missing([CLIPS[0]], ["park video"], 2, 0.0)
    (out / VIEWS[-1] / f"{n - 1:04d}.jpg").unlink()
    assert not look_rendered(clip_dir, "park video", out)
    (out / VIEWS[-1] / f"{n - 1:04d}.jpg").write_bytes(b"")
    (out / "look.json").write_text(json.dumps({**stamp, "look": {**stamp["look"], "blur": 1}}))
    assert not look_rendered(clip_dir, "park video", out)


def test_a_runs_references_are_fitted_once_and_fitted_again_when_their_frames_change(
        tmp_path, monkeypatch):
    """``references``: held still and the best fit are kept in the clip's file under the
    digest of what they follow from; the same run scored again reads them back without
    fitting, and other true frames (a later start) are fitted anew, both kept."""
    import evaluate
    from suite import CLIPS, REFERENCES_FILE, references, write_job
    from suite_footage import stage

    from core.job import load_job

    clip_dir = tmp_path / "clip"
    stage(CLIPS[0], clip_dir)
    run = "1 lateral view 15 fps"
    path = write_job(clip_dir, "muybridge", run, {})
    for image in json.loads(path.read_text())["views"][0]["images"]:
        (clip_dir / image).parent.mkdir(parents=True, exist_ok=True)
        (clip_dir / image).write_bytes(b"")
    job = load_job(path)
    limbs = Parts.of(job.skeleton.names).limbs()
    R, p = read_bvh(clip_dir / "truth.bvh").poses()
    fits = []
    fit = evaluate.best_fit
    monkeypatch.setattr(evaluate, "best_fit", lambda *a: fits.append(1) or fit(*a))
    first = references(clip_dir, job, (R[0:6:2], p[0:6:2]), limbs)
    assert len(fits) == 1 and (clip_dir / REFERENCES_FILE).is_file()
    assert first[1] < first[0]  # the best fit beats the first pose held still
    assert references(clip_dir, job, (R[0:6:2], p[0:6:2]), limbs) == first
    assert len(fits) == 1
    later = references(clip_dir, job, (R[1:7:2], p[1:7:2]), limbs)
    assert len(fits) == 2 and later != first
    assert len(json.loads((clip_dir / REFERENCES_FILE).read_text())) == 2


def test_runs_from_several_starts_are_scored_by_their_mean_and_summed_counts():
    from suite import over_starts

    runs = [{"tracker": t, "still": 30.0 + t, "best": 1.0, "tracked": k, "of": 30,
             "diverged": k < 30, "fps": f, "peak_mb": m, "flags": (1, 2, 3), "heading": h}
            for t, k, f, m, h in ((10.0, 30, 5.0, 100, 2.0), (14.0, 22, 6.0, 120, 9.0),
                                  (12.0, 29, 4.0, 90, 4.0))]
    row = over_starts(runs)
    assert (row["tracker"], row["low"], row["high"]) == (12.0, 10.0, 14.0)
    assert row["still"] == 42.0 and row["best"] == 1.0
    assert (row["tracked"], row["of"], row["stopped"], row["starts"]) == (81, 90, 2, 3)
    assert row["fps"] == 5.0 and row["peak_mb"] == 120 and row["flags"] == (3, 6, 9)
    assert row["heading"] == 5.0
    assert "image_pct" not in row
    runs[0]["image_pct"], runs[1]["image_pct"], runs[2]["image_pct"] = 1.0, 2.0, 6.0
    assert over_starts(runs)["image_pct"] == 3.0


def test_a_results_file_names_the_command_that_wrote_it_without_the_writers_folder():
    """The header of a written results file is the command to run again: the Bandai Namco
    folder (a path on the writer's machine, never stored) shows as FOLDER, and a clip list
    with spaces stays one argument."""
    from suite import command_line

    argv = ["--bandai-namco", "/home/me/data/mocap", "--clips", "BN brisk walk,BN dance",
            "--starts", "3", "--write", "docs/B.md"]
    assert command_line(argv) == ('bench/suite.py --bandai-namco FOLDER --clips '
                                  '"BN brisk walk,BN dance" --starts 3 --write docs/B.md')
    assert command_line(["--bandai-namco=/x/y", "--quick"]) == \
        "bench/suite.py --bandai-namco=FOLDER --quick"
    assert command_line([]) == "bench/suite.py"


def test_a_results_file_says_which_settings_differ_from_the_defaults():
    from suite import settings_phrase

    assert settings_phrase({}) == "the default settings"
    assert settings_phrase({"limb_search": 0, "side_on": False}) == \
        "the default settings but limb_search 0, side_on false"


def test_a_frame_whose_body_turned_out_of_side_on_flags_every_limb_there():
    """The suite's flag counts: a limb counts as flagged by its own flag, or by its frame's
    body having turned past ``OUT_OF_SIDE_ON_DEG`` (the frame is one to check, every limb
    in doubt); and as caught where it is also over ``BAD_LIMB_DEG`` off."""
    from suite import BAD_LIMB_DEG, flag_counts

    from core.side_on import OUT_OF_SIDE_ON_DEG

    sk = skeleton_from_bvh(read_bvh(ROOT / "bench" / "data" / "cmu05_01_walk.bvh"))
    limbs = Parts.of(sk.names).limbs()
    rest = np.tile(np.eye(3), (2, sk.n_joints, 1, 1)), np.zeros((2, 3))
    off = rest[0].copy()  # the left thigh (and the shank with it) turned on frame 1
    off[1, sk.index(limbs[0][1])] = se3.exp_so3(np.radians([0.0, 0.0, BAD_LIMB_DEG + 30]))
    frame = {"frame": 1, "limbs": {name: {"flag": ""} for name in sk.names}, "turned": None}
    rep = {"frames": [{"frame": 0, "limbs": {}}, frame]}
    caught, bad, flagged = flag_counts(rep, sk, (off, rest[1]), rest, limbs)
    assert (caught, flagged) == (0, 0) and bad >= 1
    frame["turned"] = OUT_OF_SIDE_ON_DEG + 1
    assert flag_counts(rep, sk, (off, rest[1]), rest, limbs) == (bad, bad, 8)
    frame["turned"] = OUT_OF_SIDE_ON_DEG - 1
    assert flag_counts(rep, sk, (off, rest[1]), rest, limbs) == (0, bad, 0)

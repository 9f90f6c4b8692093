"""Calibration files read as pinhole cameras: Qualisys against Pose2Sim's own conversion,
OpenCV's FileStorage and Pose2Sim's TOML against the cameras they were written from."""

import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from core import se3
from core.calibration import CalibrationError, read_calibration
from core.job import JobError, parse_camera

DATA = Path(__file__).resolve().parents[2] / "bench" / "data" / "pose2sim"
ROOT = Path(__file__).resolve().parents[2]


def _cameras(n=2):
    """Known cameras: (name, K, rotation vector, t, dist, (width, height))."""
    rng = np.random.default_rng(4)
    return [(f"cam{i}", np.array([[1500.0 + 10 * i, 0, 540], [0, 1490, 960], [0, 0, 1]]),
             rng.normal(0, 1, 3), rng.normal(0, 1, 3) + [0, 0, 3],
             np.array([-0.05, 0.1, 0.001, -0.002, 0.0]), (1080, 1920)) for i in range(n)]


def _same(cam, known):
    name, K, rvec, t, dist, size = known
    assert cam.name == name and cam.size == size
    np.testing.assert_allclose(cam.camera.K, K)
    np.testing.assert_allclose(cam.camera.R, se3.exp_so3(rvec), atol=1e-9)
    np.testing.assert_allclose(cam.camera.t, t)
    n = len(cam.dist)
    np.testing.assert_allclose(cam.dist, dist[:n])


def test_qualisys_reads_as_pose2sims_own_conversion():
    cams = read_calibration(DATA / "Calib.qca.txt")
    ref = json.loads((DATA / "calibration.json").read_text())["cameras"]
    assert [c.name for c in cams] == [r["name"] for r in ref]
    for c, r in zip(cams, ref):
        for key, got in (("K", c.camera.K), ("R", c.camera.R), ("t", c.camera.t),
                         ("dist", c.dist)):
            np.testing.assert_allclose(got, r[key], atol=1e-9, err_msg=f"{c.name} {key}")
        assert list(c.size) == r["size"]
        np.testing.assert_allclose(c.camera.centre, r["centre_world"], atol=1e-9)
    mm = read_calibration(DATA / "Calib.qca.txt", scale=1000.0)  # a skeleton in millimetres
    np.testing.assert_allclose(mm[0].camera.t, 1000 * cams[0].camera.t)


@pytest.mark.parametrize("ext", ["yml", "json", "xml"])
def test_opencv_filestorage_one_node_per_camera(tmp_path, ext):
    known = _cameras()
    path = tmp_path / f"calib.{ext}"
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    for name, K, rvec, t, dist, (w, h) in known:
        fs.startWriteStruct(name, cv2.FileNode_MAP)
        fs.write("camera_matrix", K)
        fs.write("distortion_coefficients", dist.reshape(1, -1))
        fs.write("rvec", rvec.reshape(3, 1))
        fs.write("tvec", t.reshape(3, 1))
        fs.write("image_width", w)
        fs.write("image_height", h)
        fs.endWriteStruct()
    fs.release()
    cams = read_calibration(path)
    assert len(cams) == 2
    for c, k in zip(cams, known):
        _same(c, k)


def test_opencv_single_camera_with_a_rotation_matrix(tmp_path):
    name, K, rvec, t, dist, _ = _cameras(1)[0]
    path = tmp_path / "cam0.yaml"
    fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_WRITE)
    fs.write("K", K)
    fs.write("D", dist)
    fs.write("R", se3.exp_so3(rvec))
    fs.write("T", t)
    fs.release()
    (cam,) = read_calibration(path)
    assert cam.name == "cam0" and cam.size is None
    np.testing.assert_allclose(cam.camera.R, se3.exp_so3(rvec), atol=1e-9)
    np.testing.assert_allclose(cam.camera.t, t)
    fs = cv2.FileStorage(str(tmp_path / "nopose.yml"), cv2.FILE_STORAGE_WRITE)
    fs.write("camera_matrix", K)
    fs.release()
    with pytest.raises(CalibrationError, match=r"nopose.yml: camera 'nopose' has no pose"):
        read_calibration(tmp_path / "nopose.yml")


def test_pose2sim_toml(tmp_path):
    known = _cameras()
    lines = []
    for name, K, rvec, t, dist, size in known:
        lines += [f"[{name}]", f'name = "{name}"', f"size = {list(size)}",
                  f"matrix = {K.tolist()}", f"distortions = {dist[:4].tolist()}",
                  f"rotation = {rvec.tolist()}", f"translation = {t.tolist()}",
                  "fisheye = false", ""]
    lines += ["[metadata]", "adjusted = false", "error = 0.0"]
    (tmp_path / "Calib.toml").write_text("\n".join(lines))
    cams = read_calibration(tmp_path / "Calib.toml")
    assert len(cams) == 2
    for c, k in zip(cams, known):
        _same(c, k)


def test_the_command_line_writes_cameras_a_job_takes_by_name(tmp_path):
    out = tmp_path / "cameras.json"
    proc = subprocess.run([sys.executable, "-m", "core", "cameras", DATA / "Calib.qca.txt",
                           "--out", out], cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    assert "4 cameras" in proc.stderr and "cam03: 1088x1920" in proc.stderr
    direct = read_calibration(DATA / "Calib.qca.txt")
    (cam,), dist = parse_camera({"calibration": "cameras.json", "name": "cam03"}, "cam", tmp_path)
    np.testing.assert_allclose(cam.K, direct[2].camera.K)
    np.testing.assert_allclose(cam.R, direct[2].camera.R)
    np.testing.assert_allclose(dist, direct[2].dist)
    (cam,), _ = parse_camera({"calibration": str(DATA / "Calib.qca.txt"), "name": "cam01",
                           "scale": 100}, "cam", tmp_path)
    np.testing.assert_allclose(cam.t, 100 * direct[0].camera.t)
    with pytest.raises(JobError, match=r"cam.name: 'cameras.json' holds 4 cameras \(cam01, "):
        parse_camera({"calibration": "cameras.json"}, "cam", tmp_path)
    with pytest.raises(JobError, match="has no camera 'cam9'"):
        parse_camera({"calibration": "cameras.json", "name": "cam9"}, "cam", tmp_path)
    bad = subprocess.run([sys.executable, "-m", "core", "cameras", tmp_path / "x.txt",
                          "--out", out], cwd=ROOT, capture_output=True, text=True)
    assert bad.returncode == 2 and "no such calibration file" in bad.stderr

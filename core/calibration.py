"""Calibration files read as pinhole cameras: OpenCV's FileStorage (YAML or JSON), Pose2Sim's
TOML, Qualisys' ``.qca.txt``, and this project's own ``cameras.json`` (what
``python -m core cameras`` writes).

Every camera comes out in OpenCV's convention (``core.camera.Pinhole``): x_cam = R X + t with
X in metres (times ``scale``), pixel = (K x_cam / z)[:2], ``dist`` = OpenCV's [k1, k2, p1,
p2, k3], ``size`` = [width, height] of the footage it was calibrated on.
"""

from __future__ import annotations

import json
import tomllib
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from . import se3
from .camera import Pinhole, intrinsics_problem
from .errors import InputError


class CalibrationError(InputError):
    """A calibration file that cannot be read; the message names the file and the field."""


@dataclass
class CalibratedCamera:
    name: str
    camera: Pinhole
    dist: np.ndarray | None  # OpenCV's distortion coefficients, None for none
    size: tuple[int, int] | None  # (width, height) in pixels, when the file says

    def as_json(self) -> dict:
        """This camera as a job's ``camera`` field (with its name and size beside)."""
        out = {"name": self.name, "model": "pinhole", "K": self.camera.K.tolist(),
               "R": self.camera.R.tolist(), "t": self.camera.t.tolist()}
        if self.dist is not None:
            out["dist"] = self.dist.tolist()
        if self.size is not None:
            out["size"] = list(self.size)
        return out


def read_calibration(path: str | Path, scale: float = 1.0) -> list[CalibratedCamera]:
    """Every camera of a calibration file, its world scaled by ``scale`` (world units per
    metre, for a skeleton in other units), in the file's order."""
    path = Path(path)
    if not path.is_file():
        raise CalibrationError(f"{path}: no such calibration file")
    name = path.name.lower()
    if name.endswith(".qca.txt") or name.endswith(".qca"):
        cams = _qualisys(path)
    elif name.endswith(".toml"):
        cams = _pose2sim(path)
    elif name.endswith((".yml", ".yaml", ".json", ".xml")):
        ours = _ours(path) if name.endswith(".json") else None
        cams = _opencv(path) if ours is None else ours
    else:
        raise CalibrationError(f"{path}: not a calibration format read here (OpenCV's .yml, "
                               ".yaml, .xml or .json; Pose2Sim's .toml; Qualisys' .qca.txt)")
    if not cams:
        raise CalibrationError(f"{path}: holds no camera")
    for c in cams:
        c.camera.t = c.camera.t * scale
    return cams


def _checked(path: Path, name: str, K, R, t, dist=None, size=None) -> CalibratedCamera:
    where = f"{path.name}: camera '{name}'"
    K, R, t = (np.asarray(x, dtype=float) for x in (K, R, t))
    problem = intrinsics_problem(K)
    if problem:
        raise CalibrationError(f"{where}: K: {problem}")
    if not se3.is_rotation(R):
        raise CalibrationError(f"{where}: its rotation is not a 3x3 rotation matrix")
    if t.size != 3:
        raise CalibrationError(f"{where}: expected 3 translations, got {t.size}")
    d = None if dist is None else np.asarray(dist, dtype=float).ravel()
    if d is not None and not np.any(d):
        d = None
    return CalibratedCamera(name, Pinhole(K, R, t.ravel()), d,
                            None if size is None else (int(size[0]), int(size[1])))


def _qualisys(path: Path) -> list[CalibratedCamera]:
    """Qualisys Track Manager's export: per camera a ``transform`` (the camera's rotation
    rows and centre in millimetres, its y and z axes opposite OpenCV's) and ``intrinsic``
    (sub-pixel units, 64 to a pixel), distortion k1, k2, k3, p1, p2."""
    try:
        root = ET.parse(path).getroot()
    except ET.ParseError as e:
        raise CalibrationError(f"{path}: not a Qualisys calibration ({e})") from None
    out = []
    for i, cam in enumerate(root.iter("camera")):
        name = cam.get("serial") or f"camera {i + 1}"
        tr, intr, fov = cam.find("transform"), cam.find("intrinsic"), cam.find("fov_video")
        if tr is None or intr is None:
            raise CalibrationError(f"{path.name}: camera '{name}' lacks its transform or "
                                   "intrinsic")
        if int(float(cam.get("viewrotation", "0"))):
            raise CalibrationError(f"{path.name}: camera '{name}' is rotated in its view "
                                   "(viewrotation): not read here; export it unrotated")
        try:
            Rq = np.array([[float(tr.get(f"r{a}{b}")) for b in "123"] for a in "123"])
            centre = np.array([float(tr.get(k)) for k in "xyz"]) / 1000.0
            g = {k: float(v) for k, v in intr.attrib.items()}
            left, top = (0.0, 0.0) if fov is None else (float(fov.get("left")),
                                                          float(fov.get("top")))
            size = None if fov is None else (int(fov.get("right")) - int(left) + 1,
                                             int(fov.get("bottom")) - int(top) + 1)
            K = [[g["focalLengthU"] / 64, g.get("skew", 0.0), g["centerPointU"] / 64 - left],
                 [0, g["focalLengthV"] / 64, g["centerPointV"] / 64 - top], [0, 0, 1]]
            dist = [g["radialDistortion1"], g["radialDistortion2"], g["tangentalDistortion1"],
                    g["tangentalDistortion2"], g["radialDistortion3"]]
        except (TypeError, KeyError) as e:
            raise CalibrationError(f"{path.name}: camera '{name}' lacks a field ({e})") from None
        R = np.diag([1.0, -1.0, -1.0]) @ Rq
        out.append(_checked(path, name, K, R, -R @ centre, dist, size))
    return out


def _pose2sim(path: Path) -> list[CalibratedCamera]:
    """Pose2Sim's TOML: one table per camera with ``matrix`` (K), ``distortions`` [k1, k2,
    p1, p2], ``rotation`` (a rotation vector) and ``translation`` (metres), world to
    camera."""
    try:
        data = tomllib.loads(path.read_text())
    except (tomllib.TOMLDecodeError, UnicodeDecodeError) as e:
        raise CalibrationError(f"{path}: not a TOML file ({e})") from None
    out = []
    for key, cam in data.items():
        if not isinstance(cam, dict) or "matrix" not in cam:
            continue  # e.g. the [metadata] table
        if cam.get("fisheye"):
            raise CalibrationError(f"{path.name}: camera '{key}' is a fisheye: its lens "
                                   "model is not read here")
        try:
            R = cv2.Rodrigues(np.asarray(cam["rotation"], dtype=float))[0]
            out.append(_checked(path, str(cam.get("name", key)), cam["matrix"], R,
                                cam["translation"], cam.get("distortions"), cam.get("size")))
        except KeyError as e:
            raise CalibrationError(f"{path.name}: camera '{key}' lacks {e}") from None
    return out


_OPENCV_KEYS = {"K": ("camera_matrix", "cameraMatrix", "K", "intrinsic", "intrinsics"),
                "dist": ("distortion_coefficients", "dist_coeffs", "distCoeffs", "D", "dist"),
                "R": ("R", "rotation_matrix"), "rvec": ("rvec", "rotation", "r"),
                "t": ("T", "t", "tvec", "translation"),
                "width": ("image_width", "width"), "height": ("image_height", "height")}


def _opencv(path: Path) -> list[CalibratedCamera]:
    """OpenCV's FileStorage (YAML, XML or JSON): one camera at the top level, or one node
    per camera, each with a camera matrix, distortion, R (or a rotation vector) and T."""
    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
    except cv2.error as e:
        raise CalibrationError(f"{path}: OpenCV cannot read it ({e.err})") from None
    try:
        root = fs.root()
        nodes = [(path.stem, root)] if _opencv_field(root, "K") is not None else [
            (k, root.getNode(k)) for k in root.keys()
            if root.getNode(k).isMap() and _opencv_field(root.getNode(k), "K") is not None]
        out = []
        for name, node in nodes:
            K, dist = _opencv_field(node, "K"), _opencv_field(node, "dist")
            R, rvec, t = (_opencv_field(node, k) for k in ("R", "rvec", "t"))
            if R is None and rvec is not None:
                R = cv2.Rodrigues(rvec.reshape(3, 1))[0]
            if R is None or t is None:
                raise CalibrationError(f"{path.name}: camera '{name}' has no pose (R or rvec, "
                                       "and T): the tracker needs where each camera stands")
            w, h = (_opencv_field(node, k) for k in ("width", "height"))
            size = None if w is None or h is None else (int(w.item()), int(h.item()))
            out.append(_checked(path, name, K, R, t, dist, size))
        return out
    finally:
        fs.release()


def _opencv_field(node, key: str) -> np.ndarray | None:
    """A node's field by any of its usual names (``_OPENCV_KEYS``), as an array (None when
    absent)."""
    for n in _OPENCV_KEYS[key]:
        sub = node.getNode(n)
        if sub.empty():
            continue
        if sub.isReal() or sub.isInt():
            return np.array([sub.real()])
        mat = sub.mat()
        if mat is not None:
            return np.asarray(mat, dtype=float)
        if sub.isSeq():
            return np.array([sub.at(i).real() for i in range(sub.size())])
    return None


def _ours(path: Path) -> list[CalibratedCamera] | None:
    """A ``cameras.json``'s cameras: ``{"cameras": [{"name", "K", "R", "t", "dist"?,
    "size"?}]}``; None for a JSON file of another layout (OpenCV's)."""
    try:
        data = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError):
        return None
    if not isinstance(data, dict) or not isinstance(data.get("cameras"), list):
        return None
    out = []
    for i, cam in enumerate(data["cameras"]):
        name = str(cam.get("name", f"camera {i + 1}"))
        try:
            out.append(_checked(path, name, cam["K"], cam["R"], cam["t"], cam.get("dist"),
                                cam.get("size")))
        except KeyError as e:
            raise CalibrationError(f"{path.name}: camera '{name}' lacks {e}") from None
    return out


def write_cameras(cameras: list[CalibratedCamera], path: str | Path) -> None:
    """``cameras.json``: every camera as a job's ``camera`` field, in order."""
    Path(path).write_text(json.dumps(
        {"convention": "x_cam = R X + t (z forward, x right, y down), pixel = (K x_cam / z)"
                       "[:2] before OpenCV's distortion dist",
         "cameras": [c.as_json() for c in cameras]}, indent=1) + "\n")

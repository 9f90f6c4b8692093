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

from .camera import Pinhole
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
    elif name.endswith(".json") and _is_ours(path):
        cams = _ours(path)
    elif name.endswith((".yml", ".yaml", ".json", ".xml")):
        cams = _opencv(path)
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
    if K.shape != (3, 3) or R.shape != (3, 3) or t.size != 3:
        raise CalibrationError(f"{where}: expected a 3x3 K, a 3x3 rotation and 3 translations")
    if not (K[0, 0] > 0 and K[1, 1] > 0):
        raise CalibrationError(f"{where}: focal lengths must be > 0, got {K[0, 0]}, {K[1, 1]}")
    if not np.allclose(R @ R.T, np.eye(3), atol=1e-4) or np.linalg.det(R) < 0:
        raise CalibrationError(f"{where}: its rotation is not a rotation matrix")
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
                "t": ("T", "t", "tvec", "translation")}


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
            w, h = (_opencv_field(node, k, ("image_width", "width")) for k in ("w", "h"))
            size = None if w is None or h is None else (int(w.item()), int(h.item()))
            out.append(_checked(path, name, K, R, t, dist, size))
        return out
    finally:
        fs.release()


def _opencv_field(node, key: str, names=None) -> np.ndarray | None:
    """A node's field by any of its usual names, as an array (None when absent)."""
    if key in ("w", "h"):
        names = ("image_width", "width") if key == "w" else ("image_height", "height")
    for n in names or _OPENCV_KEYS[key]:
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


def _is_ours(path: Path) -> bool:
    try:
        data = json.loads(path.read_text())
    except (json.JSONDecodeError, UnicodeDecodeError):
        return False
    return isinstance(data, dict) and isinstance(data.get("cameras"), list)


def _ours(path: Path) -> list[CalibratedCamera]:
    """A ``cameras.json``: ``{"cameras": [{"name", "K", "R", "t", "dist"?, "size"?}]}``."""
    out = []
    for i, cam in enumerate(json.loads(path.read_text())["cameras"]):
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

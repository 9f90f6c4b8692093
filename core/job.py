"""The tracking job: a JSON file naming the skeleton, the initial pose, the views and the mode,
read and checked here, each error naming the field and what it expects.

The format is a public contract, described field by field in ``docs/JOB_FORMAT.md``
(``python -m core track JOB.json``; ``fit`` adds ``clicks``): fields may be added, never
removed or changed in meaning. Relative paths are relative to the job file's folder.
"""

from __future__ import annotations

import dataclasses
import glob
import json
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from . import se3
from .bvh import BvhError, BvhFile, read_bvh
from .calibration import CalibrationError, read_calibration
from .camera import Camera, Pinhole, View, intrinsics_problem
from .errors import InputError
from .image import ImageError, load_image
from .init_fit import FitError, clicked_point
from .lens import Undistorted, undistort_points
from .pose import CALIBRATED, INDEPENDENT, BodyPose, pose_from_bvh
from .settings import TrackerSettings
from .skeleton import BALL, FIXED, HINGE, Skeleton, skeleton_from_bvh
from .video import VideoFrames, is_video


class JobError(InputError):
    """A job that cannot run; the message names the field and what is expected."""


@dataclass
class Job:
    skeleton: Skeleton
    bvh: BvhFile  # the skeleton's BVH: hierarchy and channel layout of the output
    initial: BodyPose
    images: list  # per view, per frame: image paths, or a movie's VideoFrames
    cameras: list[Camera]  # the cameras as given (the initial pose's views start as copies)
    mode: str
    settings: TrackerSettings
    frame_time: float
    corrections: dict[int, BodyPose] = dataclasses.field(default_factory=dict)  # by image
    moving: list = dataclasses.field(default_factory=list)  # per view: its camera per frame
    # where it moves, else None (``Tracker``'s ``moving``)
    clean_plates: list = dataclasses.field(default_factory=list)  # per view: an image of
    # its scene without the body, or None (``Tracker``'s ``clean_plates``)


def _field(d: dict, key: str, where: str, kind=None):
    if not isinstance(d, dict) or key not in d:
        raise JobError(f"{where}: missing field '{key}'")
    v = d[key]
    if kind is not None and not isinstance(v, kind):
        names = kind.__name__ if isinstance(kind, type) else "/".join(k.__name__ for k in kind)
        raise JobError(f"{where}.{key}: expected {names}, got {type(v).__name__}")
    return v


def _vector(v, n: int, where: str) -> np.ndarray:
    try:
        a = np.asarray(v, dtype=float)
    except (TypeError, ValueError):
        raise JobError(f"{where}: expected {n} numbers, got {v!r}") from None
    if a.shape != (n,) or not np.all(np.isfinite(a)):
        raise JobError(f"{where}: expected {n} finite numbers, got {v!r}")
    return a


def _poses(d: dict, where: str) -> tuple[np.ndarray, np.ndarray]:
    """A camera's ``R`` and ``t``: one of each for a camera that stands still, or one per
    frame for one that moves (F, 3, 3) and (F, 3); a still camera's F is 1."""
    try:
        R = np.asarray(_field(d, "R", where), dtype=float)
    except (TypeError, ValueError):
        R = np.zeros(0)
    if R.shape == (3, 3):
        R = R[None]
    if R.ndim != 3 or R.shape[1:] != (3, 3):
        raise JobError(f"{where}.R: expected a 3x3 rotation matrix (list of 3 rows), or one "
                       "per frame for a camera that moves")
    bad = [i for i, r in enumerate(R) if not se3.is_rotation(r)]
    if bad:
        at = f" (frame {bad[0]})" if len(R) > 1 else ""
        raise JobError(f"{where}.R: expected a 3x3 rotation matrix (orthonormal, det +1){at}")
    try:
        t = np.asarray(_field(d, "t", where), dtype=float)
    except (TypeError, ValueError):
        t = np.zeros(0)
    t = t[None] if t.shape == (3,) else t
    if t.ndim != 2 or t.shape[1] != 3 or not np.all(np.isfinite(t)):
        raise JobError(f"{where}.t: expected 3 finite numbers, or 3 per frame for a camera "
                       f"that moves, got {d['t']!r}")
    if len(R) != len(t) and 1 not in (len(R), len(t)):
        raise JobError(f"{where}: R is given on {len(R)} frames, t on {len(t)}")
    n = max(len(R), len(t))
    return np.broadcast_to(R, (n, 3, 3)), np.broadcast_to(t, (n, 3))


def _intrinsics(d: dict, where: str) -> np.ndarray:
    try:
        K = np.asarray(_field(d, "K", where), dtype=float)
    except (TypeError, ValueError):
        K = np.zeros(0)
    problem = intrinsics_problem(K)
    if problem:
        raise JobError(f"{where}.K: {problem}")
    return K


def _calibrated(d: dict, base: Path, where: str) -> tuple[Camera, np.ndarray | None]:
    """The camera named ``name`` in the calibration file ``calibration`` (the only one when
    it holds one), its world scaled by ``scale``."""
    file = _field(d, "calibration", where, str)
    scale = d.get("scale", 1.0)
    if not isinstance(scale, (int, float)) or not scale > 0:
        raise JobError(f"{where}.scale: expected world units per metre > 0, got {scale!r}")
    try:
        cams = read_calibration(base / file, scale)
    except CalibrationError as e:
        raise JobError(f"{where}.calibration: {e}") from None
    names = [c.name for c in cams]
    if "name" not in d and len(cams) > 1:
        raise JobError(f"{where}.name: '{file}' holds {len(cams)} cameras ({', '.join(names)})"
                       ": name this view's")
    name = d.get("name", names[0])
    if name not in names:
        raise JobError(f"{where}.name: '{file}' has no camera '{name}' (it has "
                       f"{', '.join(names)})")
    cam = cams[names.index(name)]
    return cam.camera, cam.dist


def parse_camera(d, where: str, base: Path = Path(".")
                 ) -> tuple[list[Camera], np.ndarray | None]:
    """A view's camera, one per frame where it moves (else one), and its lens distortion
    (OpenCV's k1, k2, p1, p2[, k3[, ...]]; None: none): ``scaled_orthographic`` (R, t,
    scale, center), ``pinhole`` (K, R, t, and optionally dist), or a camera of a calibration
    file (``calibration``, relative to ``base``, and ``name``)."""
    if not isinstance(d, dict):
        raise JobError(f"{where}: expected an object with model and the model's fields")
    if "calibration" in d:
        cam, dist = _calibrated(d, base, where)
        return [cam], dist
    model = _field(d, "model", where, str)
    if model == "pinhole":
        K, (Rs, ts) = _intrinsics(d, where), _poses(d, where)
        dist = None
        if d.get("dist") is not None:
            try:
                dist = np.asarray(d["dist"], dtype=float)
            except (TypeError, ValueError):
                dist = np.zeros(0)
            if dist.ndim != 1 or len(dist) not in (4, 5, 8, 12, 14) or not np.all(
                    np.isfinite(dist)):
                raise JobError(f"{where}.dist: expected OpenCV's distortion coefficients "
                               f"[k1, k2, p1, p2, k3] (4, 5, 8, 12 or 14 numbers), got "
                               f"{d['dist']!r}")
            if not np.any(dist):
                dist = None
        return [Pinhole(K, R.copy(), t.copy()) for R, t in zip(Rs, ts)], dist
    if model != "scaled_orthographic":
        raise JobError(f"{where}.model: expected 'pinhole' or 'scaled_orthographic', got "
                       f"'{model}'")
    Rs, ts = _poses(d, where)
    scale = _field(d, "scale", where, (int, float))
    if not scale > 0:
        raise JobError(f"{where}.scale: expected pixels per world unit > 0, got {scale}")
    center = _vector(_field(d, "center", where), 2, f"{where}.center")
    return [View(se3.Similarity(scale, R.copy(), t.copy()), center.copy())
            for R, t in zip(Rs, ts)], None


def _images(spec, base: Path, where: str):
    if isinstance(spec, str) and is_video(spec):
        path = base / spec
        if not path.is_file():
            raise JobError(f"{where}: the movie '{spec}' is not found (relative to {base})")
        try:
            return VideoFrames(path)
        except ImageError as e:
            raise JobError(f"{where}: {e}") from None
    if isinstance(spec, str):
        paths = sorted(glob.glob(str(base / spec)))
        if not paths:
            raise JobError(f"{where}: the pattern '{spec}' matches no file (relative to {base})")
        return paths
    if isinstance(spec, list) and all(isinstance(p, str) for p in spec):
        paths = [str(base / p) for p in spec]
        missing = [p for p in paths if not Path(p).is_file()]
        if missing:
            raise JobError(f"{where}: {len(missing)} image(s) not found, first: {missing[0]}")
        return paths
    raise JobError(f"{where}: expected a movie file, a glob pattern or a list of image paths")


def _clean_plate(spec, base: Path, where: str, cam: Camera, dist):
    """A view's ``backdrop``: an image of its scene without the body (undistorted like its
    footage), or None when not given."""
    if spec is None:
        return None
    path = base / spec if isinstance(spec, str) else None
    if path is None or not path.is_file():
        raise JobError(f"{where}: expected the path of an image of the scene without the "
                       f"body (relative to {base}), got {spec!r}")
    try:
        img = load_image(path)
    except ImageError as e:
        raise JobError(f"{where}: {e}") from None
    return str(path) if dist is None else Undistorted([img], cam.K, dist)[0]


def _reaches_out(sk: Skeleton, j: int) -> bool:
    """Whether anything joint j turns (a joint or end site below it) lies away from it."""
    rest = sk.rest_positions
    below = np.flatnonzero(sk.moved_by()[:, j])
    tips = [rest[k] + e for k in below for e in sk.end_sites[k]]
    points = np.concatenate([rest[below], np.reshape(tips, (-1, 3))])
    return bool(np.any(np.linalg.norm(points - rest[j], axis=1) > 1e-9))


def _apply_joints(sk: Skeleton, spec, where: str) -> None:
    if not isinstance(spec, dict) or not spec:
        raise JobError(f"{where}: expected an object naming the tracked joints")
    for name, js in spec.items():
        if name not in sk.names:
            raise JobError(
                f"{where}.{name}: no such joint in the BVH; it has {', '.join(sk.names)}")
        j = sk.names.index(name)
        kind = js if isinstance(js, str) else js.get("kind") if isinstance(js, dict) else None
        if kind not in (BALL, HINGE, FIXED):
            raise JobError(f"{where}.{name}: expected 'ball', 'fixed' or {{\"kind\": \"hinge\","
                           f" \"axis\": [x, y, z]}}, got {js!r}")
        if j == 0 and kind != FIXED:
            raise JobError(f"{where}.{name}: the root moves with the view poses; track its"
                           " children instead")
        if kind != FIXED and not _reaches_out(sk, j):
            raise JobError(f"{where}.{name}: every bone below this joint has zero length in "
                           "the BVH, so no pixel can show it turn: track another joint, or "
                           "give the BVH's offsets their lengths")
        sk.kinds[j] = kind
        if kind == HINGE:
            if not isinstance(js, dict) or "axis" not in js:
                raise JobError(
                    f"{where}.{name}: a hinge needs an 'axis' in the joint's local frame")
            a = _vector(js["axis"], 3, f"{where}.{name}.axis")
            if np.linalg.norm(a) < 1e-9:
                raise JobError(f"{where}.{name}.axis: the axis must not be zero")
            sk.axes[j] = a / np.linalg.norm(a)
            if "limits" in js:
                lo, hi = _vector(js["limits"], 2, f"{where}.{name}.limits")
                if not lo < hi:
                    raise JobError(f"{where}.{name}.limits: expected [lowest, highest] angle in "
                                   f"degrees, lowest first, got {js['limits']!r}")
                sk.limits[j] = np.radians([lo, hi])


def _apply_blobs(sk: Skeleton, spec, where: str) -> None:
    if not isinstance(spec, dict):
        raise JobError(f"{where}: expected an object of joint name -> blob settings")
    for name, bs in spec.items():
        if name not in sk.names:
            raise JobError(f"{where}.{name}: no such joint in the BVH")
        j = sk.names.index(name)
        if bs is False:
            sk.blobs = [b for b in sk.blobs if b.joint != j]
            continue
        if not isinstance(bs, dict) or not ({"radius", "radii", "length"} & bs.keys()):
            raise JobError(f"{where}.{name}: expected {{\"radius\": r}}, {{\"radii\": [r1, r2]}},"
                           " an optional \"length\", or false")
        r = _vector(bs["radii"], 2, f"{where}.{name}.radii") if "radii" in bs else np.full(
            2, float(bs["radius"])) if "radius" in bs else None
        length = bs.get("length")
        if r is not None and np.any(r <= 0) or length is not None and not (
                isinstance(length, (int, float)) and length > 0):
            raise JobError(f"{where}.{name}: radii and length must be positive numbers")
        for b in sk.blobs:
            if b.joint == j:
                if r is not None:
                    b.radii[1:] = r
                if length is not None:
                    b.radii[0] = length / 2


def _settings(spec, where: str) -> TrackerSettings:
    if spec is None:
        return TrackerSettings()
    if not isinstance(spec, dict):
        raise JobError(f"{where}: expected an object of tracker settings")
    fields = {f.name: f for f in dataclasses.fields(TrackerSettings)}
    kw = {}
    for k, v in spec.items():
        if k not in fields:
            raise JobError(f"{where}.{k}: unknown setting; known: {', '.join(fields)}")
        default = fields[k].default
        if isinstance(default, bool) and not isinstance(v, bool) or not isinstance(
            default, bool) and (isinstance(v, bool) or not isinstance(v, (int, float))):
            raise JobError(f"{where}.{k}: expected a {type(default).__name__}, got {v!r}")
        kw[k] = type(default)(v)
    try:
        return TrackerSettings(**kw)
    except ValueError as e:
        raise JobError(f"{where}: {e}") from None


def _read_json(path: Path, what: str) -> dict:
    try:
        d = json.loads(path.read_text())
    except OSError as e:
        raise JobError(f"{path}: cannot read the {what} ({e.strerror})") from None
    except json.JSONDecodeError as e:
        raise JobError(f"{path}: not valid JSON (line {e.lineno}: {e.msg})") from None
    if not isinstance(d, dict):
        raise JobError(f"{path.name}: expected a JSON object")
    return d


def _body(d: dict, base: Path, where: str) -> tuple[Skeleton, BvhFile, Path, BvhFile, int]:
    """The ``skeleton`` and ``initial`` fields: skeleton, its BVH and that file's path, the
    initial BVH and frame."""
    sk_spec = _field(d, "skeleton", where, dict)
    bvh_path = base / _field(sk_spec, "bvh", f"{where}.skeleton", str)
    try:
        bvh = read_bvh(bvh_path)
    except BvhError as e:
        raise JobError(f"{where}.skeleton.bvh: {e}") from None
    sk = skeleton_from_bvh(bvh)
    _apply_joints(sk, _field(sk_spec, "joints", f"{where}.skeleton"), f"{where}.skeleton.joints")
    sk.blobs = sk.default_blobs()
    if "blobs" in sk_spec:
        _apply_blobs(sk, sk_spec["blobs"], f"{where}.skeleton.blobs")
    init_bvh, frame = _bvh_pose(_field(d, "initial", where, dict), bvh, bvh_path, base,
                                f"{where}.initial")
    return sk, bvh, bvh_path, init_bvh, frame


def _bvh_pose(spec: dict, bvh: BvhFile, bvh_path: Path, base: Path, where: str
              ) -> tuple[BvhFile, int]:
    """A pose given as ``{"bvh": path, "frame": k}`` (frame 0 if not given): the BVH holding
    it (``bvh`` itself when the path is ``bvh_path``) and the frame, checked."""
    path = base / _field(spec, "bvh", where, str)
    frame = _field(spec, "frame", where, int) if "frame" in spec else 0
    try:
        pose_bvh = bvh if path == bvh_path else read_bvh(path)
    except BvhError as e:
        raise JobError(f"{where}.bvh: {e}") from None
    if pose_bvh.names != bvh.names:
        raise JobError(f"{where}.bvh: its hierarchy differs from the skeleton's BVH")
    if not 0 <= frame < len(pose_bvh.motion):
        raise JobError(f"{where}.frame: {frame} is outside 0..{len(pose_bvh.motion) - 1}")
    return pose_bvh, frame


def _corrections(spec, sk: Skeleton, bvh: BvhFile, bvh_path: Path, base: Path,
                 cameras: list[Camera], n_frames: int, where: str) -> dict[int, BodyPose]:
    """The ``corrections`` field: footage frame -> the pose the user gives there."""
    if not isinstance(spec, list):
        raise JobError(f"{where}: expected a list of {{image, bvh, frame}}")
    out = {}
    for i, c in enumerate(spec):
        at = f"{where}[{i}]"
        if not isinstance(c, dict):
            raise JobError(f"{at}: expected an object with image, bvh and frame")
        image = _field(c, "image", at, int)
        if not 1 <= image < n_frames:
            raise JobError(f"{at}.image: {image} is outside 1..{n_frames - 1} (frame 0 is "
                           "the initial pose's)")
        if image in out:
            raise JobError(f"{at}.image: frame {image} is corrected twice")
        pose_bvh, frame = _bvh_pose(c, bvh, bvh_path, base, at)
        out[image] = pose_from_bvh(pose_bvh, frame, cameras)
    return out


def _views(d: dict, base: Path, where: str) -> tuple[list[dict], list[list[Camera]], list]:
    """The ``views`` field (at least one), each view's camera (one per frame where it moves)
    and its lens distortion."""
    views = _field(d, "views", where, list)
    if not views:
        raise JobError(f"{where}.views: expected at least one view")
    parsed = [parse_camera(_field(v, "camera", f"{where}.views[{i}]"),
                           f"{where}.views[{i}].camera", base) for i, v in enumerate(views)]
    return views, [c for c, _ in parsed], [dist for _, dist in parsed]


def _mode(d: dict, cameras: list[Camera], where: str) -> str:
    """The ``mode`` field: 'calibrated' by default with pinhole cameras (and only then),
    'independent' otherwise."""
    pinhole = [i for i, c in enumerate(cameras) if c.central]
    mode = d.get("mode", CALIBRATED if pinhole else INDEPENDENT)
    if mode not in (CALIBRATED, INDEPENDENT):
        raise JobError(f"{where}.mode: expected 'calibrated' or 'independent', got {mode!r}")
    if pinhole and mode != CALIBRATED:
        raise JobError(f"{where}.mode: view {pinhole[0] + 1}'s camera is a pinhole, whose "
                       "pose is its calibration's: the mode must be 'calibrated'")
    return mode


def _in_front(pose: BodyPose, sk: Skeleton, where: str) -> None:
    """Every joint of ``pose`` in front of every pinhole camera (a JobError naming the view
    and a joint behind it)."""
    X = sk.world_positions(pose.rotations, pose.root_position)
    for i, cam in enumerate(pose.views):
        if cam.central:
            z = cam.camera_points(X)[:, 2]
            if np.any(z <= 0):
                j = int(np.argmin(z))
                raise JobError(f"{where}: the joint '{sk.names[j]}' lies behind view {i + 1}'s "
                               f"camera (depth {z[j]:.3g}): check the camera's R and t "
                               "(x_cam = R X + t, z forward) and the pose's units")


def load_job(path: str | Path) -> Job:
    """Read and validate a job file; raises JobError naming the first bad field."""
    path = Path(path)
    d = _read_json(path, "job file")
    base, where = path.parent, path.name
    sk, bvh, bvh_path, init_bvh, frame = _body(d, base, where)
    views, paths, dists = _views(d, base, where)
    cameras = [p[0] for p in paths]
    images = [_images(_field(v, "images", f"{where}.views[{i}]"), base,
                      f"{where}.views[{i}].images") for i, v in enumerate(views)]
    images = [x if dist is None else Undistorted(x, cam.K, dist)
              for x, cam, dist in zip(images, cameras, dists)]
    plates = [_clean_plate(v.get("backdrop"), base, f"{where}.views[{i}].backdrop", cam, dist)
              for i, (v, cam, dist) in enumerate(zip(views, cameras, dists))]
    counts = {len(x) for x in images}
    if len(counts) > 1:
        raise JobError(f"{where}.views: every view needs the same number of frames, got "
                       + ", ".join(str(len(x)) for x in images))
    if min(counts) < 2:
        raise JobError(f"{where}.views: at least two frames are needed to track")
    mode = _mode(d, cameras, where)
    moving = [p if len(p) > 1 else None for p in paths]
    for i, p in enumerate(moving):
        at = f"{where}.views[{i}].camera"
        if p is not None and len(p) != len(images[i]):
            raise JobError(f"{at}: its R and t are given on {len(p)} frames, its footage has "
                           f"{len(images[i])}: one per frame, or one for a camera that stands "
                           "still")
        if p is not None and mode != CALIBRATED:
            raise JobError(f"{at}: a camera that moves needs \"mode\": \"calibrated\" (the "
                           "body's root is tracked in the world)")
    settings = _settings(d.get("settings"), f"{where}.settings")
    ft = d.get("frame_time", bvh.frame_time)
    if not isinstance(ft, (int, float)) or ft <= 0:
        raise JobError(f"{where}.frame_time: expected seconds per frame > 0, got {ft!r}")
    pose = pose_from_bvh(init_bvh, frame, cameras)
    _in_front(pose, sk, f"{where}.initial")
    corrections = _corrections(d.get("corrections", []), sk, bvh, bvh_path, base, cameras,
                               len(images[0]), f"{where}.corrections")
    return Job(sk, bvh, pose, images, cameras, mode, settings, float(ft), corrections, moving,
               plates)


@dataclass
class FitJob:
    """A fit: the skeleton and its guessed pose, the cameras, and per view the clicked joints
    (name -> pixel)."""

    skeleton: Skeleton
    bvh: BvhFile
    guess: BodyPose
    cameras: list[Camera]
    clicks: list[dict[str, np.ndarray]]
    mode: str
    fit_lengths: bool = True  # also fit the bone lengths (needs two views or more)


def load_fit(path: str | Path) -> FitJob:
    """Read and validate a fit file (a tracking job's ``skeleton``, ``initial``, ``views``
    with cameras and no images needed, ``mode``, ``clicks``: per view, joint -> [x, y], and
    optionally ``fit_lengths``, true unless set false)."""
    path = Path(path)
    d = _read_json(path, "fit file")
    base, where = path.parent, path.name
    sk, bvh, _, init_bvh, frame = _body(d, base, where)
    views, paths, dists = _views(d, base, where)
    cameras = [p[0] for p in paths]  # the clicks are on the first frame
    clicks_in = _field(d, "clicks", where, list)
    if len(clicks_in) != len(views):
        raise JobError(f"{where}.clicks: expected one object per view ({len(views)}), got "
                       f"{len(clicks_in)}")
    clicks = []
    for i, c in enumerate(clicks_in):
        w = f"{where}.clicks[{i}]"
        if not isinstance(c, dict):
            raise JobError(f"{w}: expected an object of joint name -> [x, y]")
        for name in c:
            try:
                clicked_point(sk, name)
            except FitError as e:
                raise JobError(f"{w}.{name}: {e}") from None
        at = {name: _vector(p, 2, f"{w}.{name}") for name, p in c.items()}
        if dists[i] is not None and at:  # clicked on the footage as filmed
            ideal = undistort_points(np.array(list(at.values())), cameras[i].K, dists[i])
            at = dict(zip(at, ideal))
        clicks.append(at)
    fit_lengths = _field(d, "fit_lengths", where, bool) if "fit_lengths" in d else True
    guess = pose_from_bvh(init_bvh, frame, cameras)
    _in_front(guess, sk, f"{where}.initial")
    return FitJob(sk, bvh, guess, cameras, clicks, _mode(d, cameras, where), fit_lengths)

"""Footage for the benchmark suite: a capture rendered through three views in one of several
looks that vary what real footage varies.

A look sets the body's cloth (its texture and its contrast with what is behind it), the
backdrop (Muybridge's ruled black, a bright brick wall, a busy park-like scene), the light
(soft studio, or hard sun casting the body's shadow on the wall beside it), motion blur
(sub-frames averaged over half the frame interval), sensor noise and JPEG compression, and
the lens: orthographic (a body far off), or perspective cameras a few metres away, the
lateral one panning to keep the body mid-image (the ruled backdrop turning past as it
turns). The body is the same skinned capsule body as the walk benchmark's
(``walk_footage``), sized by the capture's parts.

Footage is rendered at 30 frames per second (15 fps runs take every other frame) into
``<clip folder>/<look folder>/<view>/NNNN.png|jpg`` (frames from 0), with ``truth.bvh``
(the capture at 30 fps, in metres) and ``cameras.json`` (the orthographic cameras;
``look_cameras`` makes a look's own) in the clip's folder; footage already rendered with
the same look and frames is kept.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np
from captures import Parts, normalized
from walk_footage import (
    RADII,
    add_camera,
    backdrop,
    build_scene,
    cloth_colour,
    pinhole_job_camera,
    place_camera,
)

from core.bvh import read_bvh, write_bvh
from core.skeleton import skeleton_from_bvh

WIDTH, HEIGHT = 480, 360
PIXELS_PER_METRE = 125.0  # a 1.7 m body stands about 210 px tall; 3.8 m of stage across
VIDEO_FPS = 30
VIEWS = ("lateral", "endon", "oblique60")


@dataclass(frozen=True)
class Look:
    cloth: str  # "woven" (blotchy weave), "plain" (one light colour), "stripes" (dark/light)
    backdrop: str  # "ruled" (dark, light lines), "bricks" (a bright wall), "park" (busy)
    light: str  # "studio" (soft) or "sun" (hard: the body's shadow falls on the backdrop)
    blur: int  # sub-frames averaged per frame (1: no motion blur)
    noise: float  # sensor noise, grey levels of 255
    jpeg: int  # JPEG quality (0: lossless PNG)
    distance: float | None = None  # perspective cameras this far (m) from the stage's centre
    pan: bool = False  # the lateral camera turns to keep the body's root mid-image


LOOKS = {
    "muybridge": Look("woven", "ruled", "studio", 1, 2.0, 0),
    "sunlit wall": Look("plain", "bricks", "sun", 1, 3.0, 75),
    "park video": Look("stripes", "park", "studio", 3, 4.0, 60),
    "close lens": Look("woven", "ruled", "studio", 1, 2.0, 0, distance=3.5),
    "panning": Look("woven", "ruled", "studio", 1, 2.0, 0, distance=3.5, pan=True),
}


@dataclass(frozen=True)
class Clip:
    name: str
    path: Path  # a capture of one of captures.NAMINGS
    first: int  # file frames first..last (inclusive) at the capture's own rate
    last: int


def _smooth_noise(rng, shape, scale: float) -> np.ndarray:
    import cv2

    small = rng.normal(size=(max(shape[0] // int(scale), 2) + 2,
                             max(shape[1] // int(scale), 2) + 2))
    big = cv2.resize(small, (shape[1] + 2 * int(scale), shape[0] + 2 * int(scale)),
                     interpolation=cv2.INTER_CUBIC)
    return big[int(scale):int(scale) + shape[0], int(scale):int(scale) + shape[1]]


def backdrop_image(kind: str, seed: int) -> np.ndarray:
    """A still backdrop, BGR 0..255 (HEIGHT, WIDTH, 3)."""
    rng = np.random.default_rng(seed)
    if kind == "ruled":
        return backdrop()
    if kind == "bricks":  # light bricks 30 x 12 px, offset every other row, pale mortar
        y, x = np.mgrid[:HEIGHT, :WIDTH]
        row = y // 12
        col = (x + 15 * (row % 2)) // 30
        tint = rng.normal(0, 12, (row.max() + 1, col.max() + 2))[row, col]
        img = np.empty((HEIGHT, WIDTH, 3))
        img[:] = (150.0, 175.0, 205.0)  # BGR: a warm light wall
        img += tint[..., None]
        mortar = (y % 12 == 0) | ((x + 15 * (row % 2)) % 30 == 0)
        img[mortar] = (190.0, 200.0, 210.0)
        return img + 8 * _smooth_noise(rng, (HEIGHT, WIDTH), 40)[..., None]
    if kind == "park":  # foliage and trunks: texture at several scales, greens and browns
        leaves = sum(w * _smooth_noise(rng, (HEIGHT, WIDTH), s)
                     for w, s in ((0.5, 3), (0.8, 9), (1.0, 30), (0.7, 90)))
        img = np.stack([40 + 18 * leaves, 95 + 30 * leaves, 70 + 20 * leaves], -1)
        for x0 in rng.uniform(0, WIDTH, 5).astype(int):  # dark trunks
            w = int(rng.uniform(6, 18))
            img[:, x0:x0 + w] = (40.0, 55.0, 70.0) + 10 * rng.normal(size=(HEIGHT, 1, 1))
        ground = np.arange(HEIGHT) > 0.8 * HEIGHT
        img[ground] = (90.0, 130.0, 150.0) + 15 * rng.normal(size=(int(ground.sum()), WIDTH, 3))
        return img
    raise ValueError(f"no backdrop '{kind}'")


SHADOW_OFFSET = (22, 8)  # pixels the sun's shadow of the body falls right and down of it
SHADOW_DEPTH = 0.55  # share of the backdrop's light the shadow takes away


def cast_shadow(alpha: np.ndarray) -> np.ndarray:
    """The body's shadow on the wall behind it (H, W, 1) in [0, 1]: its coverage ``alpha``
    (H, W, 1) moved by ``SHADOW_OFFSET``, its edge softened over a pixel (a hard sun).
    Rendering Workbench's own shadows costs 2.5 s a frame without a GPU; on a flat wall
    square to the camera a shadow is this shift."""
    import cv2

    dx, dy = SHADOW_OFFSET
    moved = np.zeros_like(alpha[..., 0])
    moved[dy:, dx:] = alpha[:-dy, :-dx, 0]
    return cv2.GaussianBlur(moved, (3, 3), 0.8)[..., None]


def cloth(kind: str, P: np.ndarray) -> np.ndarray:
    """Vertex colours (N, 3) RGB in [0, 1] of rest-pose positions P (N, 3)."""
    if kind == "woven":
        return cloth_colour(P)
    if kind == "plain":  # light beige with faint blotches: little texture, low contrast
        blotch = np.sin(P @ np.array([31.0, 17.0, 23.0])) * 0.03
        return np.clip(np.array([0.78, 0.70, 0.58]) + blotch[:, None], 0, 1)
    if kind == "stripes":  # navy and white bands around the body every 8 cm
        band = np.sin(P[:, 1] * 2 * np.pi / 0.08) > 0
        return np.where(band[:, None], [0.9, 0.9, 0.85], [0.1, 0.12, 0.3])
    raise ValueError(f"no cloth '{kind}'")


def view_rotations(lateral: np.ndarray) -> dict[str, np.ndarray]:
    """World-to-camera rotations (rows: image x, image y down, viewing direction) for a body
    whose left points along ``lateral`` (horizontal): the lateral view looks across it from
    its right, the end-on view at its front, the oblique one 60 degrees between."""
    up = np.array([0.0, 1.0, 0.0])
    side = lateral / np.linalg.norm(lateral)
    forward = np.cross(side, up)

    a = np.radians(60)
    return {"lateral": _looking(side), "endon": _looking(-forward),
            "oblique60": _looking(np.cos(a) * side - np.sin(a) * forward)}


def job_camera(R: np.ndarray, centre: np.ndarray) -> dict:
    return {"model": "scaled_orthographic", "R": R.tolist(), "t": (-R @ centre).tolist(),
            "scale": PIXELS_PER_METRE, "center": [WIDTH / 2 - 0.5, HEIGHT / 2 - 0.5]}


def turned_backdrop(back: np.ndarray, K: np.ndarray, R0: np.ndarray, R: np.ndarray
                    ) -> np.ndarray:
    """The backdrop ``back`` (as the camera with intrinsics K shows it turned by R0) seen by
    the same camera turned to R about its centre: every still point moves by the homography
    K R R0^T K^-1, whatever its depth. The backdrop is taken to repeat beyond its edges
    (it is drawn periodic across), so a wide pan never runs out of wall."""
    import cv2

    h, w = back.shape[:2]
    shift = np.array([[1.0, 0, w], [0, 1, h], [0, 0, 1]])  # the middle tile of a 3 x 3
    H = K @ R @ R0.T @ np.linalg.inv(K) @ np.linalg.inv(shift)
    return cv2.warpPerspective(np.tile(back, (3, 3, 1)), H, (w, h), flags=cv2.INTER_LINEAR)


HALF = "_half"  # after a look's name: its footage and jobs at half the size (``halve_job``)


def halved_camera(cam: dict) -> dict:
    """A job's camera (``job_camera``, ``pinhole_job_camera``) on its footage halved: pixel
    p (centres at integers) becomes (p + 0.5) / 2 - 0.5, as a camera twice as far, or with
    half the focal length, would show the body."""
    out = dict(cam)
    if cam["model"] == "scaled_orthographic":
        out["scale"] = cam["scale"] / 2
        out["center"] = [(c + 0.5) / 2 - 0.5 for c in cam["center"]]
    else:
        K = np.array(cam["K"], float)
        K[:2, :2] /= 2
        K[:2, 2] = (K[:2, 2] + 0.5) / 2 - 0.5
        out["K"] = K.tolist()
    return out


def _retouched_job(job_path: Path, tag: str, retouch, camera=None) -> Path:
    """The suite job ``job_path`` (``<look>__<run>...json``, its images under ``<look>/``) on
    its footage retouched: each image ``retouch(image, name)`` (its pixels as stored, its
    path in the job) into ``<look><tag>/`` beside it (once), each view's camera
    ``camera(camera)`` (None: as it is); the job written as ``<look><tag>__<run>...json``."""
    import cv2

    look, rest = job_path.name.split("__", 1)
    job = json.loads(job_path.read_text())
    for view in job["views"]:
        if camera is not None:
            view["camera"] = camera(view["camera"])
        retouched = []
        for image in view["images"]:
            parts = Path(image).parts
            out = Path(parts[0] + tag, *parts[1:])
            target = job_path.parent / out
            if not target.exists():
                target.parent.mkdir(parents=True, exist_ok=True)
                stored = cv2.imread(str(job_path.parent / image), cv2.IMREAD_UNCHANGED)
                cv2.imwrite(str(target), retouch(stored, image))
            retouched.append(out.as_posix())
        view["images"] = retouched
    out = job_path.with_name(f"{look}{tag}__{rest}")
    out.write_text(json.dumps(job, indent=1))
    return out


def halve_job(job_path: Path) -> Path:
    """The suite job ``job_path`` on its footage halved in size (``_retouched_job``): every
    image's 2 x 2 pixels averaged into ``<look>_half/``, the cameras with it
    (``halved_camera``), the job ``<look>_half__<run>...json``. A body 100 pixels tall
    instead of 205, as a wide shot or a far camera shows one."""
    import cv2

    def halved(img: np.ndarray, _name: str) -> np.ndarray:
        h, w = img.shape[:2]
        return cv2.resize(img, (w // 2, h // 2), interpolation=cv2.INTER_AREA)

    return _retouched_job(job_path, HALF, halved, halved_camera)


DRIFT = "_drift"  # after a look's name: its footage with the exposure drifting (``drift_job``)
DRIFT_SWING = 0.3  # the drifting exposure's gain swings this far either side of 1
DRIFT_PERIOD = 45  # capture frames (30 fps) of one swing up and down: one and a half seconds


def drift_gain(frame: int) -> float:
    """The drifting exposure's gain on capture frame ``frame``: 1 + 0.3 sin(2 pi f / 45)."""
    return 1.0 + DRIFT_SWING * float(np.sin(2 * np.pi * frame / DRIFT_PERIOD))


def drift_job(job_path: Path) -> Path:
    """The suite job ``job_path`` on its footage with the exposure drifting, as a phone's
    automatic exposure does (``_retouched_job``): every image (its name its capture frame)
    times ``drift_gain``, clipped, into ``<look>_drift/``; the job
    ``<look>_drift__<run>...json``."""

    def drifted(img: np.ndarray, name: str) -> np.ndarray:
        gain = drift_gain(int(Path(name).stem))
        return np.clip(img * gain + 0.5, 0, 255).astype(np.uint8)

    return _retouched_job(job_path, DRIFT, drifted)


def look_cameras(clip_dir: Path, look: Look) -> dict[str, dict]:
    """Each view's job camera in ``look``: the clip's orthographic one, or a pinhole
    ``look.distance`` metres back along its line of sight showing the stage's centre as
    large; a panning camera's R and t given per frame (the capture's 30 fps), turned about
    the vertical to look at the root's horizontal position."""
    cams = json.loads((clip_dir / "cameras.json").read_text())
    if look.distance is None:
        return cams
    root = read_bvh(clip_dir / "truth.bvh").poses()[1]
    out = {}
    for v, cam in cams.items():
        R = np.array(cam["R"])
        centre = -R.T @ np.array(cam["t"])
        position = centre - look.distance * R[2]
        Rs = [R]
        if look.pan and v == "lateral":
            sight = root - position
            sight[:, 1] = 0.0  # turned about the vertical only
            Rs = [_looking(d) for d in sight]
        out[v] = pinhole_job_camera(Rs, position, PIXELS_PER_METRE * look.distance,
                                    [WIDTH / 2 - 0.5, HEIGHT / 2 - 0.5])
    return out


def _looking(direction: np.ndarray) -> np.ndarray:
    """World-to-camera rotation of a level camera looking along ``direction``."""
    up = np.array([0.0, 1.0, 0.0])
    z = direction / np.linalg.norm(direction)
    return np.stack([np.cross(-up, z), -up, z])


def stage(clip: Clip, out: Path) -> dict:
    """Write OUT/truth.bvh (the clip at 30 fps) and OUT/cameras.json; return the cameras."""
    bvh = normalized(clip.path, clip.first, clip.last)
    step = max(int(round(1 / bvh.frame_time / VIDEO_FPS)), 1)
    bvh.motion = bvh.motion[::step]
    bvh.frame_time *= step
    out.mkdir(parents=True, exist_ok=True)
    write_bvh(bvh, out / "truth.bvh")
    sk = skeleton_from_bvh(bvh)
    parts = Parts.of(bvh.names)
    R, root = bvh.poses()
    X = sk.world_positions(R[0], root[0])
    lateral = X[sk.index(parts.roles["thigh.L"])] - X[sk.index(parts.roles["thigh.R"])]
    lateral[1] = 0.0
    centre = root.mean(0)
    cams = {v: job_camera(Rv, centre) for v, Rv in view_rotations(lateral).items()}
    (out / "cameras.json").write_text(json.dumps(cams, indent=1))
    return cams


def _look_stamp(clip_dir: Path, look_name: str) -> dict:
    """What ``out/look.json`` says of a look rendered whole: the look, the clip's frames."""
    look = LOOKS[look_name]
    meta = {"look": asdict(look), "frames": len(read_bvh(clip_dir / "truth.bvh").motion),
            "version": 1}
    if look.distance is None:  # as the looks' stamps were before lenses were looks
        del meta["look"]["distance"], meta["look"]["pan"]
    if look.pan:  # rendered again since its backdrop turns with the camera (it slid before)
        meta["backdrop"] = "turned"
    return meta


def look_rendered(clip_dir: Path, look_name: str, out: Path) -> bool:
    """Whether ``out`` holds the look's footage of ``clip_dir/truth.bvh``, every frame of
    every view, rendered with the look as it is now."""
    return _whole(out, _look_stamp(clip_dir, look_name), LOOKS[look_name])


def _whole(out: Path, meta: dict, look: Look) -> bool:
    """Whether ``out`` is stamped ``meta`` and holds every view's last frame."""
    stamp, last = out / "look.json", f"{meta['frames'] - 1:04d}.{frame_ext(look)}"
    return stamp.is_file() and json.loads(stamp.read_text()) == meta and all(
        (out / v / last).is_file() for v in VIEWS)


def frame_ext(look: Look) -> str:
    """The file type of the look's frames."""
    return "jpg" if look.jpeg else "png"


def render_look(clip_dir: Path, look_name: str, out: Path) -> int:
    """Render every frame of ``clip_dir/truth.bvh`` in every view in the look into
    ``out/<view>/``; returns how many images were rendered now (0: all were there). Blender
    renders one scene at a time: looks are rendered at once in processes of their own."""
    look, meta = LOOKS[look_name], _look_stamp(clip_dir, look_name)
    if _whole(out, meta, look):
        return 0
    import bpy
    import cv2

    stamp, n, truth = out / "look.json", meta["frames"], clip_dir / "truth.bvh"
    ext = frame_ext(look)
    cams = look_cameras(clip_dir, look)
    sk = skeleton_from_bvh(read_bvh(truth))
    parts = Parts.of(sk.names)
    _, body = build_scene(bpy, truth, radii=parts.radii(RADII), width=WIDTH, height=HEIGHT)
    P = np.array([v.co for v in body.data.vertices])
    rgba = np.concatenate([cloth(look.cloth, P), np.ones((len(P), 1))], 1)
    body.data.color_attributes["cloth"].data.foreach_set("color",
                                                         rgba.astype(np.float32).ravel())
    scene = bpy.context.scene
    rng = np.random.default_rng(n * 7919 + len(look_name))
    tmp = out / "_subframe.png"
    for k, v in enumerate(VIEWS):
        Rs, ts = np.array(cams[v]["R"]).reshape(-1, 3, 3), np.array(cams[v]["t"]).reshape(-1, 3)
        look_at = -Rs[0].T @ ts[0] + (look.distance or 0.0) * Rs[0][2]
        scene.camera = add_camera(bpy, v, Rs[0], look_at, WIDTH / PIXELS_PER_METRE,
                                  look.distance)
        still = back = backdrop_image(look.backdrop, seed=17 + k)
        (out / v).mkdir(parents=True, exist_ok=True)
        for f in range(n):
            if len(Rs) > 1:  # a pan: the camera turns, and the backdrop with it
                place_camera(scene.camera, Rs[f], -Rs[f].T @ ts[f])
                back = turned_backdrop(still, np.array(cams[v]["K"]), Rs[0], Rs[f])
            acc = np.zeros((HEIGHT, WIDTH, 3))
            for s in range(look.blur):
                sub = (s / look.blur - 0.5) * 0.5 if look.blur > 1 else 0.0  # half a frame
                whole = int(np.floor(f + 1 + sub))
                scene.frame_set(whole, subframe=f + 1 + sub - whole)
                scene.render.filepath = str(tmp)
                bpy.ops.render.render(write_still=True)
                img = cv2.imread(str(tmp), cv2.IMREAD_UNCHANGED).astype(np.float32)
                alpha = img[..., 3:] / 255
                wall = back * (1 - SHADOW_DEPTH * cast_shadow(alpha)) if look.light == "sun" \
                    else back
                acc += img[..., :3] * alpha + wall * (1 - alpha)
            img = acc / look.blur + rng.normal(0, look.noise, acc.shape)
            img = np.clip(img + 0.5, 0, 255).astype(np.uint8)
            params = [cv2.IMWRITE_JPEG_QUALITY, look.jpeg] if look.jpeg else []
            cv2.imwrite(str(out / v / f"{f:04d}.{ext}"), img, params)
    tmp.unlink(missing_ok=True)
    stamp.write_text(json.dumps(meta))
    return n * len(VIEWS)

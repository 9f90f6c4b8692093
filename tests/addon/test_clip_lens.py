"""A movie clip's lens distortion (Blender's Movie Clip editor) undone as Track reads the
footage: the conversion to OpenCV's model checked against Blender's own formulas (libmv's,
written out here in Blender's pixels, y up), and footage distorted through them read back
as the ideal lens saw it, through the real bridge and operator."""

import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
from walk_footage import HEIGHT, WIDTH, render, tracking_scene  # noqa: E402

from core.image import to_grey  # noqa: E402
from core.lens import distort_points  # noqa: E402
from support.legs import leg_errors  # noqa: E402

VIEWS = ["lateral", "endon", "oblique60"]
FOCAL, CENTRE = 520.0, (251.0, 171.0)  # pixels; the centre with y up from the bottom row
LENSES = {
    "POLYNOMIAL": {"k1": -0.22, "k2": 0.06, "k3": 0.01},
    "DIVISION": {"division_k1": 0.18, "division_k2": -0.03},
    "BROWN": {"brown_k1": -0.2, "brown_k2": 0.05, "brown_k3": 0.0, "brown_k4": 0.0,
              "brown_p1": 0.006, "brown_p2": -0.004},
}


def blender_distort(pts: np.ndarray, model: str, k: dict) -> np.ndarray:
    """Blender's (libmv's) distortion of pixels (N, 2) with y up, as its source writes it."""
    x, y = ((pts - CENTRE) / FOCAL).T
    r2 = x * x + y * y
    if model == "POLYNOMIAL":
        d = 1 + r2 * (k["k1"] + r2 * (k["k2"] + r2 * k["k3"]))
        tx = ty = 0.0
    elif model == "DIVISION":
        d = 1 / (1 + r2 * (k["division_k1"] + r2 * k["division_k2"]))
        tx = ty = 0.0
    else:
        d = 1 + r2 * (k["brown_k1"] + r2 * (k["brown_k2"] + r2 * (k["brown_k3"]
                                                                 + r2 * k["brown_k4"])))
        p1, p2 = k["brown_p1"], k["brown_p2"]
        tx = p1 * (r2 + 2 * x * x) + 2 * p2 * x * y
        ty = p2 * (r2 + 2 * y * y) + 2 * p1 * x * y
    return np.stack([x * d + tx, y * d + ty], 1) * FOCAL + CENTRE


def flip(pts: np.ndarray) -> np.ndarray:
    """Pixels with y up from the bottom row <-> y down from the top row."""
    return np.stack([pts[:, 0], HEIGHT - 1 - pts[:, 1]], 1)


def set_lens(clip, model: str) -> None:
    tc = clip.tracking.camera
    tc.focal_length_pixels = FOCAL
    tc.principal_point_pixels = CENTRE
    tc.distortion_model = model
    for name, value in LENSES[model].items():
        setattr(tc, name, value)


@pytest.fixture(scope="module")
def footage(tmp_path_factory):
    """The rendered walk, and its lateral view as filmed through the Brown lens (each pixel
    of the distorted frame takes the ideal frame's pixel that the lens sends there)."""
    folder = tmp_path_factory.mktemp("walk_lens")
    render(folder, 560, 580, 4, VIEWS)
    u, v = np.meshgrid(np.arange(WIDTH, dtype=float), np.arange(HEIGHT, dtype=float))
    seen = flip(np.stack([u.ravel(), v.ravel()], 1))  # where the lens put each pixel
    ideal = seen.copy()
    for _ in range(50):  # fixed point: the ideal pixel the lens sends to ``seen``
        ideal += seen - blender_distort(ideal, "BROWN", LENSES["BROWN"])
    src = flip(ideal).reshape(HEIGHT, WIDTH, 2).astype(np.float32)
    (folder / "lateral_lens").mkdir()
    for path in sorted((folder / "lateral").glob("*.png")):
        img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
        cv2.imwrite(str(folder / "lateral_lens" / path.name),
                    cv2.remap(img, src[..., 0], src[..., 1], cv2.INTER_LINEAR,
                              borderMode=cv2.BORDER_REPLICATE))
    return folder


@pytest.mark.parametrize("model", sorted(LENSES))
def test_a_clips_lens_in_opencvs_terms_distorts_as_blender_does(bpy_module, registered,
                                                                footage, model):
    bpy = bpy_module
    clip = bpy.data.movieclips.load(str(sorted((footage / "lateral").glob("*.png"))[0]))
    set_lens(clip, model)
    K, dist = registered.twist_addon.clip_lens.opencv_lens(clip)
    rng = np.random.default_rng(3)
    ideal = rng.uniform([0, 0], [WIDTH - 1, HEIGHT - 1], (200, 2))  # y up
    want = flip(blender_distort(ideal, model, LENSES[model]))
    got = distort_points(flip(ideal), K, dist)
    assert np.abs(want - ideal).max() > 20  # the lens moves points far...
    np.testing.assert_allclose(got, want, atol=1e-6)  # ...and OpenCV's model as far
    bpy.data.movieclips.remove(clip)


def test_footage_behind_a_distorting_clip_is_read_undistorted_and_tracked(
        bpy_module, registered, footage):
    """The lateral view's footage filmed through the Brown lens, the clip behind its camera
    holding that lens: the tracker reads each frame as the ideal lens saw it (the rendered
    frame, within resampling twice), Track says so, and the legs follow the capture. A
    model OpenCV cannot hold (Nuke) is tracked as filmed, with a note saying so."""
    bpy = bpy_module
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene, arm = tracking_scene(bpy, footage, VIEWS, 6)
    addon = registered.twist_addon
    view = scene.twist.views[0]
    view.images = str(footage / "lateral_lens" / "*.png")
    clip = bpy.data.movieclips.load(str(sorted((footage / "lateral_lens").glob("*.png"))[0]))
    set_lens(clip, "BROWN")
    bg = view.camera.data.background_images.new()
    bg.source, bg.clip = "MOVIE_CLIP", clip

    session = addon.track.TrackSession.from_scene(scene)
    inner = (slice(30, HEIGHT - 30), slice(40, WIDTH - 40))  # away from the replicated rim

    def soft(img):  # resampled twice, the backdrop's one-pixel lines soften: compare softened
        return cv2.GaussianBlur(img, (0, 0), 1.5)[inner]

    for k in (0, 5):
        rendered = cv2.imread(str(sorted((footage / "lateral").glob("*.png"))[k]),
                              cv2.IMREAD_GRAYSCALE).astype(np.float32) / 255
        filmed = cv2.imread(str(sorted((footage / "lateral_lens").glob("*.png"))[k]),
                            cv2.IMREAD_GRAYSCALE).astype(np.float32) / 255
        read = to_grey(session.tracker.seq.images[0][k])
        assert np.abs(soft(filmed) - soft(rendered)).mean() > 0.02
        # measured 0.0022; 0.0059 with the centre's y not flipped, 0.014 with Brown's
        # tangential terms taken as OpenCV's
        assert np.abs(soft(read) - soft(rendered)).mean() < 0.004, k

    assert bpy.ops.twist.track() == {"FINISHED"}
    notes = scene.twist.result.notes
    assert (f"the footage behind '{view.camera.name}' was undistorted through the lens of the "
            f"clip '{clip.name}' (Brown)") in notes
    legs = leg_errors(scene, addon.bridge, arm, footage, range(2, 7))
    assert np.all(legs < 8.0), legs

    bpy.ops.twist.clear_track()
    scene.frame_set(1)
    clip.tracking.camera.distortion_model = "NUKE"
    clip.tracking.camera.nuke_k1 = -0.1
    assert bpy.ops.twist.track() == {"FINISHED"}
    assert (f"the clip '{clip.name}' behind '{view.camera.name}' has lens distortion that the "
            "tracker does not undo (its distortion model (Nuke) is not one the tracker "
            "can undo)") in scene.twist.result.notes

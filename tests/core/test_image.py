"""Pyramids, derivatives and bilinear sampling on images with known values."""

import cv2
import numpy as np
import pytest

from core import image


def test_sampling_is_exact_at_pixels_and_linear_between():
    rng = np.random.default_rng(0)
    img = rng.uniform(size=(50, 70)).astype(np.float32)
    lv = image.Level(np.dstack([img, img, img]), 1.0)
    ys, xs = np.mgrid[1:49, 1:69]
    pts = np.stack([xs.ravel(), ys.ravel()], 1).astype(float)
    vals, inside = image.sample(lv, pts)
    assert inside.all()
    np.testing.assert_allclose(vals[:, 0], img[ys.ravel(), xs.ravel()], atol=1e-6)
    mid, _ = image.sample(lv, np.array([[10.25, 20.5]]))
    expect = (0.75 * (img[20, 10] + img[21, 10]) + 0.25 * (img[20, 11] + img[21, 11])) / 2
    assert mid[0, 0] == pytest.approx(expect, abs=1e-5)


def test_more_points_than_remap_accepts_in_one_row():
    img = np.tile(np.arange(40, dtype=np.float32), (30, 1))
    lv = image.Level(np.dstack([img, img, img]), 1.0)
    pts = np.random.default_rng(1).uniform([0, 0], [39, 29], size=(70000, 2))
    vals, _ = image.sample(lv, pts)
    np.testing.assert_allclose(vals[:, 0], pts[:, 0], atol=1 / 64 + 1e-4)  # remap's 1/32 px grid


def test_pyramid_derivatives_of_a_ramp_are_its_slope_per_full_pixel():
    H, W = 128, 160
    xs = np.arange(W, dtype=np.float32)
    img = np.tile(0.2 + 0.003 * xs, (H, 1)) + 0.002 * np.arange(H, dtype=np.float32)[:, None]
    levels = image.pyramid(img, 3)
    for lv in levels:
        pts = np.array([[60.0, 50.0], [80.3, 70.7]])
        vals, inside = image.sample(lv, pts)
        assert inside.all()
        np.testing.assert_allclose(vals[:, 1], 0.003, rtol=0.02)
        np.testing.assert_allclose(vals[:, 2], 0.002, rtol=0.02)
        np.testing.assert_allclose(vals[:, 0], 0.2 + 0.003 * pts[:, 0] + 0.002 * pts[:, 1],
                                   atol=2e-4)


def test_a_levels_values_at_its_pixels_carry_its_slope_per_level_pixel():
    H, W = 128, 160
    ys, xs = np.mgrid[0:H, 0:W].astype(np.float32)
    img = 0.2 + 0.003 * xs + 0.002 * ys
    for lv in image.pyramid(img, 3):
        px = np.array([[20, 15], [25, 22]])  # inside every level, away from its edges
        at = lv.values(px, derivatives=True)
        assert at.shape == (2, 3)
        np.testing.assert_allclose(at[:, 0], lv.values(px)[:, 0])
        full = px * lv.scale  # the level pixel's full-resolution place (its corner)
        np.testing.assert_allclose(at[:, 0], image.sample(lv, full.astype(float))[0][:, 0],
                                   atol=1e-5)
        np.testing.assert_allclose(at[:, 1], 0.003 * lv.scale, rtol=0.02)
        np.testing.assert_allclose(at[:, 2], 0.002 * lv.scale, rtol=0.02)


def test_points_outside_are_flagged():
    lv = image.pyramid(np.zeros((20, 30), np.float32), 2)[1]
    _, inside = image.sample(lv, np.array([[-3.0, 5.0], [10.0, 10.0], [29.9, 19.0]]))
    assert inside.tolist() == [False, True, False]


def test_load_grey_reads_files_and_names_bad_ones(tmp_path):
    path = tmp_path / "a.png"
    cv2.imwrite(str(path), np.full((4, 5, 3), 255, np.uint8))
    np.testing.assert_allclose(image.load_grey(path), 1.0)
    with pytest.raises(image.ImageError, match="missing.png"):
        image.load_grey(tmp_path / "missing.png")


JPEG_KINDS = pytest.mark.parametrize("params", [[], [cv2.IMWRITE_JPEG_PROGRESSIVE, 1],
                                                [cv2.IMWRITE_JPEG_RST_INTERVAL, 4]],
                                     ids=["baseline", "progressive", "restart markers"])


@JPEG_KINDS
def test_a_jpeg_ends_whole_and_not_when_cut_short_anywhere(params):
    """Every cut of an encoded JPEG, in its headers or its coded data, stops before the end
    marker; the whole file reaches it, with data after it (some cameras append their own)
    or not."""
    img = (np.random.default_rng(0).random((60, 80, 3)) * 255).astype(np.uint8)
    data = cv2.imencode(".jpg", img, params)[1].tobytes()
    assert image.jpeg_ends(data)
    assert image.jpeg_ends(data + b"\xff\xda\x00\x10appended by a camera")
    assert not any(image.jpeg_ends(data[:k]) for k in range(2, len(data) - 1))
    assert not image.jpeg_ends(data[:-2])  # all but the end marker


@JPEG_KINDS
def test_the_footage_check_names_a_jpeg_cut_short_which_the_decoder_fills_with_grey(
        tmp_path, params):
    img = (np.random.default_rng(1).random((60, 80, 3)) * 255).astype(np.uint8)
    data = cv2.imencode(".jpg", img, params)[1].tobytes()
    paths = [tmp_path / f"{f:03d}.jpg" for f in range(4)]
    for f, path in enumerate(paths):
        path.write_bytes(data if f != 2 else data[:len(data) // 2])
    with image.quiet_stderr():  # the decoder's warning
        assert cv2.imread(str(paths[2])) is not None  # it decodes, half of it grey
    image.check_footage(paths[:2], "view 1's footage")
    with pytest.raises(image.ImageError, match="002.jpg: cannot read this image"):
        image.check_footage(paths, "view 1's footage")


def test_a_pyramid_of_channels_is_each_channels_pyramid_and_samples_them_all():
    rng = np.random.default_rng(5)
    img = cv2.GaussianBlur(rng.random((48, 64, 3)).astype(np.float32), (0, 0), 2)
    stacked = image.pyramid(img, 3, highpass=4.0)
    pixels = rng.uniform(0, 60, (40, 2))
    for ch in range(3):
        alone = image.pyramid(np.ascontiguousarray(img[..., ch]), 3, highpass=4.0)
        for a, b in zip(stacked, alone, strict=True):
            assert a.channels == 3 and b.channels == 1
            np.testing.assert_allclose(a.stack[..., ch::3], b.stack, atol=1e-6)
            both, inside = image.sample(a, pixels)
            one, _ = image.sample(b, pixels)
            np.testing.assert_allclose(both[:, ch::3], one, atol=1e-6)


def test_chroma_channels_read_hue_and_are_even_for_grey():
    bgr = np.array([[[128, 128, 128], [0, 0, 255], [255, 0, 0]]], np.uint8)
    grey = image.to_grey(bgr)
    out = image.with_chroma(grey, bgr)
    np.testing.assert_array_equal(out[..., 0], grey)
    np.testing.assert_allclose(out[0, 0, 1:], 0.5, atol=1e-6)  # grey: no hue
    assert out[0, 1, 1] > 0.9 and out[0, 2, 2] > 0.9  # red: Cr, blue: Cb


@pytest.mark.parametrize("channels", [None, 3])
@pytest.mark.parametrize("window", [(70, 40, 150, 130), (0, 0, 60, 50), (120, 90, 333, 251)])
@pytest.mark.parametrize("blur, highpass", [(0.8, 4.0), (1.3, 7.2), (0.8, 0.0)])
def test_a_pyramid_made_over_a_window_is_the_whole_ones_there(channels, window, blur,
                                                              highpass):
    """Every level's stack over the window (with or without the shading filter, of any
    width, and odd sizes) is the whole image's to the bit; its shape is the whole level's."""
    rng = np.random.default_rng(7)
    shape = (251, 333) if channels is None else (251, 333, channels)
    img = cv2.GaussianBlur(rng.random(shape).astype(np.float32), (0, 0), 1.5)
    whole = image.pyramid(img, 4, blur=blur, highpass=highpass)
    part = image.pyramid(img, 4, blur=blur, highpass=highpass, window=window)
    for lv, (a, b) in enumerate(zip(whole, part, strict=True)):
        assert b.shape == a.shape and b.scale == a.scale and b.channels == a.channels
        (x0, y0), (h, w) = b.origin, b.stack.shape[:2]
        assert x0 <= window[0] / 2**lv and y0 <= window[1] / 2**lv
        assert x0 + w >= min(window[2] / 2**lv, a.shape[1])
        assert y0 + h >= min(window[3] / 2**lv, a.shape[0])
        np.testing.assert_array_equal(b.stack, a.stack[y0:y0 + h, x0:x0 + w])


def test_reading_a_windowed_level_outside_its_window_widens_it_and_reads_the_same():
    """Samples and pixel values anywhere in the image are the whole pyramid's, bit for bit:
    inside the window from the window's stack, outside after the level is made whole
    (from the image given again); a read inside leaves the window as it is."""
    rng = np.random.default_rng(3)
    img = cv2.GaussianBlur(rng.random((200, 240, 3)).astype(np.float32), (0, 0), 1.5)
    whole = image.pyramid(img, 3, highpass=4.0)
    asked = []

    def again():
        asked.append(1)
        return img

    part = image.pyramid(img, 3, highpass=4.0, window=(80, 60, 160, 140), again=again)
    near = rng.uniform((90, 70), (150, 130), (500, 2))  # full-resolution pixels
    for a, b in zip(whole, part):
        np.testing.assert_array_equal(image.sample(b, near)[0], image.sample(a, near)[0])
    assert all(b.whole is not None for b in part) and not asked
    anywhere = np.concatenate([near, rng.uniform((-5, -5), (245, 205), (500, 2))])
    for a, b in zip(whole, part):
        got, inside = image.sample(b, anywhere)
        want, inside_whole = image.sample(a, anywhere)
        np.testing.assert_array_equal(inside, inside_whole)
        np.testing.assert_array_equal(got[inside], want[inside])
        assert b.whole is None and b.origin == (0, 0)
    assert len(asked) == 3
    part = image.pyramid(img, 3, highpass=4.0, window=(80, 60, 160, 140))
    pix = np.array([[0, 0], [239, 199], [100, 100]])
    np.testing.assert_array_equal(part[0].values(pix), whole[0].stack[pix[:, 1], pix[:, 0], :3])


def test_a_sample_between_a_window_s_last_pixel_and_the_next_widens_the_level():
    rng = np.random.default_rng(5)
    img = cv2.GaussianBlur(rng.random((120, 160)).astype(np.float32), (0, 0), 1.5)
    whole = image.pyramid(img, 1, highpass=4.0)[0]
    for side in (0, 1):  # right, then bottom
        part = image.pyramid(img, 1, highpass=4.0, window=(40, 30, 90, 80))[0]
        (x0, y0), (h, w) = part.origin, part.stack.shape[:2]
        edge = np.array([[x0 + w - 0.5, y0 + 10.0] if side == 0 else [x0 + 10.0, y0 + h - 0.5]])
        np.testing.assert_array_equal(image.sample(part, edge)[0], image.sample(whole, edge)[0])
        assert part.whole is None

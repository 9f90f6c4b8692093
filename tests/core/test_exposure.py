"""A frame's exposure read against a still backdrop."""

import cv2
import numpy as np
import pytest

from core.exposure import MIN_PIXELS, STRIDE, exposure_gain


def _scene(shape=(240, 320), seed=0, low=0.1, high=0.9):
    """A textured backdrop with values over ``low``-``high``."""
    rng = np.random.default_rng(seed)
    img = cv2.GaussianBlur(rng.uniform(0, 1, shape).astype(np.float32), (0, 0), 2)
    img = (img - img.min()) / (img.max() - img.min())
    return (low + (high - low) * img).astype(np.float32)


@pytest.mark.parametrize("gain", [0.6, 1.0, 1.3])
def test_the_gain_is_read_where_the_scene_is_the_same_though_a_body_fills_most_of_the_frame(
        gain):
    rng = np.random.default_rng(1)
    backdrop = _scene()
    frame = np.clip(gain * backdrop + rng.normal(0, 0.004, backdrop.shape), 0, 1)
    body = np.zeros(backdrop.shape, bool)
    body[:, :180] = True  # 56 % of the frame: a close body, brighter than what it hides
    frame[body] = np.clip(backdrop[body] * 1.6 + 0.2 * rng.uniform(size=body.sum()), 0, 1)
    found = exposure_gain(frame.astype(np.float32), backdrop)
    assert found == pytest.approx(gain, rel=0.005)
    # the plain median of the ratios is pulled far off by the body's
    k = STRIDE
    median = np.median(frame[::k, ::k] / backdrop[::k, ::k])
    assert abs(median / gain - 1) > 0.05


def test_pixels_a_brighter_exposure_clipped_and_those_the_backdrop_has_not_seen_are_not_read():
    backdrop = _scene(seed=2, low=0.35, high=0.95)
    frame = np.clip(1.5 * backdrop, 0, 1)  # about a third of the frame clipped at 1
    assert np.mean(frame >= 1) > 0.25
    unseen = np.zeros(backdrop.shape, bool)
    unseen[60:180, 80:240] = True  # painted in: any value at all
    frame[unseen] = 0.9 * backdrop[unseen]
    assert exposure_gain(frame, backdrop, ~unseen) == pytest.approx(1.5, rel=0.005)


def test_a_scene_too_dark_to_read_keeps_its_exposure():
    backdrop = np.full((120, 160), 0.02, np.float32)
    frame = backdrop * 1.4
    frame[:10, :10 * STRIDE] = 0.5  # too few readable pixels on their own
    assert np.count_nonzero(frame[::STRIDE, ::STRIDE] > 0.05) < MIN_PIXELS
    assert exposure_gain(frame, backdrop) == 1.0


def test_a_gain_of_a_few_per_cent_is_read_as_one_and_a_larger_as_it_is():
    """Footage of one exposure, or nearly, is left as it is (``TOLERANCE``)."""
    backdrop = _scene(seed=3)
    for gain in (1.02, 0.98, 1.0):
        assert exposure_gain(backdrop * gain, backdrop) == 1.0
    for gain in (1.04, 0.96):
        assert exposure_gain(backdrop * gain, backdrop) == pytest.approx(gain, rel=0.002)


"""Frames read ahead on the worker thread are the frames read when asked for."""

import cv2
import numpy as np
import pytest

from core.image import ImageError
from core.sequence import ImageSequence


@pytest.fixture
def footage(tmp_path):
    """Two views of three textured 60x80 frames as PNG files: paths[view][frame]."""
    rng = np.random.default_rng(3)
    paths = []
    for c in range(2):
        paths.append([])
        for f in range(3):
            p = tmp_path / f"view{c}_{f:02d}.png"
            cv2.imwrite(str(p), rng.integers(0, 256, (60, 80, 3), dtype=np.uint8))
            paths[-1].append(p)
    return paths


def test_a_frame_read_ahead_is_the_frame_read_when_asked(footage):
    ahead, plain = (ImageSequence(footage, 3, highpass=4.0) for _ in range(2))
    ahead.read_ahead(1)
    for c in range(2):
        np.testing.assert_array_equal(ahead.grey(c, 1), plain.grey(c, 1))
        np.testing.assert_array_equal(ahead.colour(c, 1), cv2.imread(str(footage[c][1])))
        np.testing.assert_array_equal(plain.peek(c, 1)[1], ahead.colour(c, 1))
        for a, b in zip(ahead.pyramid(c, 1), plain.pyramid(c, 1), strict=True):
            np.testing.assert_array_equal(a.stack, b.stack)
            assert a.scale == b.scale


def test_a_frame_read_ahead_survives_its_file_and_the_cache_trim(footage):
    seq = ImageSequence(footage, 2)
    seq.read_ahead(2)
    seq._ahead[2].result()  # read: the files are no longer needed
    for c in range(2):
        footage[c][2].unlink()
    seq.keep_only(set())
    assert seq.pyramid(1, 2)[1].shape == (30, 40)


def test_an_unreadable_frame_read_ahead_fails_when_asked_for_naming_its_file(footage):
    footage[1][2].write_bytes(b"not a png")
    seq = ImageSequence(footage, 2)
    seq.read_ahead(2)  # no error yet: the frame may never be asked for
    seq.pyramid(0, 1)
    with pytest.raises(ImageError, match="view1_02.png"):
        seq.pyramid(0, 2)


def test_a_movie_read_from_two_threads_gives_each_its_own_frame(footage, tmp_path):
    """The read-ahead thread and the tracker's thread share one decoder: each seek must stay
    with its read (without the decoder's lock, frames came back corrupt or from elsewhere)."""
    from concurrent.futures import ThreadPoolExecutor

    from core.video import VideoFrames

    movie = tmp_path / "view0.avi"
    writer = cv2.VideoWriter(str(movie), cv2.VideoWriter_fourcc(*"MJPG"), 30, (80, 60))
    for p in footage[0]:
        writer.write(cv2.imread(str(p)))
    writer.release()
    video = VideoFrames(movie)
    once = [video[i] for i in range(3)]
    order = [2, 0, 1, 1, 2, 0] * 20
    with ThreadPoolExecutor(2) as pool:
        got = list(pool.map(lambda i: (i, video[i]), order))
    for i, frame in got:
        np.testing.assert_array_equal(frame, once[i])


def test_a_movie_read_out_of_order_gives_the_frames_decoded_in_order(tmp_path):
    """Jumps back, short jumps forward (decoded through) and a long one (sought) each give
    the frame a plain decode from the start gives there."""
    from core.video import DECODE_AHEAD, VideoFrames

    n = DECODE_AHEAD + 20
    movie = tmp_path / "count.avi"
    writer = cv2.VideoWriter(str(movie), cv2.VideoWriter_fourcc(*"MJPG"), 30, (64, 48))
    rng = np.random.default_rng(7)
    for _ in range(n):
        writer.write(rng.integers(0, 256, (48, 64, 3), dtype=np.uint8))
    writer.release()
    video = VideoFrames(movie)
    in_order = [video[i] for i in range(n)]
    again = VideoFrames(movie)
    for i in (0, 3, 4, 9, 2, 5, 5 + DECODE_AHEAD, 1, 2 + DECODE_AHEAD + 1, n - 1, 0):
        np.testing.assert_array_equal(again[i], in_order[i], err_msg=f"frame {i}")


def test_grey_footage_has_no_colour(tmp_path):
    """Grey files, and grey pictures stored as colour (three equal channels), have none."""
    img = np.random.default_rng(4).integers(0, 256, (20, 30), dtype=np.uint8)
    cv2.imwrite(str(tmp_path / "grey.png"), img)
    cv2.imwrite(str(tmp_path / "as_colour.png"), cv2.merge([img] * 3))
    seq = ImageSequence([[tmp_path / "grey.png", tmp_path / "as_colour.png"]], 1)
    assert seq.colour(0, 0) is None and seq.colour(0, 1) is None
    np.testing.assert_allclose(seq.grey(0, 0), seq.grey(0, 1), atol=1e-6)


def test_chroma_pyramids_hold_grey_then_hue_and_grey_footage_stays_grey(footage, tmp_path):
    grey_file = tmp_path / "grey.png"
    cv2.imwrite(str(grey_file), np.full((60, 80), 90, np.uint8))
    seq = ImageSequence([footage[0][:1], [grey_file]], 2, chroma=True)
    colour = seq.pyramid(0, 0)
    assert [lv.channels for lv in colour] == [3, 3]
    plain = ImageSequence(footage, 2).pyramid(0, 0)  # its grey channel and derivatives
    np.testing.assert_array_equal(colour[0].stack[..., ::3], plain[0].stack)
    hue = cv2.cvtColor(cv2.imread(str(footage[0][0])), cv2.COLOR_BGR2YCrCb)[..., 1]
    assert np.corrcoef(colour[0].stack[..., 1].ravel(), hue.ravel())[0, 1] > 0.5
    assert [lv.channels for lv in seq.pyramid(1, 0)] == [1, 1]

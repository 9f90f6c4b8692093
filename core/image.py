"""Grey float images, Gaussian pyramids, gradients and bilinear sampling.

Images are float32 arrays (height, width) with values in [0, 1], or (height, width,
channels) where the tracker reads colour (``with_chroma``); pixel (x, y) is column x,
row y, with integer coordinates at pixel centres. Level l of a pyramid halves the size l
times with ``cv2.pyrDown``, whose pixel i is centred on pixel 2i of the level below: full-
resolution pixel p sits at p / 2**l on level l. Bilinear sampling goes through ``cv2.remap``,
which rounds sample positions to 1/32 pixel.
"""

from __future__ import annotations

import functools
import os
import sys
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from .errors import InputError

# cv2.remap takes maps of at most 32767 columns
_REMAP_COLS = 16384


IMAGE_SUFFIXES = {".png", ".jpg", ".jpeg", ".tif", ".tiff", ".bmp", ".exr", ".webp"}


class ImageError(InputError):
    """An image that cannot be read; the message names the file."""


def load_image(path: str | Path) -> np.ndarray:
    """Read an image file as it is stored: (H, W) or (H, W, C) in BGR(A) order, of its own
    type (uint8, uint16 or float)."""
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise ImageError(f"{path}: cannot read this image (missing, or not an image format)")
    return img


def load_grey(path: str | Path) -> np.ndarray:
    """Read an image file as float32 grey in [0, 1]."""
    return to_grey(load_image(path))


def read_source(source) -> np.ndarray:
    """A frame given as a path (read as stored, ``load_image``) or as an array (itself)."""
    return source if isinstance(source, np.ndarray) else load_image(source)


def grey_and_colour(source) -> tuple[np.ndarray, np.ndarray | None]:
    """A frame (path or array) as float32 grey and uint8 colour (None for grey footage)."""
    img = read_source(source)
    return to_grey(img), to_colour(img)


def check_footage(paths, where: str) -> None:
    """ImageError naming the first of the image files ``paths`` (str or Path; other sources,
    a movie's frames or arrays, are not checked) that cannot be decoded (a JPEG cut short
    among them: the decoder would fill it out with grey), or that differs in size from the
    first, before any is tracked: a file cut short in the middle of a sequence must neither
    stop a run half way nor be tracked as it is, and frames of one view are one camera's
    (cells cropped each its own way are not). The files are decoded on every core (the
    decoder releases the interpreter's lock); its own complaints are kept off the terminal."""
    paths = getattr(paths, "source", paths)  # footage read undistorted: its files
    files = [p for p in paths if isinstance(p, (str, Path))]
    if not files:
        return
    size = first = None
    pool = ThreadPoolExecutor(os.cpu_count() or 1, thread_name_prefix="twist-check")
    with quiet_stderr():
        try:
            shapes = pool.map(_decoded_shape, files)
            for p, shape in zip(files, shapes):
                if shape is None:
                    raise ImageError(f"{p}: cannot read this image ({where}; cut short, or not "
                                     "an image format): replace it, or leave it out of the "
                                     "footage")
                if size is None:
                    size, first = shape, p
                elif shape != size:
                    raise ImageError(
                        f"{where}: its images differ in size ({Path(first).name} is "
                        f"{size[1]}x{size[0]}, {Path(p).name} {shape[1]}x{shape[0]}): "
                        "crop or pad them to one size, lined up as the camera saw them")
        finally:  # the decodes still running finish while the decoder is quiet
            pool.shutdown(cancel_futures=True)


def _decoded_shape(path) -> tuple[int, int] | None:
    """(height, width) of an image file, decoded whole; None if it cannot be, or if it is a
    JPEG cut short (which the decoder fills out with grey, only warning)."""
    try:
        data = Path(path).read_bytes()
    except OSError:
        return None
    if Path(path).suffix.lower() in (".jpg", ".jpeg") and not jpeg_ends(data):
        return None
    img = cv2.imdecode(np.frombuffer(data, np.uint8), cv2.IMREAD_GRAYSCALE)
    return None if img is None else img.shape


def jpeg_ends(data: bytes) -> bool:
    """Whether a JPEG file's segments run through to its end-of-image marker, as they do
    unless the file was cut short (a copy or download stopped part way). Each marker's
    segment is stepped over by its length; after a start of scan, the coded data runs to
    the next marker (0xFF not followed by a stuffed 0x00 or a restart marker). What comes
    after the end (some cameras append data) is not read; data that does not start as a
    JPEG is left to the decoder (True)."""
    if data[:2] != b"\xff\xd8":
        return True
    i, n = 2, len(data)
    while True:
        if i >= n:
            return False  # the data ends before its end marker
        if data[i] != 0xFF:
            return True  # not a marker where one should be: for the decoder to judge
        while i < n and data[i] == 0xFF:  # fill bytes before a marker
            i += 1
        if i >= n:
            return False
        marker, i = data[i], i + 1
        if marker == 0xD9:
            return True
        if 0xD0 <= marker <= 0xD7 or marker == 0x01:  # no segment follows
            continue
        if i + 2 > n:
            return False
        i += int.from_bytes(data[i:i + 2], "big")
        if marker == 0xDA:  # coded data up to the next marker
            while True:
                i = data.find(b"\xff", i)
                if i < 0 or i + 1 >= n:
                    return False
                if data[i + 1] != 0x00 and not 0xD0 <= data[i + 1] <= 0xD7:
                    break
                i += 2


class quiet_stderr:
    """Standard error at the file-descriptor level sent nowhere (libpng and libjpeg write to
    it directly); put back on leaving, an error or not."""

    def __enter__(self):
        sys.stderr.flush()
        self._saved = os.dup(2)
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, 2)
        os.close(devnull)

    def __exit__(self, *exc):
        os.dup2(self._saved, 2)
        os.close(self._saved)


def to_float(img: np.ndarray) -> np.ndarray:
    """uint8/uint16/float image (H, W[, C]) in BGR(A) order to float32 in [0, 1], grey (H, W)
    or BGR (H, W, 3) (alpha dropped)."""
    if img.dtype == np.uint8:
        img = img.astype(np.float32) / 255
    elif img.dtype == np.uint16:
        img = img.astype(np.float32) / 65535
    else:
        img = img.astype(np.float32)
    if img.ndim == 3 and img.shape[2] == 1:
        img = img[..., 0]
    return np.ascontiguousarray(img[..., :3] if img.ndim == 3 else img)


def to_uint8(img: np.ndarray) -> np.ndarray:
    """A float image in [0, 1] as 8 bits, rounded to the nearest (beyond the range clipped)."""
    return np.clip(img * 255 + 0.5, 0, 255).astype(np.uint8)


def to_grey(img: np.ndarray) -> np.ndarray:
    """uint8/uint16/float image (H, W[, C]) in BGR(A) order to float32 grey in [0, 1]."""
    img = to_float(img)
    return cv2.cvtColor(img, cv2.COLOR_BGR2GRAY) if img.ndim == 3 else img


def to_colour(img: np.ndarray) -> np.ndarray | None:
    """uint8/uint16/float image (H, W[, C]) in BGR(A) order to uint8 BGR (H, W, 3); None for
    a grey image (one channel, or three equal ones: a grey picture stored as colour)."""
    if img.ndim != 3 or img.shape[2] < 3:
        return None
    img = img[..., :3]
    if img.dtype == np.uint16:
        img = (img >> 8).astype(np.uint8)
    elif img.dtype != np.uint8:
        img = to_uint8(img)
    if np.array_equal(img[..., 0], img[..., 1]) and np.array_equal(img[..., 1], img[..., 2]):
        return None
    return np.ascontiguousarray(img)


def with_chroma(grey: np.ndarray, colour: np.ndarray) -> np.ndarray:
    """The grey image (H, W) and the two chroma channels of its uint8 BGR colour (H, W, 3)
    stacked (H, W, 3), float32: grey, then OpenCV's Cr and Cb (0.713 (R - Y) and
    0.564 (B - Y), each about 0.5 for a grey pixel), so that a body and what lies behind it
    that differ in hue but not in brightness differ in the image the tracker reads."""
    ycrcb = cv2.cvtColor(colour.astype(np.float32) / 255, cv2.COLOR_BGR2YCrCb)
    ycrcb[..., 0] = grey  # the luma's place taken in place: a fifth of a new stack's time
    return ycrcb


@dataclass
class Level:
    """One pyramid level: the image's C channels, then their x derivatives, then their y
    derivatives, stacked (rows, cols, 3 C), float32. A level built over a window of the
    image holds the stack there alone: its (rows, cols) start at level pixel ``origin`` (x,
    y) of the level's whole ``size`` (H, W), and ``whole`` makes it over the whole level
    when a read falls outside (``holding``; reading the frame again)."""

    stack: np.ndarray
    scale: float  # full-resolution pixels per level pixel
    origin: tuple[int, int] = (0, 0)
    size: tuple[int, int] | None = None  # the whole level's (H, W); None: the stack's
    whole: Callable[[], np.ndarray] | None = None  # the stack over the whole level

    @property
    def shape(self) -> tuple[int, int]:
        """The whole level's (H, W)."""
        return self.size if self.size is not None else self.stack.shape[:2]

    @property
    def channels(self) -> int:
        return self.stack.shape[2] // 3

    def holding(self, x: np.ndarray, y: np.ndarray, reach: int) -> Level:
        """This level, widened to the whole level first if the stack lacks a pixel within
        ``reach`` (0-2) pixels right of and below level pixels (x, y) (floats or ints)
        that lie in the level; the edges of the level itself are the stack's own."""
        if self.whole is None or not len(x):
            return self
        H, W = self.shape
        (x0, y0), (h, w) = self.origin, self.stack.shape[:2]
        inside = (x >= 0) & (x <= W - 1) & (y >= 0) & (y <= H - 1)
        fx, fy = np.floor(x[inside]) - x0, np.floor(y[inside]) - y0
        last_x = w - 1 if x0 + w == W else w - 1 - reach
        last_y = h - 1 if y0 + h == H else h - 1 - reach
        if len(fx) and (fx.min() < 0 or fy.min() < 0 or fx.max() > last_x
                        or fy.max() > last_y):
            self.stack, self.origin, self.size, self.whole = self.whole(), (0, 0), None, None
        return self

    def values(self, pixels: np.ndarray, derivatives: bool = False) -> np.ndarray:
        """The channels' values (N, C) at integer level pixels (N, 2) = (x, y) in the level;
        with ``derivatives``, (N, 3 C): then their x and y derivatives per level pixel."""
        self.holding(pixels[:, 0], pixels[:, 1], 0)
        x0, y0 = self.origin
        upto = 3 * self.channels if derivatives else self.channels
        return self.stack[pixels[:, 1] - y0, pixels[:, 0] - x0, :upto]


def _blur_reach(sigma: float) -> int:
    """Pixels each side that OpenCV's Gaussian blur of ``sigma`` reads in a float image (its
    kernel 8 sigma + 1 wide, rounded, odd); 0 for no blur."""
    return (round(sigma * 8 + 1) | 1) // 2 if sigma > 0 else 0


def stack_reach(blur: float, highpass: float) -> int:
    """Level pixels round a pixel that its stack entry (``_stack``) reads of the level's
    image: the blur's, the shading filter's and the gradient's one (20 at ``pyramid``'s
    defaults and the tracker's highpass of 4)."""
    return _blur_reach(blur) + _blur_reach(highpass) + 1


def _stack(cur: np.ndarray, blur: float, highpass: float) -> np.ndarray:
    """A level's image (rows, cols[, C]) smoothed and filtered (``pyramid``), with its x and y
    derivatives, stacked (rows, cols, 3 C)."""
    sm = cv2.GaussianBlur(cur, (0, 0), blur) if blur > 0 else cur
    if highpass > 0:
        sm = sm - cv2.GaussianBlur(sm, (0, 0), highpass)
    gx = cv2.Sobel(sm, cv2.CV_32F, 1, 0, ksize=3, scale=1 / 8)
    gy = cv2.Sobel(sm, cv2.CV_32F, 0, 1, ksize=3, scale=1 / 8)
    # OpenCV's merge: numpy's dstack took 7 times as long on a colour level
    return cv2.merge([sm, gx, gy])


def _whole_stack(image: Callable[[], np.ndarray], level: int, blur: float, highpass: float
                 ) -> np.ndarray:
    """Level ``level``'s stack over the whole of ``image()`` (``pyramid``'s own numbers)."""
    cur = image()
    for _ in range(level):
        cur = cv2.pyrDown(cur)
    return _stack(cur, blur, highpass)


def pyramid(img: np.ndarray, levels: int, blur: float = 0.8, highpass: float = 0.0,
            window: tuple[int, int, int, int] | None = None,
            again: Callable[[], np.ndarray] | None = None) -> list[Level]:
    """Gaussian pyramid with derivatives of a grey image (H, W) or a stack of channels
    (H, W, C), finest level first; each level lightly pre-smoothed
    (sigma ``blur`` level pixels) so that gradients see past the sensor noise, and, when
    ``highpass`` > 0, stripped of its local mean over that sigma (level pixels) so that slow
    shading changes across a turning limb do not read as motion. With ``window`` (x0, y0,
    x1, y1, full-resolution pixels), each level's stack is made over that window only (each
    level's image itself is the whole image's, halved from it), the same numbers there as
    over the whole level: the filters read ``stack_reach`` level pixels round each one.
    ``again`` gives ``img`` once more when a level is widened (``Level.whole``; None: the
    levels keep ``img``)."""
    reach = stack_reach(blur, highpass)
    out = []
    cur = img
    for lv in range(levels):
        if window is None:
            out.append(Level(_stack(cur, blur, highpass), float(2**lv)))
        else:
            H, W = cur.shape[:2]
            x0, y0 = (max(0, int(np.floor(v / 2**lv))) for v in window[:2])
            x1, y1 = min(W, int(np.ceil(window[2] / 2**lv)) + 1), \
                min(H, int(np.ceil(window[3] / 2**lv)) + 1)
            # the filters read ``reach`` round every pixel: a border of it, cut off after
            bx0, by0 = max(0, x0 - reach), max(0, y0 - reach)
            bx1, by1 = min(W, x1 + reach), min(H, y1 + reach)
            part = _stack(cur[by0:by1, bx0:bx1], blur, highpass)
            out.append(Level(np.ascontiguousarray(part[y0 - by0:y1 - by0, x0 - bx0:x1 - bx0]),
                             float(2**lv), (x0, y0), (H, W),
                             functools.partial(_whole_stack, again or (lambda: img), lv, blur,
                                               highpass)))
        if lv + 1 < levels:
            cur = cv2.pyrDown(cur)
    return out


def true_pixels(mask: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rows and columns of a 2-D mask's true pixels in row-major order: ``np.nonzero``'s,
    from the flat indices (numpy's 2-D ``nonzero`` takes several times as long)."""
    return np.divmod(np.flatnonzero(mask), mask.shape[1])


def to_level(pixels: np.ndarray, level: Level) -> np.ndarray:
    """Full-resolution pixel coordinates (..., 2) to the level's coordinates."""
    return pixels / level.scale


def sample(level: Level, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Bilinear samples (N, 3 C) = (I, dI/dx, dI/dy) of each of the level's C channels (the
    channels' values, then their x derivatives, then their y derivatives) at
    full-resolution pixels (N, 2), with the derivatives per full-resolution pixel, and a
    mask of points inside the image."""
    p = to_level(pixels, level).astype(np.float32)
    N = len(p)
    H, W = level.shape
    inside = (p[:, 0] >= 0) & (p[:, 0] <= W - 1) & (p[:, 1] >= 0) & (p[:, 1] <= H - 1)
    C = level.channels
    if N == 0:
        return np.zeros((0, 3 * C), np.float32), inside
    level.holding(p[:, 0], p[:, 1], 2)  # a sample reads the next pixel too (and its weight
    # is rounded, so a little more)
    if level.origin != (0, 0):  # exact: an integer off a float under 2^24 that exceeds it
        p = p - np.array(level.origin, np.float32)
    cols = min(N, _REMAP_COLS)
    rows = -(-N // cols)
    maps = np.zeros((rows * cols, 2), np.float32)  # remap takes a 2-D map; pad the tail
    maps[:N] = p
    vals = cv2.remap(level.stack, maps.reshape(rows, cols, 2), None, cv2.INTER_LINEAR,
                     borderMode=cv2.BORDER_REPLICATE)
    # per full-resolution pixel: the scale is a power of two, so multiplying by its inverse
    # is exact
    per_pixel = np.repeat(np.array([1.0, 1 / level.scale, 1 / level.scale], np.float32), C)
    return vals.reshape(-1, 3 * C)[:N] * per_pixel, inside

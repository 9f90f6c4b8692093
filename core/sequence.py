"""Every view's frames, read on demand and kept while they are needed; the next frame is
read ahead on a worker thread while the current one is tracked.

Reading a frame (decoding the file, building its pyramid) is OpenCV work that releases the
interpreter's lock, so it runs beside the tracker's own on the machine's other core. A frame
read ahead gives the same arrays as one read when asked for, and a file that cannot be read
raises its ``ImageError`` when its frame is asked for, not when it is read ahead.
"""

from __future__ import annotations

from collections.abc import Sequence
from concurrent.futures import Future, ThreadPoolExecutor

import numpy as np

from . import image as imagelib


class ImageSequence:
    """``images[view][frame]`` is a path or an array; grey images are float32 (H, W) in
    [0, 1], colour ones uint8 BGR (H, W, 3) (None for grey footage), pyramids finest level
    first (``core.image.pyramid``), ``levels[view]`` levels each (``levels`` given as one
    number for every view), of the grey image, or with ``chroma`` of a colour frame's grey
    and chroma channels (``core.image.with_chroma``)."""

    def __init__(self, images: Sequence[Sequence], levels: int, highpass: float = 0.0,
                 chroma: bool = False):
        self.images = images
        self.levels = [levels] * len(images)
        self.highpass = highpass
        self.chroma = chroma
        self._pyramids: dict[tuple[int, int], list[imagelib.Level]] = {}  # (view, frame)
        self._grey: dict[tuple[int, int], np.ndarray] = {}
        self._colour: dict[tuple[int, int], np.ndarray | None] = {}
        self._ahead: dict[int, Future] = {}  # frame -> per view (grey, colour, pyramid)
        self._reader = ThreadPoolExecutor(max_workers=1, thread_name_prefix="twist-read")

    @property
    def n_views(self) -> int:
        return len(self.images)

    def n_frames(self) -> int:
        return min(len(v) for v in self.images)

    def pyramid(self, view: int, frame: int) -> list[imagelib.Level]:
        key = (view, frame)
        if key not in self._pyramids:
            self._collect(frame)
        if key not in self._pyramids:
            self._pyramids[key] = self._build(view, self.grey(view, frame),
                                              self.colour(view, frame))
        return self._pyramids[key]

    def grey(self, view: int, frame: int) -> np.ndarray:
        """The full-resolution grey image, unfiltered."""
        key = (view, frame)
        if key not in self._grey:
            self._collect(frame)
        if key not in self._grey:
            self._grey[key], self._colour[key] = self._read(view, frame)
        return self._grey[key]

    def colour(self, view: int, frame: int) -> np.ndarray | None:
        """The full-resolution colour image, None for grey footage."""
        self.grey(view, frame)
        return self._colour[view, frame]

    def peek(self, view: int, frame: int) -> tuple[np.ndarray, np.ndarray | None]:
        """``grey`` and ``colour``, without keeping them for later (a glance at a frame the
        run may not reach for a long time)."""
        key = (view, frame)
        return (self._grey[key], self._colour[key]) if key in self._grey else \
            self._read(view, frame)

    def set_levels(self, levels: Sequence[int]) -> None:
        """Build each view's pyramids with ``levels[view]`` levels from now on; those built
        already are dropped."""
        if list(levels) == self.levels:
            return
        for frame in list(self._ahead):
            self._collect(frame)  # a reader still running would build the old number
        self._pyramids.clear()
        self.levels = list(levels)

    def read_ahead(self, frame: int, windows: Sequence | None = None) -> None:
        """Start reading every view's ``frame`` and building its pyramids in the background;
        ``windows``: per view, the full-resolution box (x0, y0, x1, y1) where the body is
        expected, or None (the pyramids' stacks are made there alone, ``image.pyramid``,
        and over the whole image when a read falls outside it)."""
        if frame in self._ahead or all((c, frame) in self._pyramids
                                       for c in range(self.n_views)):
            return
        windows = list(windows) if windows is not None else [None] * self.n_views
        self._ahead[frame] = self._reader.submit(
            lambda: [(g, rgb, self._build(c, g, rgb, frame, windows[c])) for c, (g, rgb) in
                     ((c, self._read(c, frame)) for c in range(self.n_views))])

    def keep_only(self, keys: set[tuple[int, int]]) -> None:
        """Forget every (view, frame) not in ``keys``; frames being read ahead stay."""
        for cache in (self._pyramids, self._grey, self._colour):
            for k in list(cache):
                if k not in keys:
                    del cache[k]

    def _collect(self, frame: int) -> None:
        """Take a frame read ahead into the caches (waiting for it if need be)."""
        if frame not in self._ahead:
            return
        for c, (grey, rgb, pyr) in enumerate(self._ahead.pop(frame).result()):
            if (c, frame) not in self._grey:
                self._grey[c, frame], self._colour[c, frame] = grey, rgb
            self._pyramids.setdefault((c, frame), pyr)

    def _read(self, view: int, frame: int) -> tuple[np.ndarray, np.ndarray | None]:
        return imagelib.grey_and_colour(self.images[view][frame])

    def _build(self, view: int, grey: np.ndarray, colour: np.ndarray | None,
               frame: int | None = None, window: tuple | None = None
               ) -> list[imagelib.Level]:
        """The pyramid of a frame's (grey, colour); over ``window`` alone (``image.pyramid``),
        the frame read again from its file when a level is widened."""
        img = self._image(grey, colour)
        again = None if window is None else lambda: self._image(*self._read(view, frame))
        return imagelib.pyramid(img, self.levels[view], highpass=self.highpass, window=window,
                                again=again)

    def _image(self, grey: np.ndarray, colour: np.ndarray | None) -> np.ndarray:
        """What the pyramids are made of: the grey image, or its stack with the chroma."""
        return grey if colour is None or not self.chroma else imagelib.with_chroma(grey, colour)

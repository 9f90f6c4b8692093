"""A movie file as a sequence of frames, decoded on demand with OpenCV.

``VideoFrames(path)[i]`` is frame i (0-based) as an array (height, width, 3) in BGR order, the
same as ``cv2.imread`` gives for an image, so the tracker takes a movie wherever it takes a list
of image files. Reading forward is sequential decoding; a jump back, or far forward, seeks. A
seek decodes again from the keyframe before the frame, which in a compressed movie may be
hundreds of frames back, so a short jump forward (the backdrop's glance at frames spread over
the clip) decodes the frames in between instead. One decoder serves one reader at a time: the
tracker reads the next frame ahead on a thread of its own.
"""

from __future__ import annotations

import threading
from pathlib import Path

import cv2
import numpy as np

from .image import ImageError

VIDEO_SUFFIXES = {".mp4", ".mov", ".avi", ".mkv", ".m4v", ".webm", ".mpg", ".mpeg"}
DECODE_AHEAD = 64  # frames: a jump forward this short decodes the frames between, not seeks


def is_video(path: str | Path) -> bool:
    return Path(path).suffix.lower() in VIDEO_SUFFIXES


class VideoFrames:
    """The frames of one movie file; ``len`` is the frame count the file declares."""

    def __init__(self, path: str | Path):
        self.path = Path(path)
        self._cap = cv2.VideoCapture(str(self.path))
        if not self._cap.isOpened():
            raise ImageError(f"{self.path}: cannot open this movie (missing, or a format "
                             "OpenCV cannot decode; convert it to MP4 or an image sequence)")
        self._count = int(self._cap.get(cv2.CAP_PROP_FRAME_COUNT))
        self._next = 0
        self._lock = threading.Lock()  # a seek and its read go together

    def __len__(self) -> int:
        return self._count

    def __getitem__(self, i: int) -> np.ndarray:
        if not 0 <= i < self._count:
            raise IndexError(f"{self.path}: frame {i} is outside 0..{self._count - 1}")
        with self._lock:
            if i != self._next and not self._decode_to(i):
                self._cap.set(cv2.CAP_PROP_POS_FRAMES, i)
            ok, frame = self._cap.read()
            self._next = i + 1 if ok else -1
        if not ok:
            raise ImageError(f"{self.path}: frame {i} cannot be decoded")
        return frame

    def _decode_to(self, i: int) -> bool:
        """Decode forward to frame ``i`` where it lies at most ``DECODE_AHEAD`` frames past
        the next one; False where it does not (or the file ends first): then seek."""
        if self._next < 0 or not 0 < i - self._next <= DECODE_AHEAD:
            return False
        while self._next < i:
            if not self._cap.grab():
                self._next = -1
                return False
            self._next += 1
        return True

    def select(self, indices: list[int]) -> Selection:
        """These frames, in this order, as a sequence of their own."""
        return Selection(self, list(indices))


class Selection:
    """Some frames of a movie, in a given order (the tracker's order), decoded on demand."""

    def __init__(self, video: VideoFrames, indices: list[int]):
        self.video, self.indices = video, indices

    def __len__(self) -> int:
        return len(self.indices)

    def __getitem__(self, k: int) -> np.ndarray:
        return self.video[self.indices[k]]

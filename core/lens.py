"""Lens distortion, OpenCV's model: footage undistorted as it is read, points either way.

A pinhole view's footage filmed through a distorting lens (``dist`` = OpenCV's k1, k2, p1,
p2[, k3, ...]) is tracked undistorted: every frame is remapped to what the ideal pinhole K
would have seen, on the same pixel grid, so the tracker's pinhole needs no distortion. Points
given on the footage as filmed (clicks, reference landmarks) go through ``undistort_points``;
tracked points go back through ``distort_points``. Pixels: x right, y down, origin at the
top-left pixel's centre.
"""

from __future__ import annotations

from collections.abc import Sequence

import cv2
import numpy as np

from . import image as imagelib


class Undistorted(Sequence):
    """A view's frames (image paths, arrays or a movie's frames) read undistorted: item i is
    frame i as the ideal pinhole K sees it, a float32 image in [0, 1] with the frame's own
    channels (grey (H, W), or BGR (H, W, 3)), on the frames' own pixel grid or on one
    ``size`` = (width, height) (the calibration's, where the footage was cropped)."""

    def __init__(self, source: Sequence, K: np.ndarray, dist: np.ndarray,
                 size: tuple[int, int] | None = None):
        self.source = source  # the frames as filmed
        self.K = np.asarray(K, dtype=float)
        self.dist = np.asarray(dist, dtype=float)
        self.size = size
        self._maps: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = {}  # by (H, W)

    def __len__(self) -> int:
        return len(self.source)

    def __getitem__(self, i):
        if isinstance(i, slice):
            return [self[k] for k in range(*i.indices(len(self)))]
        return self.remap(imagelib.to_float(imagelib.read_source(self.source[i])))

    def remap(self, img: np.ndarray) -> np.ndarray:
        """An image (grey or colour) of the footage as filmed, undistorted."""
        shape = img.shape[:2]
        if shape not in self._maps:
            size = self.size or (shape[1], shape[0])
            self._maps[shape] = cv2.initUndistortRectifyMap(
                self.K, self.dist, None, self.K, size, cv2.CV_32FC1)
        return cv2.remap(img, *self._maps[shape], cv2.INTER_LINEAR,
                         borderMode=cv2.BORDER_REPLICATE)


def undistort_points(pixels: np.ndarray, K: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """Where the ideal pinhole K sees the points (N, 2) that the lens put at ``pixels``."""
    pts = np.asarray(pixels, dtype=np.float64).reshape(-1, 1, 2)
    out = cv2.undistortPointsIter(pts, K, dist, None, K, (
        cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 50, 1e-10))
    return out.reshape(np.shape(pixels))


def distort_points(pixels: np.ndarray, K: np.ndarray, dist: np.ndarray) -> np.ndarray:
    """Where the lens puts the points (N, 2) that the ideal pinhole K sees at ``pixels``."""
    pts = np.asarray(pixels, dtype=np.float64).reshape(-1, 2)
    rays = np.concatenate([pts, np.ones((len(pts), 1))], 1) @ np.linalg.inv(K).T
    out, _ = cv2.projectPoints(rays, np.zeros(3), np.zeros(3), K, dist)
    return out.reshape(np.shape(pixels))

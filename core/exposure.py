"""A frame's exposure against a still scene: the gain a camera's automatic exposure puts on
every pixel.

A camera that sets its exposure as the light changes (a phone's, unless locked) multiplies
each frame's brightness by a gain, the same over the frame. Against a still backdrop the
gain shows as the ratio of a frame's pixels to the backdrop's where the scene is the same:
most of the frame. Their log ratios pile up at the log gain; the body, a shadow or a passer-by
scatter theirs, so the gain is read from the pixels near the pile's peak (the ratio of their
sums, which the rounding of 8-bit footage does not hold at 1 as a median of ratios does),
not from all (whose mean or median a body filling half the frame would pull). Dark pixels
(ratios all rounding) and clipped ones (a gain clipped away) are not read.
"""

from __future__ import annotations

import numpy as np

STRIDE = 4  # rows and columns between the pixels read: a ratio's peak needs no more
DARK = 0.05  # pixels darker than this (0-1) in the frame or the backdrop are not read
CLIPPED = 0.98  # nor pixels this bright, which a brighter exposure may have clipped
BIN = 0.01  # the histogram's bin in log gain (1 %)
REACH = 1.2  # log gains read: a factor of e^1.2, 3.3, either way
SPREAD = 0.05  # pixels whose log ratio is this near the peak make the gain (their sums' ratio)
MIN_PIXELS = 200  # fewer pixels to read than this and the gain is taken as 1
# gains this near 1 are read as 1: footage of 8 bits reads a change of 1 % as none on most
# pixels, the shading filter and the noise scales take in a few per cent, and footage of
# one exposure is tracked as it was
TOLERANCE = 0.03


def exposure_gain(frame: np.ndarray, backdrop: np.ndarray, usable: np.ndarray | None = None
                  ) -> float:
    """The gain g with ``frame`` = g ``backdrop`` where the scene is the same: grey float
    images (H, W) in [0, 1] of one size; ``usable`` (H, W): the backdrop's pixels that show
    the scene (None: all). 1 where too few pixels can be read, or the gain is within
    ``TOLERANCE`` of 1."""
    k = STRIDE
    f, b = frame[::k, ::k], backdrop[::k, ::k]
    read = (f > DARK) & (b > DARK) & (f < CLIPPED) & (b < CLIPPED)
    if usable is not None:
        read &= usable[::k, ::k]
    if np.count_nonzero(read) < MIN_PIXELS:
        return 1.0
    f, b = f[read], b[read]
    ratio = np.log(f / b)
    counts, edges = np.histogram(ratio, bins=int(round(2 * REACH / BIN)), range=(-REACH, REACH))
    if not counts.any():
        return 1.0
    smooth = np.convolve(counts, np.ones(5), mode="same")  # a pile split across two bins
    top = int(np.argmax(smooth))
    peak = 0.5 * (edges[top] + edges[top + 1])
    near = np.abs(ratio - peak) <= SPREAD
    gain = float(np.sum(f[near]) / np.sum(b[near]))
    return 1.0 if abs(np.log(gain)) < TOLERANCE else gain

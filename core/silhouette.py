"""The body's silhouette against a still backdrop: a cue whose basin is as wide as a limb is
long, where brightness constancy only reaches a blob's width.

Each view's backdrop is the key frame with the body taken out (see ``Backdrop``); a pixel
is foreground where it differs from the backdrop by more than a threshold set from the
image's own noise (the cameras must stand still). Two chamfer terms compare the
blobs' projection (a label map) with the foreground, each in both directions:
foreground pixels no blob covers pull the nearest covered pixel toward them, and covered
pixels off the foreground are pulled to the nearest foreground pixel. Distances are in
level pixels, capped so that clutter far from the body cannot pull.
"""

from __future__ import annotations

from collections.abc import Iterable
from dataclasses import dataclass

import cv2
import numpy as np

MIN_CONTRAST = 0.06  # smallest brightness difference from the backdrop called foreground
UNCOVERED_WEIGHT = 0.3  # of foreground no blob covers: parts the blobs lack (hands, feet)
SLACK = 1.0  # level pixels of mismatch forgiven
BODY_MARGIN = 6  # full-resolution pixels the key frame's body is painted out beyond its blobs
INPAINT_RADIUS = 6  # pixels around a painted-out pixel its value is drawn from (the cost
# grows with its square: at the margin of a body 800 pixels tall, 24, it took 2 s a view)
STILL_AREA_RATIO = 4.0  # a backdrop holds while frames' foreground stays under this x body
BACKDROP_FRAMES = 12  # frames spread over the footage that show the backdrop behind the body


class Backdrop:
    """One view's still backdrop and the foreground of any frame against it.

    It starts as the key frame with the body (its blobs' pixels, widened by a margin for the
    blobs' own error) painted out from around it; as frames are tracked, ``learn`` puts in
    what a tracked frame shows where the body has moved off. (A temporal median of the
    footage would keep in the backdrop a body that stays in one place, walking toward an
    end-on camera.) ``still`` says whether the backdrop holds: False when ``frames`` of the
    footage differ from it over far more than the body's area (a moving camera, changing
    light)."""

    def __init__(self, grey: np.ndarray, body: np.ndarray, frames: Iterable[np.ndarray] = (),
                 margin: int = BODY_MARGIN):
        grey = np.asarray(grey, np.float32)
        self.margin = margin
        self.unseen = self._widen(body)  # pixels whose backdrop is only painted in
        img8 = np.clip(grey * 255 + 0.5, 0, 255).astype(np.uint8)
        self.image = cv2.inpaint(img8, self.unseen.astype(np.uint8), INPAINT_RADIUS,
                                 cv2.INPAINT_TELEA).astype(np.float32) / 255
        noise = np.abs(grey - cv2.medianBlur(grey, 3))[~self.unseen]
        self.threshold = max(MIN_CONTRAST, 6 * 1.4826 * float(np.median(noise)))
        area = [self.foreground(np.asarray(f, np.float32)).sum() for f in frames]
        self.still = not area or float(np.median(area)) <= STILL_AREA_RATIO * max(
            int(body.sum()), 1)

    def _widen(self, body: np.ndarray) -> np.ndarray:
        k = np.ones((2 * self.margin + 1,) * 2, np.uint8)
        return cv2.dilate(body.astype(np.uint8), k) > 0

    def learn(self, grey: np.ndarray, body: np.ndarray) -> None:
        """Take the backdrop from a tracked frame wherever it is still unseen and that frame's
        body (its blobs' pixels) is not."""
        if grey.shape != self.image.shape:
            return
        seen = self.unseen & ~self._widen(body)
        self.image[seen] = grey[seen]
        self.unseen &= ~seen

    def foreground(self, grey: np.ndarray) -> np.ndarray:
        """Foreground of a full-resolution grey frame, as 0/1 floats (H, W): pixels off the
        backdrop, specks removed. Holes are kept: the gap between an arm and the trunk is
        one. A frame a few pixels larger or smaller than the backdrop is compared where they
        overlap (top-left corners together); the rest is backdrop."""
        h, w = (min(a, b) for a, b in zip(grey.shape, self.image.shape))
        fg = np.zeros(grey.shape, np.float32)
        fg[:h, :w] = np.abs(grey[:h, :w] - self.image[:h, :w]) > self.threshold
        return cv2.morphologyEx(fg, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))


def at_level(fg: np.ndarray, level: int) -> np.ndarray:
    """A full-resolution 0/1 foreground as a boolean mask on pyramid level ``level``, made
    the way the image pyramid is (``cv2.pyrDown``: level pixel i centred on pixel 2i below),
    so that the mask and the level's label maps line up."""
    for _ in range(level):
        fg = cv2.pyrDown(fg)
    return fg > 0.5


@dataclass
class Mismatch:
    """Where a label map and a foreground disagree, in level pixels (x, y)."""

    model: np.ndarray  # (N, 2) covered pixels to move
    target: np.ndarray  # (N, 2) where each should go (its match, less the slack)
    cost: float  # sum of capped squared distances, weighted
    weight: np.ndarray  # (N,) each pair's weight


class NearestPixel:
    """Where the nearest pixel of a mask (H, W) is from any pixel: one distance transform,
    made when first asked and then looked up (a level's foreground, against which every
    candidate pose of the level is costed)."""

    def __init__(self, mask: np.ndarray):
        self.mask = mask
        self._label: np.ndarray | None = None  # per pixel, the rank of its nearest
        self._flat: np.ndarray | None = None  # flat index of each mask pixel, by rank

    def __call__(self, ys: np.ndarray, xs: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Rows and columns of the mask pixels nearest to pixels (ys, xs)."""
        if self._label is None:
            # OpenCV numbers the zero pixels in row-major order: label k is the k-th
            _, self._label = cv2.distanceTransformWithLabels(
                (~self.mask).astype(np.uint8), cv2.DIST_L2, cv2.DIST_MASK_5,
                labelType=cv2.DIST_LABEL_PIXEL)
            self._flat = np.flatnonzero(self.mask)
        return np.divmod(self._flat[self._label[ys, xs] - 1], self.mask.shape[1])


def mismatch(labels: np.ndarray, fg: np.ndarray, cap: float, slack: float = SLACK,
             uncovered_weight: float = UNCOVERED_WEIGHT,
             nearest_fg: NearestPixel | None = None) -> Mismatch:
    """Both chamfer terms between a label map (H, W; -1 where no blob) and a foreground: a
    pixel ``d`` from its match costs (min(d, cap) - slack)^2 if positive, and wants to move
    d - slack toward it (the slack forgives outline noise and the holes a body shows where
    it happens to match the backdrop). Uncovered foreground weighs ``uncovered_weight``:
    it also comes from what the blobs do not model, and pulled the shanks toward the feet.
    ``nearest_fg``: the foreground's ``NearestPixel`` (its mask is ``fg``), to share
    between label maps."""
    covered = labels >= 0
    cost = 0.0
    # uncovered foreground pulls its nearest covered pixel; covered background is pulled to
    # its nearest foreground pixel
    model, target, weight = [], [], []
    nearest_fg = NearestPixel(fg) if nearest_fg is None else nearest_fg
    for src, nearest, move_near, w in ((fg & ~covered, NearestPixel(covered), True,
                                        uncovered_weight),
                                       (covered & ~fg, nearest_fg, False, 1.0)):
        if not src.any() or not nearest.mask.any():
            continue
        ys, xs = np.nonzero(src)
        iy, ix = nearest(ys, xs)
        dist = np.hypot(iy - ys, ix - xs)
        cost += w * float(np.sum(np.maximum(np.minimum(dist, cap) - slack, 0) ** 2))
        keep = (dist <= cap) & (dist > slack)
        near = np.stack([ix[keep], iy[keep]], 1).astype(float)
        here = np.stack([xs[keep], ys[keep]], 1).astype(float)
        m, t = (near, here) if move_near else (here, near)
        model.append(m)
        target.append(m + (t - m) * (1 - slack / dist[keep])[:, None])
        weight.append(np.full(len(m), w))
    if not model:
        return Mismatch(np.zeros((0, 2)), np.zeros((0, 2)), cost, np.zeros(0))
    return Mismatch(np.concatenate(model), np.concatenate(target), cost,
                    np.concatenate(weight))


class SilhouetteCue:
    """One run's silhouette state: each view's backdrop, learned from the key frame the
    first time it is asked for and then from every tracked frame, and the foregrounds of
    the frame being tracked. The tracker says where the body is (its blobs' pixels, full
    resolution); this object knows only images. A view whose camera is known to move, or
    whose footage around the body keeps changing (a camera or light moving unannounced),
    has no backdrop, and a note says so."""

    def __init__(self, seq, moving: Iterable[int] = ()):
        self.seq = seq  # the run's ImageSequence
        self.moving = frozenset(moving)  # views whose camera moves
        self.backdrops: list[Backdrop | None] | None = None  # per view; None: not started
        self._foregrounds: dict[tuple[int, int], np.ndarray] = {}  # (view, frame): full res

    def reset(self) -> None:
        """Forget the backdrops (a new key pose, or a new size of the body's pyramids)."""
        self.backdrops, self._foregrounds = None, {}

    @property
    def started(self) -> bool:
        return self.backdrops is not None

    def start(self, key_frame: int, bodies: list[np.ndarray], margins: list[int]) -> list[str]:
        """Each view's backdrop from the key frame with the body (``bodies``: per view, its
        pixels on the key frame) painted out ``margins`` pixels wide, checked against frames
        spread over the footage; returns the notes on views whose backdrop does not hold."""
        others = np.linspace(0, self.seq.n_frames() - 1, BACKDROP_FRAMES).astype(int)
        self.backdrops, notes = [], []
        for c, (body, margin) in enumerate(zip(bodies, margins)):
            if c in self.moving:
                notes.append(f"view {c + 1}: its camera moves, and the backdrop with it, so "
                             "its silhouette is not used")
                self.backdrops.append(None)
                continue
            backdrop = Backdrop(self.seq.grey(c, key_frame), body, (
                self.seq.peek_grey(c, f) for f in sorted(set(others) - {key_frame})), margin)
            if not backdrop.still:
                notes.append(f"view {c + 1}: the footage around the body changes from frame "
                             "to frame far more than a body's outline (a moving camera or "
                             "light, or a first pose that does not cover the body), so its "
                             "silhouette is not used")
            self.backdrops.append(backdrop if backdrop.still else None)
        return notes

    def has(self, view: int) -> bool:
        """Whether ``view`` has a still backdrop (after ``start``)."""
        return self.backdrops is not None and self.backdrops[view] is not None

    def foreground(self, view: int, frame: int) -> np.ndarray:
        """Full-resolution 0/1 foreground of ``frame`` in ``view`` (one that ``has``); only
        one frame's are kept."""
        if (view, frame) not in self._foregrounds:
            self._foregrounds = {k: v for k, v in self._foregrounds.items() if k[1] == frame}
            self._foregrounds[view, frame] = self.backdrops[view].foreground(
                self.seq.grey(view, frame))
        return self._foregrounds[view, frame]

    def unseen(self, view: int) -> bool:
        """Whether ``view``'s backdrop still has pixels only painted in."""
        return self.has(view) and bool(self.backdrops[view].unseen.any())

    def learn(self, view: int, frame: int, body: np.ndarray) -> None:
        """Let ``view``'s backdrop see what ``frame`` shows away from the body there."""
        self.backdrops[view].learn(self.seq.grey(view, frame), body)

"""The body's silhouette against the backdrop: a cue whose basin is as wide as a limb is
long, where brightness constancy only reaches a blob's width.

Each view's backdrop is the key frame with the body taken out (see ``Backdrop``), or the
clean plate the user gives (the scene without the body); a pixel is foreground where it
differs from the backdrop by more than a threshold set from the image's own noise (the
cameras stand still, or only turn about their centres: ``TurningBackdrop``), in brightness
or, in colour footage from a still camera, in colour (a body as bright as the wall behind
it). In colour footage, a changed pixel whose colour is the backdrop's, darkened or
lightened as a shadow does, is unsure: the body's own cast shadow, or one the key frame
held, on a backdrop whose colour shows it (on a colourless one a shadow cannot be told from
a grey body, and it stays foreground). Two chamfer terms compare the blobs' projection (a
label map) with the foreground, each in both directions: foreground pixels no blob covers
pull the nearest covered pixel toward them, and covered pixels off the foreground are
pulled to the nearest foreground pixel; unsure pixels do neither. Distances are in level
pixels, capped so that clutter far from the body cannot pull. A foreground map holds one
code per pixel: ``BACKDROP``, ``FOREGROUND`` or ``UNSURE`` (a boolean mask is a map with no
unsure pixels).
"""

from __future__ import annotations

import os
from collections import deque
from collections.abc import Iterable, Sequence
from concurrent.futures import ThreadPoolExecutor
from functools import cached_property

import cv2
import numpy as np

from .camera import Camera, Pinhole, turn_homography, turns_in_place
from .exposure import exposure_gain
from .image import to_float, to_uint8, true_pixels

MIN_CONTRAST = 0.06  # smallest brightness difference from the backdrop called foreground
UNCOVERED_WEIGHT = 0.3  # of foreground no blob covers: parts the blobs lack (hands, feet)
SLACK = 1.0  # level pixels of mismatch forgiven
BODY_MARGIN = 6  # full-resolution pixels the key frame's body is painted out beyond its blobs
INPAINT_RADIUS = 6  # pixels around a painted-out pixel its value is drawn from (the cost
# grows with its square: at the margin of a body 800 pixels tall, 24, it took 2 s a view)
STILL_AREA_RATIO = 4.0  # a backdrop holds while frames' foreground stays under this x body
BACKDROP_FRAMES = 12  # frames spread over the footage that show the backdrop behind the body
BACKDROP, FOREGROUND, UNSURE = 0, 1, 2  # a foreground map's codes
SHADOW_DEPTH = 0.3  # the darkest a shadow leaves its backdrop (sunlight's keep the sky's light)
NOISE_STRIDE = 4  # rows and columns between the pixels the colour noise is measured on
TURNING_REACH = 1  # pixels a turning camera's frame may lie off its backdrop (``Backdrop``)
TURNING_SOURCES = 12  # latest tracked frames a turning camera's backdrop is drawn from
SHADOW_CHROMA = 6.0  # colour off the backdrop's, in its median over pixels that stay the same,
# still called the backdrop's own


class Backdrop:
    """One view's still backdrop and the foreground of any frame against it.

    It starts as the key frame with the body (its blobs' pixels, widened by a margin for the
    blobs' own error) painted out from around it; as frames are tracked, ``learn`` puts in
    what a tracked frame shows where the body has moved off. (A temporal median of the
    footage would keep in the backdrop a body that stays in one place, walking toward an
    end-on camera.) ``still`` says whether the backdrop holds: False when ``frames`` of the
    footage differ from it over far more than the body's area (a moving camera, changing
    light)."""

    def __init__(self, grey: np.ndarray, body: np.ndarray,
                 frames: Iterable[tuple[np.ndarray, np.ndarray | None]] = (),
                 margin: int = BODY_MARGIN, colour: np.ndarray | None = None,
                 clean: bool = False, reach: int = 0):
        """``grey`` float (H, W) and ``colour`` uint8 BGR (H, W, 3) or None: the key frame,
        or, ``clean``, a clean plate (the scene without the body: nothing to paint out);
        ``body``: the key frame's body pixels; ``frames``: (grey, colour) of other frames.
        ``reach``: pixels a frame may lie off the backdrop (a turning camera's, brought into
        view by a homography: resampled, and turned by the camera's path as given) -- a pixel
        is foreground only where it is off every backdrop pixel that near."""
        grey = np.asarray(grey, np.float32)
        self.margin, self.reach = margin, reach
        # pixels whose backdrop is only painted in
        self.unseen = np.zeros(body.shape, bool) if clean else self.widen(body)
        self.image, self.colour = grey.copy(), None if colour is None else colour.copy()
        self._colour_half = None  # ``colour`` at ``recoloured``'s resolution, when made
        if self.unseen.any():
            holes = self.unseen.astype(np.uint8)
            img8 = to_uint8(grey)
            self.image = cv2.inpaint(img8, holes, INPAINT_RADIUS,
                                     cv2.INPAINT_TELEA).astype(np.float32) / 255
            if colour is not None:
                self.colour = cv2.inpaint(colour, holes, INPAINT_RADIUS, cv2.INPAINT_TELEA)
        noise = np.abs(grey - cv2.medianBlur(grey, 3))[~self.unseen]
        self.threshold = max(MIN_CONTRAST, 6 * 1.4826 * float(np.median(noise)))
        frames = [(np.asarray(f, np.float32), c) for f, c in frames]
        gains = [self.exposure(f) for f, _ in frames]
        self.chroma_noise = self._chroma_noise(frames, gains)
        area = [np.count_nonzero(self.foreground(f, c, gain=g) == FOREGROUND)
                for (f, c), g in zip(frames, gains)]
        self.still = not area or float(np.median(area)) <= STILL_AREA_RATIO * max(
            int(body.sum()), 1)

    def _chroma_noise(self, frames, gains: list[float]) -> float | None:
        """The median colour distortion (``_chroma``) of frames (grey, colour) against the
        backdrop brought to their exposures ``gains`` over the seen pixels they leave the
        same (every ``NOISE_STRIDE``-th row and column: a median needs no more); None
        without colour frames to measure it."""
        if self.colour is None:
            return None
        k = NOISE_STRIDE
        found = [np.zeros(0)]
        for (grey, c), g in zip(frames, gains):
            if c is not None and c.shape == self.colour.shape:
                same = (np.abs(grey[::k, ::k] - g * self.image[::k, ::k]) <= self.threshold) \
                    & ~self.unseen[::k, ::k]
                found.append(_chroma(c[::k, ::k][same], self.colour[::k, ::k][same])[0])
        found = np.concatenate(found)
        return float(np.median(found)) if len(found) else None

    def widen(self, body: np.ndarray) -> np.ndarray:
        """``body`` (H, W) widened by the backdrop's margin."""
        k = np.ones((2 * self.margin + 1,) * 2, np.uint8)
        return cv2.dilate(body.astype(np.uint8), k) > 0

    def learn(self, grey: np.ndarray, body: np.ndarray, colour: np.ndarray | None = None,
              gain: float | None = None) -> None:
        """Take the backdrop from a tracked frame wherever it is still unseen and that frame's
        body (its blobs' pixels) is not, at the backdrop's own exposure (``gain``: the
        frame's ``exposure``, when already read)."""
        if grey.shape != self.image.shape:
            return
        g = self.exposure(grey) if gain is None else gain
        seen = self.unseen & ~self.widen(body)
        self.image[seen] = grey[seen] / g
        if self.colour is not None and colour is not None:
            self.colour[seen] = np.clip(colour[seen] / g, 0, 255).astype(np.uint8)
            self._colour_half = None
        self.unseen &= ~seen

    def exposure(self, grey: np.ndarray) -> float:
        """A frame's (grey (H, W)) exposure against this backdrop's
        (``exposure.exposure_gain`` over the pixels it has seen), where they overlap."""
        h, w = (min(a, b) for a, b in zip(grey.shape, self.image.shape))
        return exposure_gain(grey[:h, :w], self.image[:h, :w], ~self.unseen[:h, :w])

    @property
    def learning(self) -> bool:
        """Whether some of it is still only painted in (``learn`` has more to take)."""
        return bool(self.unseen.any())

    def foreground(self, grey: np.ndarray, colour: np.ndarray | None = None,
                   against: tuple | None = None, gain: float | None = None) -> np.ndarray:
        """Foreground map (H, W) of a full-resolution frame (grey, and colour or None):
        pixels off the backdrop (brought to the frame's exposure, ``exposure``; a turning
        camera's as it is) in brightness or in colour (``recoloured``; not a turning
        camera's, resampled, whose edges would all be off by a pixel's colour, nor where
        the footage's colour noise reads 0: a grey scene stored in colour, whose colour is
        only rounding, has no noise to set the colour's bar by), specks removed, are
        ``FOREGROUND``, or ``UNSURE`` where their colour is the backdrop's shaded
        (``shaded``). Holes are kept: the gap between an arm and the trunk is one. A frame
        a few pixels larger or smaller than the backdrop is compared where they overlap
        (top-left corners together); the rest is backdrop. ``against``: (grey, colour or
        None, unknown) of the frame's own size to compare with instead of this backdrop's
        image (a turning camera's, brought into the frame's view: ``TurningBackdrop``), its
        unknown pixels ``UNSURE``. ``gain``: the frame's ``exposure``, when already read."""
        image, backdrop_colour, unknown = against or (self.image, self.colour, None)
        h, w = (min(a, b) for a, b in zip(grey.shape, image.shape))
        fg = np.zeros(grey.shape, np.uint8)
        seen, image = grey[:h, :w], image[:h, :w]
        # the backdrop brought to the frame's exposure; a turning camera's is drawn from the
        # latest frames, of exposures near its own, warped (their resampling reads as a
        # gain of a few per cent)
        if against is not None:
            gain = 1.0
        elif gain is None:
            gain = self.exposure(grey)
        image = gain * image
        if self.reach:  # off the range of the backdrop's values that near
            near = np.ones((2 * self.reach + 1,) * 2, np.uint8)
            off = np.maximum(cv2.erode(image, near) - seen, seen - cv2.dilate(image, near))
        else:
            off = np.abs(seen - image)
        fg[:h, :w] = off > self.threshold
        in_colour = self.chroma_noise is not None and colour is not None and \
            backdrop_colour is not None and colour.shape == backdrop_colour.shape
        if in_colour and not self.reach and self.chroma_noise > 0:
            own = against is None and backdrop_colour.shape[:2] == (h, w)
            fg[:h, :w] |= self.recoloured(colour[:h, :w],
                                          None if own else backdrop_colour[:h, :w])
        fg = cv2.morphologyEx(fg, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
        if in_colour:
            # the pixels off the backdrop by their flat indices: take reads their colours
            # several times faster than a 2-D boolean mask
            off_backdrop = np.flatnonzero(fg > 0)
            unsure = np.zeros(fg.shape, np.uint8)
            unsure.ravel()[off_backdrop] = self.shaded(
                colour.reshape(-1, 3).take(off_backdrop, 0),
                gain * backdrop_colour.reshape(-1, 3).take(off_backdrop, 0))
            # specks too: a shadow is a patch, a lone pixel the backdrop's colour is noise
            unsure = cv2.morphologyEx(unsure, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
            fg[unsure > 0] = UNSURE
        if unknown is not None:
            fg[unknown] = UNSURE
        return fg

    @property
    def colour_bar(self) -> float:
        """How far (0-255 units) a colour may lie off every shade of its backdrop colour
        and still be called one: ``SHADOW_CHROMA`` times the footage's colour noise."""
        return SHADOW_CHROMA * self.chroma_noise

    def recoloured(self, seen: np.ndarray, backdrop: np.ndarray | None = None) -> np.ndarray:
        """Which pixels of a frame's colour ``seen`` (H, W, 3) are no shade of their
        ``backdrop`` colour (H, W, 3; None: this backdrop's ``colour``, of the same size):
        off every brightness of it (``_chroma``) by over ``colour_bar``, the shadow test's
        own. A body the backdrop's brightness (a grey figure on a sunlit brick wall: a
        third of its pixels) still differs from it in colour. Judged on 2 x 2 blocks, the
        resolution compressed footage keeps its colour at (4:2:0), and a quarter of the
        work; this backdrop's own blocks are kept until it learns."""
        h, w = seen.shape[:2]
        f = _halved(seen)
        if backdrop is None:
            if self._colour_half is None:
                self._colour_half = _halved(self.colour)
            b = self._colour_half
        else:
            b = _halved(backdrop)
        off = _chroma(f.reshape(-1, 3), b.reshape(-1, 3))[0].reshape(f.shape[:2])
        return cv2.resize((off > self.colour_bar).astype(np.uint8), (w, h),
                          interpolation=cv2.INTER_NEAREST)

    def shaded(self, seen: np.ndarray, backdrop: np.ndarray) -> np.ndarray:
        """Which pixels' colours ``seen`` (N, 3) are their ``backdrop`` colours (N, 3)
        scaled by a shadow falling or lifting (brightness between ``SHADOW_DEPTH`` and its
        inverse), within ``colour_bar`` of them, where that backdrop's colour is told from
        grey at that brightness (else a grey body would pass for its shadow)."""
        off, scale = _chroma(seen, backdrop)
        tell = self.colour_bar
        out = (off <= tell) & (scale >= SHADOW_DEPTH) & (scale <= 1 / SHADOW_DEPTH)
        grey = np.repeat(seen[out].astype(np.float32).mean(1, keepdims=True), 3, 1)
        out[out] = _chroma(grey, backdrop[out])[0] > tell  # only where the rest holds
        return out


class TurningBackdrop:
    """The backdrop of a pinhole camera that turns about its centre (panning or tilting on a
    tripod), for any frame: what the latest tracked frames showed away from their body, then
    the key frame's ``Backdrop``, each brought into that frame's view by the turn's
    homography (``turn_homography``), the nearest in time first. Pixels none of them shows
    (scenery the camera turns onto, or behind a body that has not yet moved off it) are
    unsure. The key frame's backdrop sets the threshold and the shadow test."""

    def __init__(self, key: Backdrop, key_frame: int, cameras: Sequence[Pinhole]):
        """``cameras``: the view's camera on every frame of the footage."""
        self.key, self.key_frame, self.cameras = key, key_frame, cameras
        # (frame, grey, colour or None, pixels hidden by the body), the latest first; grey
        # in 8 bits, as footage is (a quarter of the memory of floats)
        self.sources: deque = deque(maxlen=TURNING_SOURCES)
        self.learning = True  # every tracked frame shows more

    def foreground(self, frame: int, grey: np.ndarray, colour: np.ndarray | None = None
                   ) -> np.ndarray:
        """``Backdrop.foreground`` of ``frame`` against the backdrop as it then looks."""
        return self.key.foreground(grey, colour, self.seen_from(frame, grey.shape))

    def learn(self, frame: int, grey: np.ndarray, body: np.ndarray,
              colour: np.ndarray | None = None) -> None:
        """Keep what tracked ``frame`` shows away from its body (its blobs' pixels)."""
        self.sources.appendleft((frame, to_uint8(grey), colour, self.key.widen(body)))

    def seen_from(self, frame: int, shape: tuple[int, int]) -> tuple:
        """The backdrop in ``frame``'s view: grey (H, W), colour (H, W, 3) or None, and the
        pixels nothing showed (H, W)."""
        image = np.zeros(shape, np.float32)
        colour = None if self.key.colour is None else np.zeros((*shape, 3), np.uint8)
        unknown = np.ones(shape, bool)
        size = (shape[1], shape[0])
        for src, grey, col, hidden in (*self.sources, (self.key_frame, self.key.image,
                                                       self.key.colour, None)):
            H = turn_homography(self.cameras[src], self.cameras[frame])
            shows = np.ones(grey.shape, np.float32) if hidden is None else \
                (~hidden).astype(np.float32)
            # bilinear: 1 only where every pixel a sample reads from shows the backdrop
            take = unknown & (cv2.warpPerspective(shows, H, size) > 0.999)
            if not take.any():
                continue
            ys, xs = np.nonzero(take)
            x0, y0 = xs.min(), ys.min()
            box = (slice(y0, ys.max() + 1), slice(x0, xs.max() + 1))
            M = np.array([[1.0, 0, -x0], [0, 1, -y0], [0, 0, 1]]) @ H
            part = (xs.max() + 1 - x0, ys.max() + 1 - y0)
            here = take[box]
            image[box][here] = to_float(cv2.warpPerspective(grey, M, part)[here])
            if colour is not None and col is not None:
                colour[box][here] = cv2.warpPerspective(col, M, part)[here]
            unknown &= ~take
            if not unknown.any():
                break
        return image, colour, unknown


def _halved(colour: np.ndarray) -> np.ndarray:
    """A colour image (H, W, 3) as float32 means of its 2 x 2 blocks (ceil(H / 2),
    ceil(W / 2), 3)."""
    h, w = colour.shape[:2]
    return cv2.resize(colour.astype(np.float32), ((w + 1) // 2, (h + 1) // 2),
                      interpolation=cv2.INTER_AREA)


def _chroma(seen: np.ndarray, backdrop: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """How far colours ``seen`` (N, 3) are from their ``backdrop`` colours (N, 3) scaled to
    fit them best (a length in 0-255 units), and that scale: a pixel under a shadow is its
    backdrop scaled, with no colour off it."""
    # (3, N): a channel a row, each row contiguous (a transpose's copy would keep the
    # channels interleaved, and every operation below strided)
    f, b = (np.ascontiguousarray(x.T, np.float32) for x in (seen, backdrop))
    scale = (f[0] * b[0] + f[1] * b[1] + f[2] * b[2]) / np.maximum(
        b[0] * b[0] + b[1] * b[1] + b[2] * b[2], 1.0)
    off = f - scale * b
    off *= off
    return np.sqrt(off[0] + off[1] + off[2]), scale


class LevelMaps:
    """A full-resolution foreground map (H, W) on any pyramid level, made the way the image
    pyramid is (``cv2.pyrDown``: level pixel i centred on pixel 2i below), so that the map
    and the level's label maps line up: a level pixel is foreground where most of what it
    covers is, else unsure where most is unsure. The blurred shares of each code are kept
    from one level to the next, so every level of a frame costs one pyramid."""

    def __init__(self, fg: np.ndarray):
        # per code, its share of each level's pixels (finest first); unsure only if any is
        self._shares = {code: [(fg == code).astype(np.float32)] for code in (FOREGROUND, UNSURE)
                        if code == FOREGROUND or np.any(fg == UNSURE)}
        self._maps: dict[int, np.ndarray] = {}
        self._distances: dict[int, np.ndarray] = {}

    def distance(self, level: int) -> np.ndarray:
        """``distance_to_body`` of the map on ``level``, made once."""
        if level not in self._distances:
            self._distances[level] = distance_to_body(self.at(level))
        return self._distances[level]

    def at(self, level: int) -> np.ndarray:
        """The map on pyramid level ``level`` (0: the full-resolution map's codes)."""
        if level not in self._maps:
            for shares in self._shares.values():
                while len(shares) <= level:
                    shares.append(cv2.pyrDown(shares[-1]))
            out = (self._shares[FOREGROUND][level] > 0.5).astype(np.uint8)
            if UNSURE in self._shares:
                out[(self._shares[UNSURE][level] > 0.5) & (out == BACKDROP)] = UNSURE
            self._maps[level] = out
        return self._maps[level]


class Mismatch:
    """Where a label map and a foreground disagree, in level pixels (x, y): the cost, made at
    once, and the pairs that pull, made when first asked for (most poses are only costed)."""

    def __init__(self, cost: float, slack: float, terms: list[tuple] = ()):
        """``terms``: per chamfer term, its pulling pairs as the pixels' rows and columns
        here and of their matches (four (N,) arrays), their distances (N,), whether the
        match is the covered pixel, and the term's weight."""
        self.cost = cost  # sum of capped squared distances, weighted
        self._slack = slack
        self._terms = list(terms)

    @cached_property
    def _pairs(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        model, target, weight = [np.zeros((0, 2))], [np.zeros((0, 2))], [np.zeros(0)]
        for ys, xs, iy, ix, dist, move_near, w in self._terms:
            near = np.stack([ix, iy], 1).astype(float)
            here = np.stack([xs, ys], 1).astype(float)
            m, t = (near, here) if move_near else (here, near)
            model.append(m)
            target.append(m + (t - m) * (1 - self._slack / dist)[:, None])
            weight.append(np.full(len(m), w))
        return np.concatenate(model), np.concatenate(target), np.concatenate(weight)

    @property
    def model(self) -> np.ndarray:
        """(N, 2) covered pixels to move."""
        return self._pairs[0]

    @property
    def target(self) -> np.ndarray:
        """(N, 2) where each should go (its match, less the slack)."""
        return self._pairs[1]

    @property
    def weight(self) -> np.ndarray:
        """(N,) each pair's weight."""
        return self._pairs[2]


def distance_to_body(fg: np.ndarray) -> np.ndarray:
    """Per pixel of a foreground map (H, W), how far (pixels) the nearest pixel that may be
    the body is: 0 on foreground and unsure pixels, growing over the backdrop."""
    return cv2.distanceTransform((fg == BACKDROP).astype(np.uint8), cv2.DIST_L2,
                                 cv2.DIST_MASK_PRECISE)


def near_body(fg: np.ndarray, xs: np.ndarray, ys: np.ndarray, reach: float) -> np.ndarray:
    """Whether a pixel that may be the body (foreground or unsure) lies within ``reach``
    pixels (straight-line) of each pixel (xs, ys) of a foreground map (H, W): the map's
    ``distance_to_body`` at most ``reach`` there, read from the pixels that near alone
    rather than a distance transform of the whole map."""
    r = int(np.floor(reach))
    h, w = fg.shape
    out = np.zeros(len(xs), bool)
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            if dx * dx + dy * dy > reach * reach:
                continue
            x, y = xs + dx, ys + dy
            inside = np.flatnonzero((x >= 0) & (x < w) & (y >= 0) & (y < h))
            out[inside] |= fg[y.take(inside), x.take(inside)] != BACKDROP
    return out


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
    """Both chamfer terms between a label map (H, W; -1 where no blob) and a foreground map
    (unsure pixels take no part): a pixel ``d`` from its match costs (min(d, cap) - slack)^2
    if positive, and wants to move d - slack toward it (the slack forgives outline noise and
    the holes a body shows where it happens to match the backdrop). Uncovered foreground
    weighs ``uncovered_weight``: it also comes from what the blobs do not model, and pulled
    the shanks toward the feet. ``nearest_fg``: the foreground's ``NearestPixel`` (its mask
    is ``fg == FOREGROUND``), to share between label maps."""
    covered = labels >= 0
    background = fg == BACKDROP
    fg = fg == FOREGROUND
    cost = 0.0
    # uncovered foreground pulls its nearest covered pixel; covered background is pulled to
    # its nearest foreground pixel
    terms = []
    nearest_fg = NearestPixel(fg) if nearest_fg is None else nearest_fg
    for src, nearest, move_near, w in ((fg & ~covered, NearestPixel(covered), True,
                                        uncovered_weight),
                                       (covered & background, nearest_fg, False, 1.0)):
        if not src.any() or not nearest.mask.any():
            continue
        ys, xs = true_pixels(src)
        iy, ix = nearest(ys, xs)
        dist = np.hypot(iy - ys, ix - xs)
        cost += w * float(np.sum(np.maximum(np.minimum(dist, cap) - slack, 0) ** 2))
        keep = (dist <= cap) & (dist > slack)
        terms.append((ys[keep], xs[keep], iy[keep], ix[keep], dist[keep], move_near, w))
    return Mismatch(cost, slack, terms)


class SilhouetteCue:
    """One run's silhouette state: each view's backdrop (its clean plate where one is given,
    else the key frame's, made the first time it is asked for and learned from every
    tracked frame), and the foregrounds of the frame being tracked. The tracker says where
    the body is (its blobs' pixels, full resolution); this object knows only images and
    cameras. A view whose camera turns about its centre has its backdrop turned with it
    (``TurningBackdrop``); one whose camera moves otherwise, or whose footage around the
    body keeps changing (a camera or light moving unannounced), has no backdrop, and a note
    says so."""

    def __init__(self, seq, moving: Sequence[Sequence[Camera] | None] | None = None,
                 plates=None):
        """``moving``: per view, its camera on every frame where the camera moves, else
        None; ``plates``: per view, its clean plate as (grey, colour or None), or None (a
        moving camera's is not used)."""
        self.seq = seq  # the run's ImageSequence
        self.moving = list(moving) if moving is not None else [None] * seq.n_views
        self.plates = list(plates) if plates is not None else [None] * seq.n_views
        # per view; None: not started
        self.backdrops: list[Backdrop | TurningBackdrop | None] | None = None
        self._foregrounds: dict[tuple[int, int], LevelMaps] = {}  # (view, frame)
        self._recent: list[int] = []  # the frames whose foregrounds are kept, latest last
        self._exposures: dict[tuple[int, int], float] = {}  # (view, frame)
        self._spans: dict[int, tuple[float, float]] = {}  # per view, its lowest and highest

    def reset(self) -> None:
        """Forget the backdrops (a new key pose, or a new size of the body's pyramids)."""
        self.backdrops, self._foregrounds, self._recent = None, {}, []
        self._exposures, self._spans = {}, {}

    @property
    def started(self) -> bool:
        return self.backdrops is not None

    def start(self, key_frame: int, bodies: list[np.ndarray], margins: list[int],
              body_at: np.ndarray) -> list[str]:
        """Each view's backdrop: its clean plate, or the key frame with the body
        (``bodies``: per view, its pixels on the key frame) painted out ``margins`` pixels
        wide; checked against frames spread over the footage. ``body_at``: a world point
        of the body on the key frame (how far a moving camera's backdrop is, at least).
        Returns the notes on views whose backdrop does not hold. The views' backdrops are
        made on every core (reading frames and painting in are OpenCV's work, which lets
        go of the interpreter's lock)."""
        others = np.linspace(0, self.seq.n_frames() - 1, BACKDROP_FRAMES).astype(int)
        others = sorted(set(others) - {key_frame})
        keyed = [self.plates[c] if path is None and self.plates[c] is not None else
                 (self.seq.grey(c, key_frame), self.seq.colour(c, key_frame))
                 for c, path in enumerate(self.moving)]  # read here: the cache is not shared

        def made(c: int) -> tuple[Backdrop | TurningBackdrop | None, str | None]:
            return self._backdrop(c, keyed[c], bodies[c], margins[c], others, key_frame,
                                  body_at)

        with ThreadPoolExecutor(os.cpu_count() or 1, thread_name_prefix="twist-backdrop") \
                as pool:
            views = list(pool.map(made, range(self.seq.n_views)))
        self.backdrops = [backdrop for backdrop, _ in views]
        return [note for _, note in views if note is not None]

    def _backdrop(self, c: int, keyed: tuple, body: np.ndarray, margin: int, others: list[int],
                  key_frame: int, body_at: np.ndarray
                  ) -> tuple[Backdrop | TurningBackdrop | None, str | None]:
        """View ``c``'s backdrop (``start``), or None and the note saying why it has none;
        ``keyed``: its clean plate or key frame (grey, colour)."""
        path = self.moving[c]
        if path is not None and not turns_in_place(path, body_at):
            return None, (f"view {c + 1}: its camera moves, and not only turns about its "
                          "centre, so its backdrop moves with it and its silhouette is not "
                          "used")
        if path is not None:
            frames = (self._turned(path, f, key_frame, *self.seq.peek(c, f)) for f in others)
            backdrop = Backdrop(keyed[0], body, frames, margin, keyed[1], reach=TURNING_REACH)
        else:
            backdrop = Backdrop(keyed[0], body, (self.seq.peek(c, f) for f in others),
                                margin, keyed[1], clean=self.plates[c] is not None)
        if not backdrop.still:
            return None, f"view {c + 1}: " + (
                "the footage around the body changes from frame to frame far more than a "
                "body's outline (a moving camera or light, or a first pose that does not "
                "cover the body)" if path is None else
                "its camera's turn, as given, does not line up the scene from frame to frame "
                "(check the camera's keys or solve, and its lens)") + \
                ", so its silhouette is not used"
        return (backdrop if path is None else TurningBackdrop(backdrop, key_frame, path)), None

    @staticmethod
    def _turned(path: Sequence[Pinhole], frame: int, to: int, grey: np.ndarray,
                colour: np.ndarray | None) -> tuple[np.ndarray, np.ndarray | None]:
        """A turning camera's ``frame`` (grey, colour) as the camera on frame ``to`` would
        have seen it; grey is NaN where that frame shows nothing (it counts as neither
        foreground nor backdrop)."""
        H = turn_homography(path[frame], path[to])
        size = (grey.shape[1], grey.shape[0])
        out = cv2.warpPerspective(grey, H, size, borderValue=float("nan"))
        return out, None if colour is None else cv2.warpPerspective(colour, H, size)

    def has(self, view: int) -> bool:
        """Whether ``view`` has a backdrop (after ``start``)."""
        return self.backdrops is not None and self.backdrops[view] is not None

    def foreground(self, view: int, frame: int, level: int = 0) -> np.ndarray:
        """Foreground map of ``frame`` in ``view`` (one that ``has``) on pyramid level
        ``level`` (``LevelMaps``; 0: full resolution); the maps of the last two frames asked
        for are kept (the frame being tracked and the one before it)."""
        return self._maps(view, frame).at(level)

    def distance_to_body(self, view: int, frame: int, level: int = 0) -> np.ndarray:
        """``distance_to_body`` of ``foreground``'s map, kept with it."""
        return self._maps(view, frame).distance(level)

    def near_body(self, view: int, frame: int, level: int, xs: np.ndarray, ys: np.ndarray,
                  reach: float) -> np.ndarray:
        """``near_body`` of ``foreground``'s map at level pixels (xs, ys)."""
        return near_body(self.foreground(view, frame, level), xs, ys, reach)

    def _maps(self, view: int, frame: int) -> LevelMaps:
        """``frame``'s foreground maps in ``view``, made when first asked for."""
        if self._recent[-1:] != [frame]:
            self._recent = [f for f in self._recent if f != frame][-1:] + [frame]
            self._foregrounds = {k: v for k, v in self._foregrounds.items()
                                 if k[1] in self._recent}
        if (view, frame) not in self._foregrounds:
            bd = self.backdrops[view]
            seen = (self.seq.grey(view, frame), self.seq.colour(view, frame))
            self._foregrounds[view, frame] = LevelMaps(bd.foreground(frame, *seen) if isinstance(
                bd, TurningBackdrop) else bd.foreground(*seen, gain=self.exposure(view, frame)))
        return self._foregrounds[view, frame]

    def exposure(self, view: int, frame: int) -> float | None:
        """``frame``'s exposure in ``view`` against the view's still backdrop
        (``Backdrop.exposure``), kept; None where the view has none (a camera that moves or
        turns: its backdrop is drawn from frames of their own exposures)."""
        bd = self.backdrops[view] if self.backdrops is not None else None
        if not isinstance(bd, Backdrop):
            return None
        if (view, frame) not in self._exposures:
            gain = self._exposures[view, frame] = bd.exposure(self.seq.grey(view, frame))
            lo, hi = self._spans.get(view, (gain, gain))
            self._spans[view] = (min(lo, gain), max(hi, gain))
        return self._exposures[view, frame]

    def exposure_span(self, view: int) -> tuple[float, float] | None:
        """The lowest and highest exposure read in ``view`` so far (``exposure``), None
        before any."""
        return self._spans.get(view)

    def unseen(self, view: int) -> bool:
        """Whether ``view``'s backdrop can still learn from a tracked frame."""
        return self.has(view) and self.backdrops[view].learning

    def learn(self, view: int, frame: int, body: np.ndarray) -> None:
        """Let ``view``'s backdrop see what ``frame`` shows away from the body there."""
        bd = self.backdrops[view]
        seen = (self.seq.grey(view, frame), body, self.seq.colour(view, frame))
        if isinstance(bd, TurningBackdrop):
            bd.learn(frame, *seen)
        else:
            bd.learn(*seen, gain=self.exposure(view, frame))

"""Which blob is in front at each pixel, and where: each pixel's ray against every ellipsoid.

A pixel's world ray X(l) = o + l d meets ellipsoid e, written in its own normalised frame
y = diag(1/r) Q^T (g_e^{-1} X - c), where |w + l e|^2 = 1 with w and e the ray's start and
direction in that frame. The nearest root over all blobs is the visible surface (paper eq. 17,
one quadratic per blob); the pixel belongs to that blob's segment. Under orthography e is the
same for every pixel and w is affine in the pixel; through a pinhole w is the same (the
camera's centre) and e is affine: in both, the quadratic's coefficients are polynomials in the
pixel, so whole grids of pixels are a few array operations (``render_labels``).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .camera import Camera
from .image import true_pixels
from .skeleton import Ellipsoid


@dataclass
class Hits:
    """Per queried pixel: blob index (-1 where no blob), ray parameter (world units along the
    view direction, smaller is nearer), world point (N, 3), and ``rim`` in [0, 1]: 1 - r^2 of the
    ray's normalised distance from the blob centre (0 on the outline, 1 through the middle)."""

    label: np.ndarray
    depth: np.ndarray
    world: np.ndarray
    rim: np.ndarray


@dataclass(frozen=True)
class BlobStack:
    """Every blob's fixed numbers stacked, to pose and cast them many times: the joint whose
    segment carries it (E,), and in that segment's reference frame its centre (E, 3), axes Q
    (E, 3, 3, as columns), radii (E, 3) and Q diag(1/r) (E, 3, 3)."""

    joint: np.ndarray
    centre: np.ndarray
    Q: np.ndarray
    radii: np.ndarray
    to_unit: np.ndarray

    @classmethod
    def of(cls, blobs: list[Ellipsoid] | BlobStack) -> BlobStack:
        if isinstance(blobs, BlobStack):
            return blobs
        E = len(blobs)
        return cls(np.array([b.joint for b in blobs], dtype=int),
                   np.array([b.centre for b in blobs], dtype=float).reshape(E, 3),
                   np.array([b.Q for b in blobs], dtype=float).reshape(E, 3, 3),
                   np.array([b.radii for b in blobs], dtype=float).reshape(E, 3),
                   np.array([b.Q / b.radii for b in blobs], dtype=float).reshape(E, 3, 3))

    def __len__(self) -> int:
        return len(self.joint)


def _posed(blobs: BlobStack, g: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Per blob, its segment's world rotation (E, 3, 3) and its world centre (E, 3)."""
    R, p = g[blobs.joint, :3, :3], g[blobs.joint, :3, 3]
    return R, np.einsum("eab,eb->ea", R, blobs.centre) + p


def blob_frames(blobs: list[Ellipsoid] | BlobStack, g: np.ndarray
                ) -> tuple[np.ndarray, np.ndarray]:
    """Per blob, world-to-normalised linear map (E, 3, 3) and world centre (E, 3).

    g: (J, 4, 4) segment motions, reference frame to world.
    """
    blobs = BlobStack.of(blobs)
    R, C = _posed(blobs, g)
    return _to_unit(blobs, R), C


def _to_unit(blobs: BlobStack, R: np.ndarray) -> np.ndarray:
    """World-to-normalised maps (E, 3, 3) of blobs whose segments turn by R (E, 3, 3)."""
    return np.einsum("eba,ecb->eac", blobs.to_unit, R)  # (Q diag(1 / r))^T R^T


def cast(view: Camera, pixels: np.ndarray, blobs: list[Ellipsoid] | BlobStack, g: np.ndarray
         ) -> Hits:
    """Nearest blob hit for each pixel (N, 2) in the view, blobs posed by segment motions g;
    depths are distances along the rays (``Camera.ray``)."""
    origin, d = view.ray(pixels)
    N = len(pixels)
    if not len(blobs):
        return Hits(np.full(N, -1), np.full(N, np.inf), np.zeros((N, 3)), np.zeros(N))
    A, C = blob_frames(blobs, g)
    e = np.einsum("eab,nb->nea", A, d)  # (N, E, 3)
    y0 = np.einsum("eab,neb->nea", A, origin[:, None, :] - C[None])
    a = np.sum(e * e, -1)  # (N, E)
    b = np.sum(y0 * e, -1)
    c = np.sum(y0 * y0, -1) - 1
    disc = b * b - a * c
    lam = (-b - np.sqrt(np.maximum(disc, 0))) / a
    # a pinhole sees what is in front of it; a parallel ray's start is an arbitrary plane
    lam = np.where((disc > 0) & ((lam > 0) | (not view.central)), lam, np.inf)
    label = np.argmin(lam, axis=1)
    rows = np.arange(N)
    depth = lam[rows, label]
    ok = np.isfinite(depth)
    label = np.where(ok, label, -1)
    world = origin + np.where(ok, depth, 0)[:, None] * d
    rim = np.where(ok, disc[rows, label] / a[rows, label], 0.0)
    return Hits(label, depth, world, np.clip(rim, 0.0, 1.0))


def blob_boxes(view: Camera, blobs: list[Ellipsoid] | BlobStack, g: np.ndarray) -> np.ndarray:
    """Pixel extents (E, 4) = (xmin, ymin, xmax, ymax) of every blob's outline, as floats."""
    blobs = BlobStack.of(blobs)
    Rs, C = _posed(blobs, g)
    return _boxes(view, _to_unit(blobs, Rs), C)


def outline_areas(view: Camera, blobs: list[Ellipsoid] | BlobStack, g: np.ndarray
                  ) -> np.ndarray:
    """Area (E,) in square pixels of every blob's whole outline, hidden or not: the ellipse
    (p - c)^T P (p - c) <= 1 has area pi / sqrt(det P)."""
    blobs = BlobStack.of(blobs)
    Rs, C = _posed(blobs, g)
    _, P = view.ellipses(_to_unit(blobs, Rs), C)
    return np.pi / np.sqrt(P[:, 0, 0] * P[:, 1, 1] - P[:, 0, 1] * P[:, 1, 0])


def _boxes(view: Camera, A: np.ndarray, C: np.ndarray) -> np.ndarray:
    """``blob_boxes`` of blobs with world-to-normalised maps A and world centres C: the
    outline (p - c)^T P (p - c) <= 1 reaches sqrt of P^-1's diagonal from its centre."""
    c, P = view.ellipses(A, C)
    det = P[:, 0, 0] * P[:, 1, 1] - P[:, 0, 1] * P[:, 1, 0]
    half = np.sqrt(np.stack([P[:, 1, 1], P[:, 0, 0]], 1) / det[:, None])
    return np.concatenate([c - half, c + half], 1)


def _squares(x: np.ndarray) -> np.ndarray:
    """|x|^2 (N,) of rows x (N, 3): the squares added left to right, as ``np.sum`` over the
    rows would add them, without its reduction's cost on a short axis (five times as
    much on a few thousand rows)."""
    x2 = x * x
    return x2[:, 0] + x2[:, 1] + x2[:, 2]


def _clip_box(lo, hi, shape, margin: int):
    H, W = shape
    x0, y0 = max(int(np.floor(lo[0])) - margin, 0), max(int(np.floor(lo[1])) - margin, 0)
    x1, y1 = min(int(np.ceil(hi[0])) + margin + 1, W), min(int(np.ceil(hi[1])) + margin + 1, H)
    return None if x0 >= x1 or y0 >= y1 else (x0, y0, x1, y1)


@dataclass
class LabelGrid:
    """The front-most blob at every ``step``-th pixel of a view's silhouette box: ``label``
    (rows, cols), -1 where no blob shows, its cell (i, j) at pixel (x0 + step j, y0 + step i)
    of ``box`` = (x0, y0, x1, y1), x0 and y0 multiples of ``step`` (None, and an empty grid,
    when nothing shows). The hits at its cells are worked out when asked (``hits``): most
    label maps are read for their labels alone."""

    label: np.ndarray
    box: tuple | None
    step: int
    _key: np.ndarray  # per cell the z-buffer's depth key (``label_grid``)
    _disc: np.ndarray  # per cell the front blob's discriminant over a^2
    _view: Camera
    _coefs: tuple  # per blob a, e0, ex, ey (``label_grid``)

    def covered(self) -> tuple[np.ndarray, np.ndarray]:
        """Grid rows and columns of the cells a blob covers, in row-major order."""
        return true_pixels(self.label >= 0)

    def pixels(self, rows: np.ndarray, cols: np.ndarray) -> np.ndarray:
        """Pixel coordinates (N, 2) of grid cells, as floats."""
        x0, y0 = (0, 0) if self.box is None else self.box[:2]
        return np.stack([x0 + self.step * cols, y0 + self.step * rows], 1).astype(float)

    def full(self, shape) -> np.ndarray:
        """The labels on the map of every ``step``-th pixel of an image of ``shape``
        (ceil(H / step), ceil(W / step)), whose pixel (i, j) is pixel (step j, step i)."""
        return self.window(0, 0, (-(-shape[0] // self.step), -(-shape[1] // self.step)))

    def window(self, x0: int, y0: int, shape: tuple[int, int]) -> np.ndarray:
        """The labels of ``full``'s map on its cells (y0 .. y0 + h, x0 .. x0 + w), -1 where no
        blob shows; ``shape`` is (h, w)."""
        out = np.full(shape, -1, np.int32)
        i, j = self._at
        h, w = self.label.shape
        r0, r1 = max(i, y0), min(i + h, y0 + shape[0])
        c0, c1 = max(j, x0), min(j + w, x0 + shape[1])
        if r1 > r0 and c1 > c0:
            out[r0 - y0:r1 - y0, c0 - x0:c1 - x0] = self.label[r0 - i:r1 - i, c0 - j:c1 - j]
        return out

    def hits_on_full(self, rows: np.ndarray, cols: np.ndarray) -> Hits:
        """``hits`` at covered pixels (rows, cols) of ``full``'s map."""
        i, j = self._at
        return self.hits(rows - i, cols - j)

    @property
    def _at(self) -> tuple[int, int]:
        """The grid's first cell on ``full``'s map."""
        return (0, 0) if self.box is None else (self.box[1] // self.step,
                                                self.box[0] // self.step)

    def hits(self, rows: np.ndarray, cols: np.ndarray) -> Hits:
        """The hits at covered grid cells (``covered``'s, or any of them)."""
        view, (a, e0, ex, ey) = self._view, self._coefs
        pixels = self.pixels(rows, cols)
        key, lab = self._key[rows, cols], self.label[rows, cols]
        o0, ox, oy, r0, rx, ry = view.ray_lines()
        u, v = pixels[:, :1], pixels[:, 1:]
        ray = r0 + u * rx + v * ry
        lam = -1.0 / key if view.central else key  # along ``ray``
        norm = np.sqrt(_squares(ray))
        e = e0.take(lab, 0) + u * ex.take(lab, 0) + v * ey.take(lab, 0)
        rim = self._disc[rows, cols] * a[lab] ** 2 / _squares(e)  # (b^2 - a c) / |e|^2
        return Hits(lab, lam * norm, o0 + u * ox + v * oy + lam[:, None] * ray,
                    np.minimum(rim, 1.0))


def render_labels(view: Camera, blobs: list[Ellipsoid] | BlobStack, g, shape, step: int = 1
                  ) -> tuple[np.ndarray, Hits, tuple]:
    """Z-buffer the pixels of the silhouette box whose coordinates are multiples of ``step``:
    the covered pixels (N, 2), their hits and the box (None if nothing shows); the same as
    :func:`cast` on those pixels (``label_grid``)."""
    grid = label_grid(view, blobs, g, shape, step)
    rows, cols = grid.covered()
    return grid.pixels(rows, cols), grid.hits(rows, cols), grid.box


def label_grid(view: Camera, blobs: list[Ellipsoid] | BlobStack, g, shape, step: int = 1
               ) -> LabelGrid:
    """Z-buffer the pixels of the silhouette box (of an image of ``shape``) whose coordinates
    are multiples of ``step``, over every blob's own box at once, blobs posed by segment
    motions g (J, 4, 4).

    Same labels as :func:`cast` on those pixels, at a fraction of the work: each blob's
    quadratic's coefficients are polynomials in the pixel, evaluated on its box."""
    return label_grids([view], blobs, g, [shape], [step])[0]


def label_grids(views: Sequence[Camera], blobs: list[Ellipsoid] | BlobStack, g,
                shapes: Sequence, steps: Sequence[int]) -> list[LabelGrid]:
    """``label_grid`` in each of ``views`` (an image of ``shapes[i]``, every ``steps[i]``-th
    pixel) of one pose at once: the blobs are posed once, and every view's blobs are
    z-buffered together as rows of one table (a view's grid cells apart from the others'),
    so that numpy is called once for all views where it was once a view; the same numbers
    as view by view."""
    blobs = BlobStack.of(blobs)
    E = len(blobs)
    Rs, C = _posed(blobs, g)  # once, for the boxes and the blobs' normalised frames
    A = _to_unit(blobs, Rs)
    out: list = [None] * len(views)
    seen = []  # the views where a blob shows: (index, box, xs, ys, e0, ex, ey)
    fps, boxes_all = [], []
    for i, (view, shape, step) in enumerate(zip(views, shapes, steps)):
        boxes = _boxes(view, A, C) if E else np.zeros((0, 4))
        box = _clip_box(boxes[:, :2].min(0), boxes[:, 2:].max(0), shape, 2) if E else None
        if box is None:
            empty = np.zeros((0, 0))
            out[i] = LabelGrid(np.zeros((0, 0), np.int64), None, step, empty, empty, view,
                               (np.zeros(0),) + (np.zeros((0, 3)),) * 3)
            continue
        x0, y0, x1, y1 = box
        x0, y0 = x0 - x0 % step, y0 - y0 % step  # the grid: multiples of step
        o0, ox, oy, r0, rx, ry = view.ray_lines()
        # the ray in each blob's normalised frame: start w = w0 + u wx + v wy, direction
        # e = e0 + u ex + v ey (one of the two is the same for every pixel)
        w0 = np.einsum("eab,eb->ea", A, o0 - C)
        wx, wy, e0, ex, ey = A @ ox, A @ oy, A @ r0, A @ rx, A @ ry
        # |w + l e|^2 = 1 is a l^2 + 2 b l + c = 0 with a constant, b affine and c quadratic
        # in (u, v). Under orthography (e fixed) a = |e|^2, b = w.e, c = |w|^2 - 1, and the
        # nearer root is l. Through a pinhole (w fixed), in m = 1 / l: a = |w|^2 - 1,
        # b = -w.e, c = |e|^2, and the nearer root is -m. Either way the root
        # (-b - sqrt(b^2 - a c)) / a is a depth key, smaller nearer: in terms of the fixed
        # vector f and the affine one p = p0 + u px + v py, a = |f|^2 - [pinhole],
        # b = +-p.f, c = |p|^2 - [orthography]
        fps.append(np.stack([w0, e0, ex, ey] if view.central else [e0, w0, wx, wy], 1))
        boxes_all.append(boxes)
        seen.append((i, (x0, y0, x1, y1), np.arange(x0, x1, step, dtype=float),
                     np.arange(y0, y1, step, dtype=float), e0, ex, ey))
    if not seen:
        return out
    # from here on one row per view and blob, a view's E rows after the one before's, each
    # with its view's grid's first pixel (x0, y0), image width and height, step, grid
    # columns and rows, and whether it is a pinhole
    K = len(seen)
    per_row = np.repeat(np.arange(K), E)
    n_cols, n_rows = np.array([(len(x), len(y)) for _, _, x, y, *_ in seen]).T
    origin = np.array([box[:2] for _, box, *_ in seen]).take(per_row, 0)
    image_wh = np.array([(shapes[i][1], shapes[i][0]) for i, *_ in seen]).take(per_row, 0)
    step = np.array([steps[i] for i, *_ in seen]).take(per_row)[:, None]
    grid_wh = np.stack([n_cols, n_rows], 1).take(per_row, 0)
    central = np.array([views[i].central for i, *_ in seen], float).take(per_row)
    fp = np.concatenate(fps)  # (K E, 4, 3): f, p0, px, py
    dots = np.sum(fp[:, :, None] * fp[:, None], -1)  # (K E, 4, 4): every pair's dot product
    a = dots[:, 0, 0] - central
    b0, bx, by = (np.where(central > 0, -1.0, 1.0)[:, None] * dots[:, 0, 1:]).T
    c00, c0x, c0y = dots[:, 1, 1] - (1 - central), dots[:, 1, 2], dots[:, 1, 3]
    cxx, cxy, cyy = dots[:, 2, 2], dots[:, 2, 3], dots[:, 3, 3]
    d00, dx, dy = b0 * b0 - a * c00, 2 * (b0 * bx - a * c0x), 2 * (b0 * by - a * c0y)
    dxx, dxy, dyy = bx * bx - a * cxx, 2 * (bx * by - a * cxy), by * by - a * cyy
    # each blob's grid columns and rows: its box widened by a pixel, clipped to the image
    boxes = np.concatenate(boxes_all)
    lo = np.maximum(np.floor(boxes[:, :2]) - 1, 0)
    hi = np.minimum(np.ceil(boxes[:, 2:]) + 2, image_wh)
    first = np.maximum(-((origin - lo) // step), 0).astype(int)
    stop = np.minimum(np.maximum(-((origin - hi) // step), 0), grid_wh).astype(int)
    # each view's grid columns and rows, as a row of a table as wide as the widest
    nx, ny = n_cols.max(), n_rows.max()
    xs, ys = np.zeros((K, nx)), np.zeros((K, ny))
    for k, (_, _, x, y, *_) in enumerate(seen):
        xs[k, :len(x)], ys[k, :len(y)] = x, y
    xs, ys = xs.take(per_row, 0), ys.take(per_row, 0)
    # over the whole grid at once, per blob, divided by a^2 (so that sqrt(disc) / a is one
    # root) and by -a: disc / a^2 = DV(v) + DU(u) + v KUV(u), depth = BV(v) + BU(u) - sqrt
    a2 = (a * a)[:, None]
    DU, KUV = (dxx[:, None] * xs + dx[:, None]) * xs / a2, dxy[:, None] * xs / a2
    DV = ((dyy[:, None] * ys + dy[:, None]) * ys + d00[:, None]) / a2
    BU, BV = -bx[:, None] * xs / a[:, None], -(b0[:, None] + by[:, None] * ys) / a[:, None]
    # every blob's box cells in one flat list: row (view and blob), grid row and column
    cols_n, rows_n = np.maximum(stop - first, 0).T
    size = rows_n * cols_n
    blob = np.repeat(np.arange(len(size)), size)
    k = np.arange(len(blob)) - np.repeat(np.cumsum(size) - size, size)  # index in its box
    width = cols_n[blob]
    r, c = np.divmod(k, width)
    r += first[blob, 1]
    c += first[blob, 0]
    at_r, at_c = blob * ny + r, blob * nx + c  # into the (K E, rows), (K E, cols) tables
    disc = DV.take(at_r) + DU.take(at_c) + ys.take(at_r) * KUV.take(at_c)
    # (the hits kept by their indices: take is several times faster than a boolean mask)
    hit = np.flatnonzero(disc > 0)
    r, c, at_r, at_c, disc, blob = (x.take(hit) for x in (r, c, at_r, at_c, disc, blob))
    lam = BV.take(at_r) + BU.take(at_c) - np.sqrt(disc)
    if central.any():  # what lies behind a pinhole is not seen (m < 0)
        ahead = np.flatnonzero((lam < 0) | (central.take(blob) == 0))
        r, c, blob, disc, lam = (x.take(ahead) for x in (r, c, blob, disc, lam))
    # the z-buffer: per cell the nearest hit, the first blob on a tie; the views' grids one
    # after the other
    sizes = n_rows * n_cols
    at = np.cumsum(sizes) - sizes  # each view's first cell
    cell = at.take(per_row).take(blob) + r * n_cols.take(per_row).take(blob) + c
    depth = np.full(sizes.sum(), np.inf)
    np.minimum.at(depth, cell, lam)
    front = lam == depth[cell]
    flat_label = np.full(depth.size, len(size))
    np.minimum.at(flat_label, cell[front], blob[front])
    disc_front = np.zeros(depth.size)
    won = front & (flat_label[cell] == blob)
    disc_front[cell[won]] = disc[won]
    for k, (i, box, _, _, e0, ex, ey) in enumerate(seen):
        part = slice(at[k], at[k] + sizes[k])
        shape = (n_rows[k], n_cols[k])
        own = flat_label[part]
        label = np.where(own < len(size), own - k * E, -1).reshape(shape)
        out[i] = LabelGrid(label, box, steps[i], depth[part].reshape(shape),
                           disc_front[part].reshape(shape), views[i],
                           (a[k * E:(k + 1) * E], e0, ex, ey))
    return out

"""A printed Muybridge plate into an image sequence: its cells found, cropped and registered.

A plate is one image with its cells in rows, separated by dark gutters; each cell was
cropped by hand a little differently. Rows are split where whole image rows are gutter-dark
(their 90th percentile brightness within ``GUTTER_CONTRAST`` of the plate's darkest rows),
cells within a row where whole columns of the row are; a gutter between two cells a pixel
or two wide, which the print blurs lighter, is found as a narrow dip in that brightness. A
row with no dark gutters between its cells (cells printed edge to edge) is split into as
many equal cells as its content repeats across it (the animal, once a cell: the period of
the column profile's autocorrelation), or as many as the caller says.

Muybridge's cameras stood in a row at equal spacing, each behind its own cell, so the
scene behind the animal -- the ground line, the measuring grid's rows -- stands at one
height in every cell but for where the crop fell. Each cell is moved up or down onto the
first by that backdrop (``register``; OpenCV's ECC over the backdrop's pixels did not
converge on most cells of the three plates tried); where the grid's repeating rows match
in more than one place, the animal's feet on the first cell's ground choose. The frames
are the cells resampled onto the first cell's pixels. Pixels: x right, y down, origin at
the plate's top-left pixel; boxes are (x0, y0, x1, y1), ends exclusive.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from .errors import InputError
from .image import load_grey, quiet_stderr, to_uint8

GUTTER_CONTRAST = 0.15  # brightness over the plate's darkest rows still called a gutter
GUTTER_DIP = 0.65  # a line this much darker than the lightest beside it is a thin gutter
GUTTER_REACH = 6  # pixels either side a thin gutter is compared with
MIN_CELL_SHARE = 0.4  # a run narrower than this share of the widest is a strip, not a cell
BORDER = 1  # pixels trimmed off each cell's edges (the gutter's blurred rim)
FEET_TOLERANCE = 2  # pixels an animal's lowest row may differ from the first cell's and
# still stand on the same ground (hooves and paws lift a little as they step)


class PlateError(InputError):
    """A plate whose cells cannot be found or registered."""


@dataclass
class Cell:
    box: tuple[int, int, int, int]  # (x0, y0, x1, y1) in the plate
    offset: np.ndarray  # (2,) where the first cell's pixel (0, 0) falls in this cell
    off_feet: bool = False  # the offset puts the animal's lowest point off the first cell's
    # ground: the backdrop alone lined it up


def _runs(keep: np.ndarray) -> list[tuple[int, int]]:
    """Half-open runs (start, stop) of True in a boolean line."""
    edges = np.diff(np.concatenate([[0], keep.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))


def _light(p90: np.ndarray, dark: float) -> np.ndarray:
    """Which columns of a row (by their 90th percentile brightness) are not gutter: a
    gutter column is near the plate's darkest (under ``dark``), or a narrow dip well under
    the columns beside it (a gutter a pixel or two wide, blurred lighter by the print)."""
    k = 2 * GUTTER_REACH + 1
    beside = cv2.dilate(p90.astype(np.float32)[None], np.ones((1, k), np.uint8))[0]
    return (p90 > dark) & (p90 > GUTTER_DIP * beside)


def _wide_runs(keep: np.ndarray) -> list[tuple[int, int]]:
    runs = _runs(keep)
    if not runs:
        return []
    widest = max(b - a for a, b in runs)
    return [(a, b) for a, b in runs if b - a >= MIN_CELL_SHARE * widest]


def _period(profile: np.ndarray, height: int) -> int | None:
    """The strongest repeat of a column profile, in columns, between half a row's height
    and half its width (None when nothing repeats)."""
    p = profile - profile.mean()
    n = len(p)
    ac = np.correlate(p, p, mode="full")[n - 1:]
    lo, hi = max(height // 2, 2), n // 2
    if hi <= lo or ac[0] <= 0:
        return None
    lag = lo + int(np.argmax(ac[lo:hi + 1]))
    return lag if ac[lag] > 0.2 * ac[0] else None


def find_cells(grey: np.ndarray, per_row: int | None = None) -> list[tuple[int, int, int, int]]:
    """The cells' boxes in reading order (rows top to bottom, cells left to right) of a
    plate (grey, float in [0, 1]). ``per_row``: how many cells each row holds, where the
    plate does not show it (cells printed edge to edge)."""
    rows_p90 = np.percentile(grey, 90, axis=1)
    dark = float(np.percentile(rows_p90, 2)) + GUTTER_CONTRAST
    boxes = []
    for y0, y1 in _wide_runs(rows_p90 > dark):  # between rows, gutters are wide
        cols_p90 = np.percentile(grey[y0:y1], 90, axis=0)
        cells = _wide_runs(_light(cols_p90, dark))
        if per_row is not None and len(cells) != per_row or (
                per_row is None and len(cells) == 1):
            x0, x1 = cells[0][0], cells[-1][1]
            n = per_row
            if n is None:  # cells edge to edge: as many as the content repeats
                profile = 1 - grey[y0:y1, x0:x1].mean(axis=0)
                lag = _period(profile, y1 - y0)
                n = 1 if lag is None else max(1, round((x1 - x0) / lag))
            edges = np.linspace(x0, x1, n + 1).round().astype(int)
            cells = list(zip(edges[:-1], edges[1:]))
        boxes += [(int(a), int(y0), int(b), int(y1)) for a, b in cells]
    if len(boxes) < 2:
        raise PlateError("found fewer than two cells: is this a plate of several cells "
                         "with dark gutters between its rows?")
    return [(x0 + BORDER, y0 + BORDER, x1 - BORDER, y1 - BORDER) for x0, y0, x1, y1 in boxes]


def backdrop_mask(cell: np.ndarray) -> np.ndarray:
    """Pixels of a cell (grey) that show the backdrop: not the animal (dark shapes wider
    than the grid's lines, widened by a few pixels)."""
    img8 = np.clip(cell * 255, 0, 255).astype(np.uint8)
    t, _ = cv2.threshold(img8, 0, 255, cv2.THRESH_BINARY + cv2.THRESH_OTSU)
    dark = (img8 < t).astype(np.uint8)
    body = cv2.morphologyEx(dark, cv2.MORPH_OPEN, np.ones((5, 5), np.uint8))
    return cv2.dilate(body, np.ones((7, 7), np.uint8)) == 0


def _row_profile(cell: np.ndarray, backdrop: np.ndarray) -> np.ndarray:
    """The median brightness of each row of the cell's backdrop (its ``backdrop_mask``),
    less its running mean: the grid's lines and the ground's edge, with the animal and the
    light's slow falloff left out (a row the animal covers whole reads as the median of the
    whole row)."""
    masked = np.where(backdrop, cell, np.nan)
    seen = ~np.all(np.isnan(masked), axis=1)
    p = np.median(cell, axis=1)
    p[seen] = np.nanmedian(masked[seen], axis=1)
    k = max(3, len(p) // 8) | 1
    return p - np.convolve(np.pad(p, k // 2, mode="edge"), np.ones(k) / k, mode="valid")


def _match_scores(ref: np.ndarray, cur: np.ndarray, most: int) -> np.ndarray:
    """Normalised correlation of ref[i] with cur[i + d] over their overlap, for every shift
    d in -``most``..``most`` (index d + most)."""
    scores = []
    for d in range(-most, most + 1):
        a = ref[max(0, -d):len(ref) - max(0, d)]
        b = cur[max(0, d):max(0, d) + len(a)]
        n = min(len(a), len(b))
        a, b = a[:n] - a[:n].mean(), b[:n] - b[:n].mean()
        den = np.sqrt(np.sum(a * a) * np.sum(b * b))
        scores.append(np.sum(a * b) / den if den > 0 else -1.0)
    return np.array(scores)


def _shift(scores: np.ndarray, most: int, near: float | None = None) -> tuple[float, bool]:
    """The shift d with the best score (``_match_scores``), to a fraction of a sample (a
    parabola through the peak); with ``near``, the best of the peaks (local maxima scoring
    over 0) within ``FEET_TOLERANCE`` of it, where there is one. And whether ``near`` was
    given and no peak was near it (the best overall taken instead)."""
    i = int(np.argmax(scores))
    peaks = [] if near is None else [
        k for k in range(len(scores)) if scores[k] > 0 and abs(k - most - near) <= FEET_TOLERANCE
        and (k == 0 or scores[k] >= scores[k - 1])
        and (k == len(scores) - 1 or scores[k] >= scores[k + 1])]
    if peaks:
        i = max(peaks, key=lambda k: scores[k])
    frac = 0.0
    if 0 < i < len(scores) - 1:
        c = scores[i - 1] - 2 * scores[i] + scores[i + 1]
        frac = 0.5 * (scores[i - 1] - scores[i + 1]) / c if c < 0 else 0.0
    return i - most + frac, near is not None and not peaks


def _lowest(backdrop: np.ndarray) -> float | None:
    """The lowest row of the animal in a cell, from its ``backdrop_mask``: of the largest
    dark shape that the mask leaves out, the row above its lowest half percent of pixels (a stray
    dark pixel of the print does not lower it). None when the cell shows none, or when that
    shape reaches the cell's bottom row: cut off by the crop, or run into a dark ground,
    its lowest row is not where the feet stand."""
    body = (~backdrop).astype(np.uint8)
    n, labels, stats, _ = cv2.connectedComponentsWithStats(body)
    if n < 2:
        return None
    largest = 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))
    if np.any(labels[-1] == largest):
        return None
    return float(np.percentile(np.nonzero(labels == largest)[0], 99.5))


def register(reference: np.ndarray, cell: np.ndarray) -> np.ndarray:
    """Offset (2,) of ``cell`` against ``reference`` (grey cells, any sizes): the cell's
    pixel at ``p + offset`` shows what the reference shows at p (``_offset``)."""
    backdrop = backdrop_mask(reference)
    return _offset(_row_profile(reference, backdrop), _lowest(backdrop), cell)[0]


def _offset(reference_rows: np.ndarray, reference_feet: float | None, cell: np.ndarray
            ) -> tuple[np.ndarray, bool]:
    """``register`` against a reference cell's ``_row_profile`` and its animal's lowest row.
    Down: from the backdrop's rows (the ground's edge, the measuring grid's lines), searched
    within a tenth of the cell's height, as crops differ by a few pixels. The grid's lines
    repeat, so the profile also matches a grid square off; of its matches, the best that
    keeps the animal's feet on the reference's ground (its lowest row within
    ``FEET_TOLERANCE``) is taken, and the best overall where none does (an animal leaping
    or rearing). Across: none. The cameras stood side by side, so each cell shows another
    stretch of the grid, and its columns repeat: on the three plates tried, matching them
    jumped 6 to 15 pixels between neighbouring cells, a grid square's width, not the
    crop's error. Also whether the feet were found off every match (``Cell.off_feet``)."""
    most = max(2, len(reference_rows) // 10)
    backdrop = backdrop_mask(cell)
    scores = _match_scores(reference_rows, _row_profile(cell, backdrop), most)
    feet = _lowest(backdrop)
    near = None if feet is None or reference_feet is None else feet - reference_feet
    down, off_feet = _shift(scores, most, near)
    return np.array([0.0, down]), off_feet


def import_plate(grey: np.ndarray, per_row: int | None = None
                 ) -> tuple[list[Cell], list[np.ndarray]]:
    """The plate's cells (``find_cells``), each registered to the first, and the frames:
    each cell resampled onto the first cell's pixels (grey float32, the first cell's size)."""
    boxes = find_cells(grey, per_row)
    crops = [grey[y0:y1, x0:x1] for x0, y0, x1, y1 in boxes]
    first = crops[0]
    backdrop = backdrop_mask(first)  # each cell's reference: its rows and its animal's feet
    first_rows, first_feet = _row_profile(first, backdrop), _lowest(backdrop)
    cells, frames = [], []
    for box, crop in zip(boxes, crops):
        offset, off_feet = (np.zeros(2), False) if crop is first else _offset(
            first_rows, first_feet, crop)
        cells.append(Cell(box, offset, off_feet))
        warp = np.array([[1, 0, offset[0]], [0, 1, offset[1]]], np.float32)
        frames.append(cv2.warpAffine(crop.astype(np.float32), warp,
                                     (first.shape[1], first.shape[0]),
                                     flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
                                     borderMode=cv2.BORDER_REPLICATE))
    return cells, frames


def unconfirmed(cells: list[Cell]) -> str:
    """The cells (1-based, in reading order) whose animal's feet no match of the backdrop
    stood on the first cell's ground, as advice to look at them ('' when there are none):
    their backdrop alone lined them up, and the measuring grid may have matched a square
    off."""
    doubtful = [str(k) for k, c in enumerate(cells, 1) if c.off_feet]
    if not doubtful:
        return ""
    return (f"cell{'s' if len(doubtful) > 1 else ''} {', '.join(doubtful)} lined up by the "
            "backdrop alone (the animal's lowest point not on the first cell's ground: in "
            "the air, rearing, or legs too thin to make out): check that "
            f"{'they are' if len(doubtful) > 1 else 'it is'} not a grid square too high or "
            "low")


def write_frames(plate: str | Path, out: str | Path, per_row: int | None = None
                 ) -> tuple[list[Cell], list[Path]]:
    """Import the plate file and write its frames as ``<plate name>_01.png``, ... into the
    folder ``out`` (made if missing; an earlier import's frames there are replaced);
    returns the cells and the files."""
    plate, out = Path(plate), Path(out)
    with quiet_stderr():  # libpng's warnings on digitised plates' colour profiles
        grey = load_grey(plate)
    cells, frames = import_plate(grey, per_row)
    out.mkdir(parents=True, exist_ok=True)
    for old in out.glob(f"{plate.stem}_[0-9][0-9].png"):  # an earlier import's, maybe more
        old.unlink()
    paths = []
    for i, frame in enumerate(frames, 1):
        path = out / f"{plate.stem}_{i:02d}.png"
        cv2.imwrite(str(path), to_uint8(frame))
        paths.append(path)
    return cells, paths

"""Plate import: cells found and lined up on a synthetic plate whose cells and offsets are
known, and on three printed Muybridge plates, where the ground line and the feet clicked by
hand are the check."""

import json
import subprocess
import sys
from pathlib import Path

import cv2
import numpy as np
import pytest

from core.image import load_grey, quiet_stderr
from core.plate import BORDER, PlateError, find_cells, import_plate, register, unconfirmed

ROOT = Path(__file__).resolve().parents[2]
PLATES = ROOT / "example_blends" / "muybridge_plates"


def _scene(width=900, height=160, seed=0, ground=True):
    """A backdrop as Muybridge's: light, a measuring grid of dark lines, a dark ground
    below row 110 (or a floor as light as the rest), print grain."""
    rng = np.random.default_rng(seed)
    img = np.full((height, width), 0.85)
    img[::12] = img[:, ::12] = 0.7  # printed faint
    if ground:
        img[110:] = 0.3
    return np.clip(img + rng.normal(0, 0.02, img.shape), 0, 1)


def _animal(cell, x, top, lift=0):
    """An animal standing on the scene's ground (row 110), or ``lift`` rows above it, in a
    cell cropped from scene row ``top``."""
    y = 88 - top - lift
    cv2.ellipse(cell, (x, y), (30, 12), 0, 0, 360, 0.15, -1)
    for dx in (-20, 15):  # legs
        cv2.line(cell, (x + dx, y + 5), (x + dx + 3, 109 - top - lift), 0.15, 4)


def _plate(tops, widths, gutters, per_row, height=80, lifts=None, ground=True):
    """Cells of the scene, cell k from row tops[k] (its crop's error) with its animal
    lifts[k] rows off the ground, placed on a black plate in rows of ``per_row``; returns
    the plate and the cells' boxes."""
    lifts = lifts or [0] * len(tops)
    scene = _scene(ground=ground)
    rows = [list(range(i, min(i + per_row, len(tops)))) for i in range(0, len(tops), per_row)]
    plate = np.full((8 + len(rows) * (height + 9), 8 + sum(widths[:per_row]) + 80), 0.06)
    boxes, y = [], 8
    for row in rows:
        x = 8
        for k in row:
            cell = scene[tops[k]:tops[k] + height, 40 * k:40 * k + widths[k]].copy()
            _animal(cell, 50 + 3 * k, tops[k], lifts[k])
            grain = np.random.default_rng(k).normal(0, 0.02, cell.shape)  # on the animal too
            plate[y:y + height, x:x + widths[k]] = np.where(cell == 0.15, cell + grain, cell)
            boxes.append((x, y, x + widths[k], y + height))
            x += widths[k] + gutters[k]
        y += height + 9
    return plate.astype(np.float32), boxes


def test_cells_are_found_in_reading_order_and_lined_up_on_the_backdrop():
    tops = [40, 42, 37, 44, 39, 43]
    widths = [120, 118, 121, 120, 117, 122]
    plate, boxes = _plate(tops, widths, gutters=[5, 9, 0, 4, 7, 0], per_row=3)
    found = find_cells(plate)
    assert found == [(x0 + BORDER, y0 + BORDER, x1 - BORDER, y1 - BORDER)
                     for x0, y0, x1, y1 in boxes]
    cells, frames = import_plate(plate)
    for k, cell in enumerate(cells):
        # the first cell's row r is scene row tops[0] + r, this cell's tops[k] + r
        assert cell.offset[1] == pytest.approx(tops[0] - tops[k], abs=0.3), k
        assert cell.offset[0] == 0.0
    for frame in frames:  # the ground's edge on one row in every frame
        assert frame.shape == frames[0].shape
        edge = np.argmin(np.diff(np.median(frame, axis=1)))
        assert edge == np.argmin(np.diff(np.median(frames[0], axis=1)))
    assert not any(c.off_feet for c in cells) and unconfirmed(cells) == ""


def test_a_cell_whose_animal_is_off_the_ground_is_lined_up_by_the_backdrop_and_named():
    """A light floor (no ground line): the animals' feet stand the cells on one ground, but
    the fifth leaps 15 rows, and its cell is lined up by the grid alone and named to check.
    (A smaller leap can land on a weak match near where its feet point: 9 rows up took a
    match scoring 0.08 seven rows off the true one, scoring 1.)"""
    tops = [40, 42, 37, 44, 39, 43]
    plate, _ = _plate(tops, [120, 118, 121, 120, 117, 122], gutters=[5, 9, 0, 4, 7, 0],
                      per_row=3, lifts=[0, 0, 0, 0, 15, 0], ground=False)
    cells, _ = import_plate(plate)
    for k, cell in enumerate(cells):
        assert cell.offset[1] == pytest.approx(tops[0] - tops[k], abs=0.3), k
    assert [c.off_feet for c in cells] == [False, False, False, False, True, False]
    assert unconfirmed(cells).startswith("cell 5 lined up by the backdrop alone")


def test_a_row_printed_edge_to_edge_is_split_by_how_often_it_repeats():
    tops = [40] * 5
    plate, boxes = _plate(tops, [130] * 5, gutters=[0] * 5, per_row=5)
    found = find_cells(plate)
    assert len(found) == 5
    for (x0, _, x1, _), (bx0, _, bx1, _) in zip(found, boxes):
        assert abs(x0 - bx0) <= 2 and abs(x1 - bx1) <= 2
    assert len(find_cells(plate, per_row=4)) == 4  # the caller may say otherwise


def test_an_image_that_is_not_a_plate_is_refused():
    with pytest.raises(PlateError, match="fewer than two cells"):
        find_cells(np.full((100, 150), 0.8, np.float32))


def _ground(frame):
    """The ground line: the strongest light-to-dark step down the row medians of the
    frame's lower half (a check independent of the registration's own profile match)."""
    steps = np.diff(np.median(frame, axis=1))
    low = len(steps) // 2
    return low + int(np.argmin(steps[low:-2]))


def _printed(name, n_cells):
    """A printed plate's grey image and its cells (as many as printed, of one size)."""
    with quiet_stderr():
        grey = load_grey(PLATES / f"plate_{name}.png")
    cells, frames = import_plate(grey)
    assert len(cells) == n_cells
    widths = [c.box[2] - c.box[0] for c in cells]
    assert max(widths) < 1.1 * min(widths)  # cells of one size, as printed
    return grey, cells, frames


@pytest.mark.parametrize("name, n_cells", [("camel", 10), ("mule", 8)])
def test_printed_plates_give_their_cells_with_the_ground_line_lined_up(name, n_cells):
    grey, cells, frames = _printed(name, n_cells)
    raw = [grey[y0:y1, x0:x1] for x0, y0, x1, y1 in (c.box for c in cells)]
    near = [sum(abs(_ground(f) - _ground(fs[0])) <= 1 for f in fs[1:]) for fs in (raw, frames)]
    assert near[1] > near[0] and near[1] >= 0.6 * (n_cells - 1), near


@pytest.mark.parametrize("name, n_cells", [("baboon", 12), ("camel", 10)])
def test_printed_plates_stand_the_clicked_feet_on_one_ground(name, n_cells):
    """The feet clicked by hand on every frame (``bench/data/plates``; a walker and a
    galloper always have one down, near enough) stand on one ground: the lowest clicked
    foot of each frame within 3 pixels of their median over the frames. The baboon's
    floor shows no ground line, and its measuring grid matches itself a square off."""
    _, cells, _ = _printed(name, n_cells)
    spec = json.loads((ROOT / "bench" / "data" / "plates" / f"{name}.json").read_text())
    lowest = []
    for k, cell in enumerate(cells):
        clicked = spec["scored"][str(k + 1)]
        feet = max(y for _, y in clicked["fore"] + clicked["hind"])  # clicked on the old cut
        lowest.append(feet + spec["scored_cut"][k] - cell.offset[1])
    assert np.abs(np.array(lowest) - np.median(lowest)).max() <= 3, np.round(lowest, 1)
    if name == "baboon":  # a walker: every cell's feet on the ground bear its offset out
        assert unconfirmed(cells) == ""


def test_register_finds_a_known_shift_to_a_fraction_of_a_pixel():
    scene = _scene()
    ref = scene[40:120, 100:220].astype(np.float32)
    moved = cv2.warpAffine(scene.astype(np.float32), np.float32([[1, 0, 0], [0, 1, -2.4]]),
                           (scene.shape[1], scene.shape[0]))[40:120, 100:220]
    # warpAffine's forward map: moved's row r shows scene row r + 40 + 2.4, so the
    # reference's row p is at p - 2.4 there
    assert register(ref, moved)[1] == pytest.approx(-2.4, abs=0.25)


def test_the_command_line_writes_one_image_per_cell(tmp_path):
    out = tmp_path / "frames"
    proc = subprocess.run([sys.executable, "-m", "core", "plate",
                           str(PLATES / "plate_camel.png"), "--out", str(out)],
                          cwd=ROOT, capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    files = sorted(out.glob("*.png"))
    assert [f.name for f in files] == [f"plate_camel_{i:02d}.png" for i in range(1, 11)]
    sizes = {cv2.imread(str(f), cv2.IMREAD_UNCHANGED).shape for f in files}
    assert len(sizes) == 1 and "10 cells in 2 rows" in proc.stderr
    assert "note:" not in proc.stderr  # the camel's cells: none to check
    mule = subprocess.run([sys.executable, "-m", "core", "plate",
                           str(PLATES / "plate_mule.png"), "--out", str(tmp_path / "mule")],
                          cwd=ROOT, capture_output=True, text=True)
    with quiet_stderr():
        doubtful = unconfirmed(import_plate(load_grey(PLATES / "plate_mule.png"))[0])
    assert doubtful and f"note: {doubtful}" in mule.stderr  # it rears: cells to look at
    assert "libpng" not in proc.stderr
    bad = subprocess.run([sys.executable, "-m", "core", "plate", str(tmp_path / "none.png"),
                          "--out", str(out)], cwd=ROOT, capture_output=True, text=True)
    assert bad.returncode == 2 and "no such image" in bad.stderr

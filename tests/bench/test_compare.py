"""Two suite tables compared: rows read back as the suite writes them, and a clip-look
counted as moved only beyond both runs' spreads, the first's widened by its twins'."""

import statistics
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

from compare import Row, compare, moved, pooled, read_flags, read_rows  # noqa: E402
from suite import table  # noqa: E402

RUN = "3 views 15 fps"


def _row(tracker, low, high, best=1.0, flags=(10, 20, 40)) -> dict:
    return {"tracker": tracker, "low": low, "high": high, "still": 30.0, "best": best,
            "tracked": 88, "of": 88, "stopped": 0, "starts": 3, "fps": 5.0, "peak_mb": 200,
            "flags": flags}


def _text(rows: dict) -> str:
    # a log: other lines around the tables, as ``bench/suite.py`` prints them
    return "\n".join(["CMU 131 walk / muybridge / 3 views 15 fps from frame 0: 5.0°", ""]
                     + table(rows, [RUN]) + ["", "suite time 250 s"])


BEFORE = {("walk", "ruled", RUN): _row(5.0, 4.5, 5.5),
          ("dance", "sun", RUN): _row(20.0, 18.0, 23.0, best=2.5, flags=(30, 40, 100)),
          ("turn", "park", RUN): _row(12.0, 11.0, 13.0)}


def test_rows_and_flags_read_back_as_the_suite_writes_them():
    rows = read_rows(_text(BEFORE))
    assert set(rows) == set(BEFORE)
    assert rows["dance", "sun", RUN] == Row(20.0, 18.0, 23.0, 30.0, 2.5)
    # the flags: caught of the limbs far off, right of the flags, summed over the rows
    assert read_flags(_text(BEFORE)) == {RUN: (round(100 * 50 / 80), round(100 * 50 / 180))}


def test_a_clip_look_moves_only_beyond_both_spreads():
    assert moved(Row(5.0, 4.5, 5.5, 30, 1), Row(6.5, 6.0, 7.0, 30, 1)) == 1
    assert moved(Row(5.0, 4.5, 5.5, 30, 1), Row(3.9, 3.5, 4.2, 30, 1)) == -1
    # outside the first's range, but the first's mean inside the second's
    assert moved(Row(5.0, 4.5, 5.5, 30, 1), Row(6.5, 4.8, 8.0, 30, 1)) == 0
    assert moved(Row(5.0, 4.5, 5.5, 30, 1), Row(5.4, 5.0, 5.8, 30, 1)) == 0


def test_the_comparison_names_what_moved_and_summarises_the_common_clip_looks():
    after = dict(BEFORE)
    after["dance", "sun", RUN] = _row(30.0, 28.0, 31.0, best=2.5, flags=(30, 40, 100))
    after["walk", "ruled", RUN] = _row(5.2, 4.9, 5.6)
    after["new", "look", RUN] = _row(50.0, 49.0, 51.0)  # in one file only: left out
    lines = compare(_text(BEFORE), _text(after))
    worse = [ln for ln in lines if "worse" in ln]
    assert worse == ["  worse: dance, sun: 20.0 (18.0-23.0) -> 30.0 (28.0-31.0)"]
    assert not any("better" in ln or "walk" in ln for ln in lines)
    was, now = [5.0, 20.0, 12.0], [5.2, 30.0, 12.0]
    assert lines[0] == (
        f"{RUN}, 3 clip-looks: median / mean / worst {statistics.median(was):.1f} / "
        f"{statistics.fmean(was):.2f} / 20.0 (+11.0 / +17.5 over best fit) -> "
        f"{statistics.median(now):.1f} / {statistics.fmean(now):.2f} / 30.0 "
        "(+11.0 / +27.5 over best fit)")
    # the flags as each file's summary gives them: over all its rows, the new one's too
    assert lines[1] == "  flags caught / right 62 / 28 % -> 60 / 27 %"


def test_a_run_without_change_says_so():
    lines = compare(_text(BEFORE), _text(BEFORE))
    assert lines[-1] == "  no clip-look moved beyond its spread"


def test_twins_pool_with_the_first_run():
    a, b = Row(20.0, 18.0, 23.0, 30, 2.5), Row(28.0, 25.0, 32.0, 31, 2.4)
    both = pooled([a, b])
    assert both == Row(24.0, 18.0, 32.0, 30, 2.5)
    assert pooled([a]) == a


def test_a_move_inside_what_a_twin_moved_is_no_move():
    # the dance read 28 when nothing but chaos changed: a change reading 30 has not moved it
    after = dict(BEFORE)
    after["dance", "sun", RUN] = _row(30.0, 28.0, 31.0, best=2.5, flags=(30, 40, 100))
    twin = dict(BEFORE)
    twin["dance", "sun", RUN] = _row(28.0, 25.0, 32.0, best=2.5, flags=(30, 40, 100))
    lines = compare(_text(BEFORE), _text(after), twins=[_text(twin)])
    assert lines[-1] == "  no clip-look moved beyond its spread"
    # the before side's summary is the pooled one: the dance's mean of 20 and 28
    assert "/ 24.0 (" in lines[0].split("->")[0]
    # a twin that stayed put leaves the verdict as it was
    lines = compare(_text(BEFORE), _text(after), twins=[_text(BEFORE)])
    assert [ln for ln in lines if "worse" in ln] == [
        "  worse: dance, sun: 20.0 (18.0-23.0) -> 30.0 (28.0-31.0)"]

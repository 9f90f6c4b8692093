"""Two suite runs side by side: which clip-looks a change moved beyond their starts' spread.

    python bench/compare.py BEFORE AFTER [--runs "3 views 15 fps,..."] [--twins TWIN ...]

BEFORE and AFTER are what ``bench/suite.py`` printed (its log) or wrote (``--write``): the
per-clip table's rows are read wherever they stand in the file, every other line is passed
over. For each run: the median, mean and worst limb-direction error over the clip-looks
both files hold, and their median and worst over the best fit; the flags' catch and
precision where the summary table is there too (each file's own, over all its rows); and
every clip-look that moved.

Tracking is chaotic, so a clip-look moved only where each file's mean over its starting
frames lies outside the other's lowest-highest range: a difference inside the spread of a
few starts is no difference. A file tracked from one start has no spread, and every
difference in it reads as a move.

Three starts understate the chaos: the same code with one default setting nudged in its
seventh digit (``bench/suite.py --settings '{"damping": 0.010000001}'``), or every pixel's
weight changed by a part in 10^12, moves the worst clip-looks by several degrees beyond their
starts' spread. TWIN files are such runs of BEFORE's code: BEFORE and its twins are pooled
(``pooled``), its mean over theirs and its range from their lowest to their highest, so that
a clip-look moves only beyond what a change of nothing moves it by.
"""

from __future__ import annotations

import argparse
import re
import statistics
import sys
from collections.abc import Sequence
from dataclasses import dataclass
from pathlib import Path

_DEG = r"(-?[\d.]+)°"
# a row of the per-clip table: clip | look | run | tracker | lowest-highest | held still |
# best fit | frames | image err
_ROW = re.compile(r"^\| ([^|]+?) \| ([^|]+?) \| ([^|]+?) \| " + _DEG + r" \| (-?[\d.]+)-"
                  + _DEG + r" \| " + _DEG + r" \| " + _DEG + r" \|")
# the flags' two cells of a summary row: "86 % of 2094 | 27 % of 6692"
_FLAGS = re.compile(r"\| (\d+) % of (\d+) \| (\d+) % of (\d+) \|")


@dataclass(frozen=True)
class Row:
    """One clip, look and run: the tracker's mean error over its starts and their lowest
    and highest, the first pose held still and the best fit, degrees."""

    tracker: float
    low: float
    high: float
    still: float
    best: float


def read_rows(text: str) -> dict[tuple[str, str, str], Row]:
    """The per-clip table's rows of a suite log or results file, by (clip, look, run)."""
    out = {}
    for line in text.splitlines():
        m = _ROW.match(line.strip())
        if m and m.group(1) != "clip":
            clip, look, run = (g.strip() for g in m.groups()[:3])
            out[clip, look, run] = Row(*(float(g) for g in m.groups()[3:]))
    return out


def read_flags(text: str) -> dict[str, tuple[int, int]]:
    """Per run of the summary table, the flags' catch and precision in %."""
    out = {}
    for line in text.splitlines():
        m = _FLAGS.search(line)
        if m and line.startswith("| "):
            out[line.split("|")[1].strip()] = (int(m.group(1)), int(m.group(3)))
    return out


def pooled(rows: list[Row]) -> Row:
    """Runs of one code (a file and its twins) as one: the mean of their means, their
    lowest and highest starts, the held-still and best-fit references of the first."""
    return Row(statistics.fmean(r.tracker for r in rows), min(r.low for r in rows),
               max(r.high for r in rows), rows[0].still, rows[0].best)


def moved(before: Row, after: Row) -> int:
    """+1 where ``after`` is worse beyond both runs' spreads, -1 better, 0 neither."""
    if after.tracker > before.high and before.tracker < after.low:
        return 1
    if after.tracker < before.low and before.tracker > after.high:
        return -1
    return 0


def _summary(rows: list[Row]) -> str:
    err = [r.tracker for r in rows]
    over = [r.tracker - r.best for r in rows]
    return (f"{statistics.median(err):.1f} / {statistics.fmean(err):.2f} / {max(err):.1f}"
            f" ({statistics.median(over):+.1f} / {max(over):+.1f} over best fit)")


def compare(before_text: str, after_text: str, runs: list[str] | None = None,
            twins: Sequence[str] = ()) -> list[str]:
    """The comparison's lines: per run, the summaries before -> after over the clip-looks
    both hold, the flags, and each clip-look that moved (``moved``); ``twins``: texts of
    runs of the before's code with nothing changed but chaos, pooled with it where they
    hold the clip-look (``pooled``)."""
    before, after = read_rows(before_text), read_rows(after_text)
    twin_rows = [read_rows(t) for t in twins]
    before = {k: pooled([r, *(t[k] for t in twin_rows if k in t)]) for k, r in before.items()}
    flags_before, flags_after = read_flags(before_text), read_flags(after_text)
    common = [k for k in before if k in after]
    lines = []
    for run in runs or list(dict.fromkeys(k[2] for k in common)):
        keys = [k for k in common if k[2] == run]
        if not keys:
            lines.append(f"{run}: in one file only")
            continue
        lines.append(f"{run}, {len(keys)} clip-looks: median / mean / worst "
                     f"{_summary([before[k] for k in keys])} -> "
                     f"{_summary([after[k] for k in keys])}")
        if run in flags_before and run in flags_after:
            (c0, r0), (c1, r1) = flags_before[run], flags_after[run]
            lines.append(f"  flags caught / right {c0} / {r0} % -> {c1} / {r1} %")
        ways = {k: moved(before[k], after[k]) for k in keys}
        for k, way in ways.items():
            if way:
                b, a = before[k], after[k]
                lines.append(f"  {'worse' if way > 0 else 'better'}: {k[0]}, {k[1]}: "
                             f"{b.tracker:.1f} ({b.low:.1f}-{b.high:.1f}) -> "
                             f"{a.tracker:.1f} ({a.low:.1f}-{a.high:.1f})")
        if not any(ways.values()):
            lines.append("  no clip-look moved beyond its spread")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("before", type=Path, help="a suite log or results file")
    ap.add_argument("after", type=Path, help="another, of the change")
    ap.add_argument("--runs", help="comma-separated run names (default: every run in both)")
    ap.add_argument("--twins", type=Path, nargs="*", default=[],
                    help="runs of BEFORE's code with a setting nudged in its seventh digit")
    a = ap.parse_args(argv)
    runs = a.runs.split(",") if a.runs else None
    print("\n".join(compare(a.before.read_text(), a.after.read_text(), runs,
                            [t.read_text() for t in a.twins])))
    return 0


if __name__ == "__main__":
    sys.exit(main())

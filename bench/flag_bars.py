"""The flags' bars read again over the suite's reports: what a pair of bars would catch.

    python bench/flag_bars.py [--runs "1 lateral view 15 fps,3 views 15 fps,..."]
                              [--clips NAME,...] [--half-size] [--exposure-drift]
                              [--enter 0.35,0.45,...] [--clear 0.9,0.95,0.99] [--weight W]

The flags do not steer the tracker (``core.confidence``: the tracker's doubt reads its own
confidence, at its own bars): the report's confidences are what the flags are read from, so
the suite's runs need not be tracked again to see other bars. For every report
``bench/suite.py`` left in ``.cache/suite`` for the runs with the default settings (every
clip, look and start, or the ``--clips`` named; the footage at full size, or halved or its
exposure drifting, as the suite's ``--half-size`` and ``--exposure-drift``), each limb's
flag is read again at each pair of bars from its confidence, with one view over one plus
``--weight`` times its unexplained foreground (``LimbCheck.flag_confidence``;
``confidence.reading``, each limb's flag on the frame before carried on), and scored as the
suite scores flags (``suite.flag_counts``): % of the limbs over ``suite.BAD_LIMB_DEG`` off
that are flagged / % of the flags on such limbs.
The reports keep confidences to three places, so a count can differ from the suite's by the
few limb-frames that lie on a bar. ``core.confidence.UNEXPLAINED_WEIGHT`` and the flags' bars
were chosen this way (``docs/RESEARCH.md``).
"""

from __future__ import annotations

import argparse
import copy
import json
import re
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

from suite import CACHE, flag_counts, slug, tracked_and_true  # noqa: E402
from suite_footage import DRIFT, HALF, LOOKS  # noqa: E402

from core.confidence import CLEAR, DOUBT, UNEXPLAINED_WEIGHT, discounted, reading  # noqa: E402


def reflagged(rep: dict, enter: float, clear: float, weight: float = UNEXPLAINED_WEIGHT
              ) -> dict:
    """A copy of a report (``python -m core track --report``) with every limb's flag read at
    bars ``enter`` and ``clear`` (from its confidence, with one view over one plus its
    unexplained foreground, ``LimbCheck.flag_confidence``), frame after frame in order; a
    frame without checks (one the user gave) starts every limb afresh."""
    out = copy.deepcopy(rep)
    before: dict[str, bool] = {}
    for fr in out["frames"]:
        if not fr["limbs"]:
            before = {}
        for name, check in fr["limbs"].items():
            seen = any(v is not None for v in check["views"])
            confidence = discounted(check["confidence"], check.get("unexplained"), weight)
            check["flag"] = reading(confidence, seen, before.get(name, False), enter, clear)
            before[name] = bool(check["flag"])
    return out


def run_reports(run: str, clips: list[str] | None = None, footage: str = ""
                ) -> list[tuple[Path, int]]:
    """The jobs of ``run`` the suite's cache holds tracked with the default settings (every
    start; not those of ``--settings``, whose names carry them) on the suite's looks, their
    names followed by ``footage`` (``""``, ``suite_footage.HALF`` or ``DRIFT``), as
    (job, start)."""
    looks = {slug(look) + footage for look in LOOKS}
    out = []
    for rep in sorted(CACHE.glob(f"*/*__{slug(run)}*.report.json")):
        job = rep.with_name(rep.name.replace(".report.json", ".json"))
        look, tail = job.stem.split(f"__{slug(run)}", 1)
        if look not in looks or tail and not re.fullmatch(r"__from_\d+", tail):
            continue
        if clips is not None and job.parent.name not in {slug(c) for c in clips}:
            continue
        start = int(tail[len("__from_"):]) if tail else 0
        out.append((job, start))
    return out


def bar_table(run: str, jobs: list[tuple[Path, int]], enters: list[float],
              clears: list[float], weight: float = UNEXPLAINED_WEIGHT) -> list[str]:
    """Caught / right (%) per pair of bars over ``jobs`` at the unexplained foreground's
    ``weight``, as Markdown: a row per enter bar, a column per clear bar; the bars in use
    starred."""
    sums = {(e, c): [0, 0, 0] for e in enters for c in clears}
    for job, start in jobs:
        rep = json.loads(job.with_suffix(".report.json").read_text())
        tracked, limbs, est, truth = tracked_and_true(job, run, start)
        for (e, c), total in sums.items():
            counts = flag_counts(reflagged(rep, e, c, weight), tracked.skeleton, est, truth,
                                 limbs)
            total[:] = [a + b for a, b in zip(total, counts)]
    lines = [f"{run}, {len(jobs)} runs, unexplained foreground weighed {weight:g}: % of limbs "
             "far off flagged / % of flags right", "",
             "| enter \\ clear | " + " | ".join(f"{c:g}" for c in clears) + " |",
             "|---" * (len(clears) + 1) + "|"]
    for e in enters:
        cells = []
        for c in clears:
            caught, bad, flagged = sums[e, c]
            star = "*" if (e, c) == (DOUBT, CLEAR) else ""
            cells.append(f"{star}{100 * caught / max(bad, 1):.0f} / "
                         f"{100 * caught / max(flagged, 1):.0f}{star}")
        lines.append(f"| {e:g} | " + " | ".join(cells) + " |")
    return lines


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--runs", default="1 lateral view 15 fps,1 lateral view 30 fps",
                    help="comma-separated run names")
    ap.add_argument("--clips", help="comma-separated clip names (default: every one tracked)")
    ap.add_argument("--half-size", action="store_true",
                    help="the runs on the footage halved (the suite's --half-size)")
    ap.add_argument("--exposure-drift", action="store_true",
                    help="the runs with the exposure drifting (the suite's --exposure-drift)")
    ap.add_argument("--enter", default="0.35,0.45,0.5,0.55,0.6,0.65")
    ap.add_argument("--clear", default="0.9,0.95,0.99")
    ap.add_argument("--weight", type=float, default=UNEXPLAINED_WEIGHT,
                    help="the unexplained foreground's weight in the flag's confidence")
    a = ap.parse_args(argv)
    enters = [float(x) for x in a.enter.split(",")]
    clears = [float(x) for x in a.clear.split(",")]
    for run in a.runs.split(","):
        jobs = run_reports(run, a.clips.split(",") if a.clips else None,
                           HALF * a.half_size + DRIFT * a.exposure_drift)
        if not jobs:
            raise SystemExit(f"{run}: no tracked reports in {CACHE} (run bench/suite.py)")
        print("\n".join(bar_table(run, jobs, enters, clears, a.weight)) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

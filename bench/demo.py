"""The demo: render a short clip of the CMU walk in three views and track it from the command
line, as a user of ``python -m core track`` would.

    python bench/demo.py [--out .cache/demo]

Prints where the footage, the job, the tracked BVH and the report went, and how far the tracked
limbs are from the capture.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import evaluate  # noqa: E402
from walk_footage import CAPTURE_FPS, render, write_job  # noqa: E402

from core.bvh import read_bvh  # noqa: E402
from core.job import load_job  # noqa: E402

FIRST, LAST, STEP = 540, 660, 8  # one second of steady walking at 15 frames per second


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / ".cache" / "demo")
    a = ap.parse_args(argv)
    views = ["lateral", "endon", "oblique60"]
    info = render(a.out, FIRST, LAST, STEP, views)
    job = write_job(a.out, "walk_3views", views, "calibrated", info["frames"], info["cameras"],
                    {}, STEP / CAPTURE_FPS)
    out, rep = a.out / "walk_3views.bvh", a.out / "walk_3views.report.json"
    cmd = [sys.executable, "-m", "core", "track", str(job), "--out", str(out),
           "--report", str(rep)]
    print("$", " ".join(cmd), flush=True)
    code = subprocess.run(cmd, cwd=ROOT).returncode
    if code not in (0, 3):
        return code
    sk = load_job(job).skeleton
    tracked = [sk.names[j] for j in sorted(set(sk.dof_joints_and_axes()[0].tolist()))]
    truth = read_bvh(a.out / "truth.bvh").poses()
    scores = evaluate.score(sk, tracked, read_bvh(out).poses(), truth)
    still = evaluate.score(sk, tracked, evaluate.held_still(truth), truth)
    report = json.loads(rep.read_text())
    n = len(info["frames"])
    print(f"\nfootage  {a.out}/<view>/NNNN.png ({n} frames x {len(views)} views)")
    print(f"job      {job}")
    print(f"tracked  {out}")
    print(f"report   {rep}")
    print(f"limb-direction error {scores.limb_mean_deg:.1f} deg over the eight limbs"
          f" (first frame held still: {still.limb_mean_deg:.1f} deg);"
          f" {report['frames_per_second']:.1f} frames per second")
    return code


if __name__ == "__main__":
    sys.exit(main())

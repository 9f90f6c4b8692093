"""How much a tracking result depends on where it starts: the three-view calibrated walk of
bench/walk_benchmark.py tracked from several first frames, forward and backward, each run
scored against the capture, with their mean; or, with --windows K, many short runs that
show how fast a limb is lost from the true pose, with far less spread than whole runs.

    python bench/start_spread.py [--zoom 1 [--zoomed VIEW,...]] [--quick | --windows K]
                                 [--settings JSON] [--spine]

A run starting on frame k of the 30 fps footage is posed there with the capture's pose; a
15 fps run takes every other frame from there. Sixteen runs (15 fps forward from frames 0-5
and backward from 118-113, 30 fps forward from 0 and 1 and backward from 118 and 117), or
eight with --quick (15 fps forward from 0-3 and backward from 118 and 117, 30 fps forward
from 0 and backward from 118). Two runs at a time, one per core.

A window of K frames starts from the capture's pose on its first two frames (the second is
given as a user's correction: the key frame, and the velocity known) and tracks K more: 15 fps
forward from every 8th frame and backward from every 8th, 30 fps forward from every 12th
(38 windows for K = 6). Scored on the tracked frames only, and on each window's last.

With --zoomed, only the named views come from the --zoom footage and the others from the
480x360 one: views of different sizes in one job.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from multiprocessing import Pool
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import evaluate  # noqa: E402
from walk_benchmark import RUNS  # noqa: E402
from walk_footage import (  # noqa: E402
    CAPTURE_FPS,
    add_footage_arguments,
    add_spine_argument,
    footage_cache,
    render,
    tracked_joints,
    write_job,
)

from core.bvh import read_bvh  # noqa: E402
from core.job import load_job  # noqa: E402
from core.pose import BodyPose  # noqa: E402
from core.tracker import Tracker, track  # noqa: E402

N_FRAMES = 119  # the footage: frames 300-772 of the capture at 30 fps


def starts(quick: bool) -> dict[str, list[int]]:
    """Run name -> the footage frames it tracks, in order."""
    fwd15, bwd15 = (range(4), (118, 117)) if quick else (range(6), range(118, 112, -1))
    fwd30, bwd30 = ((0,), (118,)) if quick else ((0, 1), (118, 117))
    runs = {f"15 fps forward from {k}": list(range(k, N_FRAMES, 2)) for k in fwd15}
    runs |= {f"15 fps backward from {k}": list(range(k, -1, -2)) for k in bwd15}
    runs |= {f"30 fps forward from {k}": list(range(k, N_FRAMES)) for k in fwd30}
    runs |= {f"30 fps backward from {k}": list(range(k, -1, -1)) for k in bwd30}
    return runs


def windows(k: int) -> dict[str, list[int]]:
    """Window name -> its footage frames in order: two given, then ``k`` tracked."""
    runs = {f"15 fps forward from {s}": list(range(s, s + 2 * k + 3, 2))
            for s in range(0, N_FRAMES - 2 * k - 2, 8)}
    runs |= {f"15 fps backward from {s}": list(range(s, s - 2 * k - 3, -2))
             for s in range(N_FRAMES - 1, 2 * k + 1, -8)}
    runs |= {f"30 fps forward from {s}": list(range(s, s + k + 2))
             for s in range(0, N_FRAMES - k - 1, 12)}
    return runs


def one_run(args: tuple) -> tuple[str, evaluate.Scores, int, float]:
    """Track one run's frames from the capture's pose on its first ``given`` (1 or 2; a
    second is the key frame and sets the velocity); the scores of the tracked frames (with
    the first, at 0, for a whole run), the frames it tracked and its frames per second."""
    name, frames, job_path, truth_path, given = args
    job = load_job(job_path)
    R, P = read_bvh(truth_path).poses()
    truth = (R[frames], P[frames])

    def capture(i):
        return BodyPose(truth[0][i].copy(), truth[1][i].copy(), [c.copy() for c in job.cameras])

    tracker = Tracker(job.skeleton, job.images, job.mode, job.settings)
    t0 = time.perf_counter()
    result = track(tracker, capture(0), frames, corrections={frames[1]: capture(1)}
                   if given == 2 else None)
    fps = (len(result.frames) - given) / (time.perf_counter() - t0)
    est = (np.array([f.pose.rotations for f in result.frames]),
           np.array([f.pose.root_position for f in result.frames]))
    sk = job.skeleton
    tracked = sk.tracked_joint_names()
    skip = given if given > 1 else 0  # a whole run keeps its first frame in the score
    scores = evaluate.score(sk, tracked, (est[0][skip:], est[1][skip:]),
                            (truth[0][skip:], truth[1][skip:]))
    return name, scores, len(result.frames), fps


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_footage_arguments(ap)
    ap.add_argument("--quick", action="store_true", help="eight runs instead of sixteen")
    ap.add_argument("--windows", type=int, default=0, metavar="K",
                    help="short runs of K tracked frames from the true pose instead")
    ap.add_argument("--settings", default="{}", help="tracker settings (JSON) for every run")
    add_spine_argument(ap)
    ap.add_argument("--zoomed", default="", metavar="VIEW,...",
                    help="only these views from the --zoom footage, the rest at 480x360")
    a = ap.parse_args(argv)
    a.cache = footage_cache(a)
    t0 = time.perf_counter()
    views, mode, _, _ = RUNS["3 views calibrated 30 fps"]
    info = render(a.cache, 300, 772, 4, views, a.zoom)
    zoomed = [v for v in a.zoomed.split(",") if v]
    if set(zoomed) - set(views):
        ap.error(f"--zoomed: the views are {', '.join(views)}")
    if zoomed:  # the job lives with the small footage and reaches into the zoomed one
        zoomed_cache, zoomed_cameras = a.cache, info["cameras"]
        a.cache = footage_cache(argparse.Namespace(zoom=1, cache=None))
        info = render(a.cache, 300, 772, 4, views, 1)
    job_path = write_job(a.cache, "start_spread", views, mode, info["frames"], info["cameras"],
                         json.loads(a.settings), 4 / CAPTURE_FPS,
                         tracked_joints(a))
    if zoomed:
        job = json.loads(job_path.read_text())
        for name, view in zip(views, job["views"]):
            if name in zoomed:
                view["images"] = [str(zoomed_cache / name / Path(p).name)
                                  for p in view["images"]]
                view["camera"] = zoomed_cameras[name]
        job_path.write_text(json.dumps(job, indent=1))
    runs = windows(a.windows) if a.windows else starts(a.quick)
    given = 2 if a.windows else 1
    with Pool(2) as pool:
        out = pool.map(one_run, [(name, frames, str(job_path), str(a.cache / "truth.bvh"),
                                  given) for name, frames in runs.items()])
    limbs = list(out[0][1].limb_deg)
    if a.windows:
        print_windows(out, runs, limbs, time.perf_counter() - t0)
        return 0
    print("| run | frames | limb dir. err (8 limbs) | " + " | ".join(limbs) + " | fps |")
    print("|---" * (len(limbs) + 4) + "|")
    for name, scores, n, fps in out:
        print(f"| {name} | {n}/{len(runs[name])} | {scores.limb_mean_deg:.1f}° | "
              + " | ".join(f"{scores.limb_deg[k]:.1f}" for k in limbs) + f" | {fps:.1f} |")
    means = [s.limb_mean_deg for _, s, _, _ in out]
    print(f"\nmean of the {len(out)} runs: {np.mean(means):.2f}° (median {np.median(means):.1f},"
          f" worst {np.max(means):.1f}); {time.perf_counter() - t0:.0f} s")
    return 0


def print_windows(out: list, runs: dict, limbs: list[str], seconds: float) -> None:
    """Per limb, the mean over every window's tracked frames, and the eight limbs' mean on
    the windows' last frames."""
    complete = sum(n == len(runs[name]) for name, _, n, _ in out)
    print(f"{len(out)} windows of {len(next(iter(runs.values()))) - 2} tracked frames, "
          f"{complete} tracked to the end; {seconds:.0f} s\n")
    print("| limb direction (°) | mean over the windows' frames |")
    print("|---|---|")
    for k in limbs:
        print(f"| {k} | {np.mean([s.limb_deg[k] for _, s, _, _ in out]):.1f} |")
    mean = np.mean([s.limb_mean_deg for _, s, _, _ in out])
    last = np.mean([s.per_frame_limb_deg[-1] for _, s, _, _ in out])
    print(f"| mean of the eight limbs | {mean:.2f} (last frame {last:.2f}) |")


if __name__ == "__main__":
    sys.exit(main())

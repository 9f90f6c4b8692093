"""The tracking benchmark: rendered CMU walk, three Muybridge-style views, tracked through the
command line, scored against the capture.

    python bench/walk_benchmark.py [--zoom 1] [--runs NAME,...] [--settings JSON]
                                   [--correct-every N]

Renders the footage once (bench/walk_footage.py, cached), writes one job per run, runs
``python -m core track`` on each, and prints tables of limb-direction error, joint-position
error, the limb ends' distance from the truth in the footage, local-rotation error, frames
tracked before any divergence and speed, beside references on the same frames: the first
frame held still, the best fit that the tracked degrees of freedom allow to the true 3-D
joints, and for one view the limbs read in its image with nothing in depth (each true limb
laid into the image plane) and lifted into depth by their lengths, the depth signs guessed
by the steadiest motion (with their ends read exactly, and 1 and 2 pixels off). Each run
tracks the paper's 19 degrees of freedom, or ("+ spine") 22 with the lower back a ball too.
With --correct-every N, every N-th frame is given the capture's pose as a user's correction,
and the frames between are scored.
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import evaluate  # noqa: E402
from walk_footage import (  # noqa: E402
    CAPTURE_FPS,
    HEIGHT,
    JOINTS,
    SPINE_JOINTS,
    WIDTH,
    add_footage_arguments,
    footage_cache,
    render,
    write_job,
)

from core.bvh import read_bvh  # noqa: E402
from core.job import load_job  # noqa: E402
from core.side_on import side_on_skeleton  # noqa: E402

THREE = ["lateral", "endon", "oblique60"]
# one view on the stretch where the walker crosses it (the clip's first 22 frames at 15 fps
# are a kneel facing it), with the paper's 19 DOF and tracked side-on, the paper's answer to
# one camera (every joint that could turn in depth a hinge about the line of sight)
WALK_RUN = "1 lateral view 15 fps on the walk"
SIDE_ON_RUN = "1 lateral view 15 fps side-on on the walk"
STARTS = {WALK_RUN: 24, SIDE_ON_RUN: 24}  # a run's first frame, in its own frames (else 0)
RUN_SETTINGS = {SIDE_ON_RUN: {"side_on": True}}  # over --settings
# one view's limbs lifted into depth by their lengths (evaluate.lifted_from_the_image) with
# their ends read exactly and this many pixels off, the mean of LIFT_DRAWS draws of the noise
LIFT_PIXELS = (0, 1, 2)
LIFT_DRAWS = 8
# name: (views, mode, capture frames per video frame: 4 = 30 fps, 8 = 15 fps, tracked joints)
RUNS = {
    "3 views calibrated 15 fps": (THREE, "calibrated", 8, JOINTS),
    "1 lateral view 15 fps": (["lateral"], "calibrated", 8, JOINTS),
    "3 views independent 15 fps": (THREE, "independent", 8, JOINTS),
    "3 views calibrated 30 fps": (THREE, "calibrated", 4, JOINTS),
    "1 lateral view 30 fps": (["lateral"], "calibrated", 4, JOINTS),
    "3 views calibrated 15 fps + spine": (THREE, "calibrated", 8, SPINE_JOINTS),
    "1 lateral view 15 fps + spine": (["lateral"], "calibrated", 8, SPINE_JOINTS),
    "3 views independent 15 fps + spine": (THREE, "independent", 8, SPINE_JOINTS),
    "3 views calibrated 30 fps + spine": (THREE, "calibrated", 4, SPINE_JOINTS),
    WALK_RUN: (["lateral"], "calibrated", 8, JOINTS),
    SIDE_ON_RUN: (["lateral"], "calibrated", 8, JOINTS),
}


def one_step_poses(job, poses: tuple, at_truth: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """Each frame of ``job`` tracked alone from ``poses`` (rotations (F, J, 3, 3), roots
    (F, 3): the truth, or its best fit) of the frame before, predicted from those of the two
    before (the first from the one before), against frame 0's as the key frame: how well a
    single step follows the body, apart from how errors add up along the sequence. With
    ``at_truth`` the prediction is the frame's own pose: where the tracker's cost has its
    minimum, apart from how far its prediction and search start from it. Returns the
    tracked (rotations, roots), frame 0 the given one."""
    from core.pose import BodyPose, extrapolate
    from core.tracker import Tracker

    tracker = Tracker(job.skeleton, job.images, job.mode, job.settings, job.moving or None)

    def pose(i):
        return BodyPose(poses[0][i].copy(), poses[1][i].copy(), [c.copy() for c in job.cameras])

    est_R, est_p = [poses[0][0]], [poses[1][0]]
    for i in range(1, min(len(poses[0]), len(job.images[0]))):
        pred = (pose(i) if at_truth else pose(i - 1) if i == 1
                else extrapolate(pose(i - 2), pose(i - 1)))
        res = tracker.track_frame(pose(i - 1), i - 1, pose(0), 0, pred, i)
        est_R.append(res.pose.rotations)
        est_p.append(res.pose.root_position)
    return np.array(est_R), np.array(est_p)


def one_step(job_path: Path, truth: tuple, at_truth: bool = False) -> evaluate.Scores:
    """``one_step_poses`` of a job from the truth, scored against it."""
    job = load_job(job_path)
    tracked = job.skeleton.tracked_joint_names()
    return evaluate.score(job.skeleton, tracked, one_step_poses(job, truth, at_truth), truth)


# ``python -m core`` that writes, as it exits, its peak resident memory (Linux's VmHWM, in kB)
# to the file named by its first argument. (A child's ru_maxrss is no use here: Linux carries
# the parent's high-water mark over fork and exec, and this script holds Blender.)
_WITH_PEAK = """import atexit, runpy, sys
out = sys.argv.pop(1)
def peak():
    hwm = [line.split()[1] for line in open("/proc/self/status") if line.startswith("VmHWM")]
    open(out, "w").write(hwm[0])
atexit.register(peak)
runpy.run_module("core", run_name="__main__")
"""


def track_job(job_path: Path, out: Path, rep_path: Path) -> tuple[int, float]:
    """Run ``python -m core track`` on a job as a user would; its exit status and its peak
    resident memory in MB (the whole process: Python, numpy, OpenCV and the tracker). Its
    error output is passed on."""
    peak = rep_path.with_suffix(".peak")
    cmd = [sys.executable, "-c", _WITH_PEAK, str(peak), "track", str(job_path), "--out",
           str(out), "--report", str(rep_path), "--quiet"]
    code = subprocess.run(cmd, cwd=ROOT, stdout=subprocess.DEVNULL).returncode
    mb = int(peak.read_text()) / 1024
    peak.unlink()
    return code, mb


def fmt(x, digits=1):
    return "-" if x is None else f"{x:.{digits}f}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_footage_arguments(ap)
    ap.add_argument("--first", type=int, default=300)
    ap.add_argument("--last", type=int, default=772)
    ap.add_argument("--runs", default=",".join(RUNS), help="comma-separated run names")
    ap.add_argument("--settings", default="{}", help="tracker settings (JSON) for every run")
    ap.add_argument("--correct-every", type=int, default=0, metavar="N",
                    help="correct every N-th frame to the capture's pose, as a user would")
    a = ap.parse_args(argv)
    a.cache = footage_cache(a)
    t0 = time.perf_counter()
    info = render(a.cache, a.first, a.last, 4, THREE, a.zoom)
    print(f"footage: {len(info['frames'])} frames x 3 views at 30 fps in {a.cache}"
          f" ({info['rendered']} rendered, {time.perf_counter() - t0:.0f} s)", flush=True)
    truth_bvh = read_bvh(a.cache / "truth.bvh")
    truth_all = truth_bvh.poses()
    settings = json.loads(a.settings)

    results, refs, steps, flat, lifted, image_px = {}, {}, {}, {}, {}, {}
    # run name -> its references' key in refs: (frame step, first rendered frame, body)
    ref_of = {}
    for name in a.runs.split(","):
        views, mode, step, joints = RUNS[name]
        # the run's frames among the rendered ones (30 fps), which truth.bvh holds too
        sel = slice(STARTS.get(name, 0) * (step // 4), None, step // 4)
        job_path = write_job(a.cache, name.replace(" + ", "_").replace(" ", "_"), views, mode,
                             info["frames"][sel], info["cameras"],
                             settings | RUN_SETTINGS.get(name, {}),
                             step / CAPTURE_FPS, joints, a.correct_every)
        out = job_path.with_suffix(".bvh")
        rep_path = job_path.with_suffix(".report.json")
        code, peak_mb = track_job(job_path, out, rep_path)
        if code not in (0, 3):
            raise SystemExit(f"{name}: the tracker failed (exit {code})")
        rep = json.loads(rep_path.read_text())
        rep["peak_mb"] = peak_mb
        job = load_job(job_path)
        sk = job.skeleton
        tracked_names = sk.tracked_joint_names()
        truth = (truth_all[0][sel], truth_all[1][sel])
        est = read_bvh(out).poses()
        # corrected frames are the capture's own: scored are the frames tracked
        scored = [i for i in range(len(est[0])) if i not in job.corrections]
        results[name] = (evaluate.score(sk, tracked_names, (est[0][scored], est[1][scored]),
                                        (truth[0][scored], truth[1][scored])), rep)
        # independent views: the BVH holds the body as the first view places it
        image_px[name] = evaluate.image_error_px(
            sk, (est[0][scored], est[1][scored]), (truth[0][scored], truth[1][scored]),
            job.cameras if mode == "calibrated" else job.cameras[:1])
        # the best fit of the joints tracked: side-on, those hinges about the line of sight
        fitted = side_on_skeleton(sk, job.initial) if job.settings.side_on else sk
        body = ("best fit + spine" if joints is SPINE_JOINTS
                else "best fit, side-on" if fitted is not sk else "best fit")
        ref_of[name] = step, sel.start, body
        if ref_of[name] not in refs:
            refs[ref_of[name]] = (
                evaluate.score(sk, tracked_names, evaluate.held_still(truth), truth),
                evaluate.score(sk, tracked_names, evaluate.best_fit(fitted, truth), truth),
            )
        if len(views) == 1:  # what that view shows without depth, and with it from lengths
            camera = info["cameras"][views[0]]
            sight = np.array(camera["R"])[2]
            flat[name] = evaluate.in_the_image_plane(sk, truth, sight)["mean"]
            lift = evaluate.lifted_from_the_image
            lifted[name] = [np.mean([
                lift(sk, truth, sight, px / camera["scale"], seed)["mean"]
                for seed in range(LIFT_DRAWS if px else 1)]) for px in LIFT_PIXELS]
        if mode == "calibrated" and not job.settings.side_on:  # (no true pose to start from)
            steps[name] = one_step(job_path, truth)
            steps[name + ", at the truth"] = one_step(job_path, truth, at_truth=True)
        s = results[name][0]
        print(f"{name}: limb {s.limb_mean_deg:.1f} deg, {rep['frames_tracked']}/"
              f"{rep['frames_total']} frames, {rep['frames_per_second']:.1f} fps", flush=True)

    print()
    print("| run | frames tracked | limb dir. err (8 limbs) | neck-head | joint pos. err |"
          " image err | held still | best fit | image plane only | lifted by lengths"
          f" ({' / '.join(f'{px} px' for px in LIFT_PIXELS)}) | tracking fps |"
          " s / iteration | peak memory |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for name, (s, rep) in results.items():
        still, best = refs[ref_of[name]]
        first_div = rep["diverged_frames"][0] if rep["diverged_frames"] else None
        tracked = f"{rep['frames_tracked']}/{rep['frames_total']}" + (
            f" (diverged at {first_div})" if first_div is not None else "")
        print(f"| {name} | {tracked} | {s.limb_mean_deg:.1f}° | {s.limb_deg['neck-head']:.1f}° |"
              f" {s.position_mm:.0f} mm | {image_px[name]:.1f} px | {still.limb_mean_deg:.1f}° |"
              f" {best.limb_mean_deg:.1f}° |"
              f" {fmt(flat.get(name))}{'°' if name in flat else ''} |"
              f" {' / '.join(fmt(x) for x in lifted.get(name, [None]))}"
              f"{'°' if name in lifted else ''} |"
              f" {fmt(rep['frames_per_second'])} | {fmt(rep['seconds_per_iteration'], 3)} |"
              f" {rep['peak_mb']:.0f} MB |")
    print()
    names = list(results)
    # the references at 15 fps (else the first rate run): held still, and each body's best fit
    whole = {k: ref for k, ref in refs.items() if k[1] == 0} or refs  # over the whole clip
    step = 8 if any(k[0] == 8 for k in whole) else next(iter(whole))[0]
    bests = {body: ref[1] for (st, _, body), ref in whole.items() if st == step}
    still = next(ref[0] for (st, _, _), ref in whole.items() if st == step)
    fps = f" ({CAPTURE_FPS // step} fps)"
    print("| limb direction (°) | " + " | ".join(names) + f" | held still{fps} | "
          + " | ".join(k + fps for k in bests) + " |")
    print("|---" * (len(names) + 2 + len(bests)) + "|")
    for limb in results[names[0]][0].limb_deg:
        cells = [f"{results[n][0].limb_deg[limb]:.1f}" for n in names]
        print(f"| {limb} | " + " | ".join(cells) + f" | {still.limb_deg[limb]:.1f} | "
              + " | ".join(f"{b.limb_deg[limb]:.1f}" for b in bests.values()) + " |")
    print()
    print("| local rotation (°, for information) | " + " | ".join(names) + " | "
          + " | ".join(bests) + " |")
    print("|---" * (len(names) + 1 + len(bests)) + "|")
    joints = dict.fromkeys(j for n in names for j in results[n][0].local_deg)
    for joint in joints:
        cells = [fmt(results[n][0].local_deg.get(joint)) for n in names]
        cells += [fmt(b.local_deg.get(joint)) for b in bests.values()]
        print(f"| {joint} | " + " | ".join(cells) + " |")
    if steps:
        print("\n| one step from the true pose (°; *at the truth*: predicted at the frame's own)"
              " | " + " | ".join(steps) + " |")
        print("|---" * (len(steps) + 1) + "|")
        for limb in next(iter(steps.values())).limb_deg:
            print(f"| {limb} | " + " | ".join(f"{s.limb_deg[limb]:.1f}" for s in steps.values())
                  + " |")
        print("| mean of the eight limbs | " + " | ".join(
            f"{s.limb_mean_deg:.1f}" for s in steps.values()) + " |")
        print("| worst frame (its eight limbs' mean) | " + " | ".join(
            f"{s.per_frame_limb_deg.max():.1f} (frame {s.per_frame_limb_deg.argmax()})"
            for s in steps.values()) + " |")
    print(f"\nbenchmark time {time.perf_counter() - t0:.0f} s; {WIDTH * a.zoom}x"
          f"{HEIGHT * a.zoom} footage, "
          f"{len(JOINTS)} tracked joints (19 degrees of freedom), + spine "
          f"{len(SPINE_JOINTS)} (22)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

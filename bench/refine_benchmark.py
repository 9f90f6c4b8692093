"""The skeleton refinement benchmark: the rendered CMU walk (bench/walk_footage.py), tracked
with a skeleton whose left knee sits 4 cm forward of the capture's and whose right knee axis
is turned 15 degrees, refined (core.refine), and scored before and after.

    python bench/refine_benchmark.py [--cache .cache/walk] [--first 60] [--last 119]
                                     [--rounds 10] [--zoom 1] [--spine] [--settings JSON]

Frames are indices into the 30 fps footage (the default stretch is its steady walking, to
the end); the refinement runs until the joints settle or ``--rounds`` are done. Prints each
refined joint's centre and axis error against the capture's skeleton and the legs'
limb-direction errors when tracked with the skeleton before and after refinement, and,
as the floor those errors read against, what the same estimate makes of each joint at the
capture's own poses instead of tracked ones (no tracking error to carry). With
``--zoom 2`` the footage is 960x720 of the same stage (cached in .cache/walk2x), to tell
what the footage's resolution decides from what it does not.
With ``--settings`` the refinement tracks and reads with those tracker settings (the legs
are scored with the defaults).
"""

from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import evaluate  # noqa: E402
from walk_benchmark import RUNS  # noqa: E402
from walk_footage import (  # noqa: E402
    add_footage_arguments,
    add_spine_argument,
    footage_cache,
    render,
    tracked_joints,
    write_job,
)

from core import se3  # noqa: E402
from core.bvh import read_bvh  # noqa: E402
from core.job import load_job  # noqa: E402
from core.pose import BodyPose  # noqa: E402
from core.refine import carried_pose, joint_from_track, moved_joint, refine  # noqa: E402
from core.settings import TrackerSettings  # noqa: E402
from core.skeleton import Skeleton  # noqa: E402
from core.tracker import Tracker, track  # noqa: E402

LEGS = ["left thigh", "right thigh", "left shank", "right shank"]


def capture_axis(R: np.ndarray) -> np.ndarray:
    """A joint's own hinge axis in the capture: the dominant axis of its steps R(t) R(t-1)^T
    (rotation vectors, first singular vector), taken into the joint's local frame at the
    first frame, as ``core.refine`` reads a hinge."""
    steps = np.array([se3.log_so3(R[t] @ R[t - 1].T) for t in range(1, len(R))])
    axis = np.linalg.svd(steps, full_matrices=False)[2][0]
    return R[0].T @ axis


def leg_errors(sk, truth_sk, images, initial, truth, frames) -> dict[str, float]:
    """Mean limb-direction error (degrees) of each leg bone, tracked with ``sk``."""
    res = track(Tracker(sk, images, "calibrated"), initial, frames)
    R = np.array([f.pose.rotations for f in res.frames])
    P = np.array([f.pose.root_position for f in res.frames])
    got, want = evaluate.limb_vectors(sk, R, P), evaluate.limb_vectors(truth_sk, *truth)
    return {k: float(np.degrees(se3.angle_between_vectors(got[k], want[k][:len(R)])).mean())
            for k in LEGS}


def at_capture(sk, images, truth, cameras, joints: list[int], settings: TrackerSettings
               ) -> dict[int, Skeleton]:
    """Per joint, ``sk`` with that joint where ``core.refine`` reads it (centre and hinge axis)
    from the footage, filtered as ``settings`` say, at the capture's own poses ``truth``
    (rotations, roots) of every frame of ``images``: one tracker, so each frame is read and
    filtered once."""
    poses = [BodyPose(R.copy(), p.copy(), [c.copy() for c in cameras]) for R, p in zip(*truth)]
    tracker = Tracker(sk, images, "calibrated", settings)
    return {j: moved_joint(sk, j, *joint_from_track(tracker, poses, range(len(poses)), j))
            for j in joints}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--first", type=int, default=60)
    ap.add_argument("--last", type=int, help="one past the last frame (default: the end)")
    ap.add_argument("--rounds", type=int, default=10, help="track-and-refine rounds, at most")
    ap.add_argument("--settings", default="{}",
                    help="tracker settings (JSON) of the refinement (the legs are scored "
                         "with the defaults)")
    add_footage_arguments(ap)
    add_spine_argument(ap)
    a = ap.parse_args(argv)
    a.cache = footage_cache(a)
    t0 = time.perf_counter()
    views, mode, _, _ = RUNS["3 views calibrated 30 fps"]
    info = render(a.cache, 300, 772, 4, views, a.zoom)
    a.last = len(info["frames"]) if a.last is None else a.last
    if not 0 <= a.first < a.last - 2 or a.last > len(info["frames"]):
        ap.error(f"--first {a.first} --last {a.last}: the footage has frames 0-"
                 f"{len(info['frames']) - 1}; give at least three, with --last one past them")
    job = load_job(write_job(a.cache, "refine", views, mode, info["frames"], info["cameras"],
                             {}, 4 / 120, tracked_joints(a)))
    truth_sk = job.skeleton
    T = read_bvh(a.cache / "truth.bvh").poses()
    sel = slice(a.first, a.last)
    truth = (T[0][sel], T[1][sel])
    images = [v[sel] for v in job.images]
    frames = list(range(a.last - a.first))
    initial_true = BodyPose(truth[0][0].copy(), truth[1][0].copy(),
                            [c.copy() for c in job.cameras])
    lk, rk = truth_sk.index("LeftKnee"), truth_sk.index("RightKnee")
    turned = se3.exp_so3(np.array([0, np.radians(15), 0])) @ truth_sk.axes[rk]
    guess = moved_joint(moved_joint(truth_sk, lk, np.array([0.0, 0.0, 0.04])), rk,
                        np.zeros(3), turned)
    initial = carried_pose(truth_sk, guess, initial_true)  # lined up, centres wrong
    settings = TrackerSettings(**json.loads(a.settings))
    result = refine(guess, images, initial, ["LeftKnee", "RightKnee"], settings,
                    rounds=a.rounds)
    refined = result.skeleton

    settled = "settled" if result.settled() else "not settled"
    print(f"frames {a.first}-{a.last - 1} of the 30 fps footage, {len(result.shifts)} rounds"
          f" ({settled})\n")
    print("| joint | centre error before | after | axis error before | after | after, against"
          " the capture's own axis | read at the capture's poses |")
    print("|---|---|---|---|---|---|---|")
    floors = at_capture(truth_sk, images, truth, job.cameras, [lk, rk], settings)
    for j in (lk, rk):
        def centre(s, j=j):
            return 100 * np.linalg.norm(s.rest_positions[j] - truth_sk.rest_positions[j])

        def axis(s, j=j, want=truth_sk.axes[j]):
            a = np.degrees(se3.angle_between_vectors(s.axes[j], want))
            return min(a, 180 - a)  # a hinge axis has no sign

        own = capture_axis(truth[0][:, j])
        floor = floors[j]
        print(f"| {truth_sk.names[j]} | {centre(guess):.1f} cm | {centre(refined):.1f} cm |"
              f" {axis(guess):.1f}° | {axis(refined):.1f}° | {axis(refined, want=own):.1f}°"
              f" (job's axis: {axis(truth_sk, want=own):.1f}°) | {centre(floor):.1f} cm,"
              f" {axis(floor):.1f}° |")
    before = leg_errors(guess, truth_sk, images, initial, truth, frames)
    after = leg_errors(refined, truth_sk, images, result.initial, truth, frames)
    exact = leg_errors(truth_sk, truth_sk, images, initial_true, truth, frames)
    print("\n| limb direction (°) | skeleton as guessed | refined | capture's skeleton |")
    print("|---|---|---|---|")
    for k in LEGS:
        print(f"| {k} | {before[k]:.1f} | {after[k]:.1f} | {exact[k]:.1f} |")
    print(f"| mean of the legs | {np.mean(list(before.values())):.1f} |"
          f" {np.mean(list(after.values())):.1f} | {np.mean(list(exact.values())):.1f} |")
    print(f"\nbenchmark time {time.perf_counter() - t0:.0f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())

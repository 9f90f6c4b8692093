"""Running a tracking job end to end: load, track, write the BVH and the report."""

from __future__ import annotations

import json
import time
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .frame_fit import FrameResult
from .job import Job
from .pose import world_pose
from .tracker import Tracker, TrackResult, frames_tracked, track


def run_job(
    job: Job,
    progress: Callable[[FrameResult, int, int], None] | None = None,
    cancel: Callable[[], bool] | None = None,
) -> TrackResult:
    """Track every frame of the job's footage from its first frame (a corrected frame takes
    its given pose)."""
    tracker = Tracker(job.skeleton, job.images, job.mode, job.settings, job.moving or None,
                      job.clean_plates or None)
    frames = list(range(len(job.images[0])))
    return track(tracker, job.initial, frames, progress, cancel, job.corrections)


def result_bvh(job: Job, result: TrackResult):
    """The job's BVH hierarchy holding one frame per tracked frame (a diverged frame's pose
    is not kept: the add-on does not key it either)."""
    rots, roots = [], []
    for fr in (f for f in result.frames if not f.diverged):
        R, p0 = world_pose(job.mode, job.cameras[0], fr.pose)
        rots.append(R)
        roots.append(p0)
    out = job.bvh.with_motion(np.array(rots), np.array(roots))
    out.frame_time = job.frame_time
    return out


def report(job: Job, result: TrackResult, seconds: float) -> dict:
    """Per-frame residual, iterations, convergence and timing, with a summary. Frames are
    counted as the add-on counts them: those after the first (the user's pose), tracked
    without diverging, of those there are. Numbers that are not (a diverged frame's
    residual) are null, so that the report is strict JSON."""
    tracked = result.frames[1:]
    iters = sum(f.iterations for f in tracked)
    return {
        "mode": job.mode,
        "views": len(job.images),
        "degrees_of_freedom": len(job.skeleton.dof_names()),
        "frames_total": len(job.images[0]) - 1,
        "frames_tracked": frames_tracked(result.frames),
        "cancelled": result.cancelled,
        "diverged_frames": result.diverged_frames,
        "frames_to_check": sorted(result.frames_to_check),
        "doubts_begin": [{"frame": f, "flags": flags}
                         for f, flags in sorted(result.doubts_begun.items())],
        "notes": result.notes,
        "seconds": seconds,
        "frames_per_second": len(tracked) / seconds if seconds > 0 else None,
        "seconds_per_iteration": sum(f.seconds for f in tracked) / iters if iters else None,
        "frames": [
            {
                "frame": f.frame,
                "residual": f.residual if np.isfinite(f.residual) else None,
                "iterations": f.iterations,
                "converged": f.converged,
                "diverged": f.diverged,
                "reason": f.reason,
                "seconds": f.seconds,
                "given": f.given,
                "turned": None if f.turned is None else round(f.turned, 1),
                "searched": list(f.searched),
                "limbs": {name: {"confidence": round(c.own_confidence, 3), "flag": c.flag,
                                 "views": [None if v is None else round(v, 3)
                                           for v in c.flag_views],
                                 "unexplained": None if c.unexplained is None
                                 else round(c.unexplained, 3)}
                          for name, c in f.limbs.items()},
            }
            for f in result.frames
        ],
    }


def write_report(path: str | Path, rep: dict) -> None:
    Path(path).write_text(json.dumps(rep, indent=1, allow_nan=False))


def timed_run(job: Job, progress=None, cancel=None) -> tuple[TrackResult, float]:
    t0 = time.perf_counter()
    res = run_job(job, progress, cancel)
    return res, time.perf_counter() - t0

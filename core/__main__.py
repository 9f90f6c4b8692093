"""Command line:

    python -m core track JOB.json --out TRACKED.bvh [--report REPORT.json]
    python -m core fit FIT.json --out FITTED.bvh

Exit status: 0 done; 2 the job is malformed or the clicks cannot determine a fit (nothing
written); 3 tracking stopped at a diverged frame (the frames before it are written).
"""

from __future__ import annotations

import argparse
import dataclasses
import sys

from .bvh import write_bvh
from .image import ImageError
from .init_fit import FitError, fit_pose, least_certain
from .job import JobError, load_fit, load_job
from .pose import world_pose
from .run import report, result_bvh, timed_run, write_report


def _track(args) -> int:
    try:
        job = load_job(args.job)
    except JobError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2

    def progress(res, done, total):
        if not args.quiet:
            flag = f"  DIVERGED: {res.reason}" if res.diverged else ""
            print(f"frame {res.frame:4d}  {done}/{total}  residual {res.residual:.4f}"
                  f"  iterations {res.iterations}{flag}", file=sys.stderr)

    try:
        result, seconds = timed_run(job, progress)
    except ImageError as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    write_bvh(result_bvh(job, result), args.out)
    if args.report:
        write_report(args.report, report(job, result, seconds))
    for note in result.notes:
        print(f"note: {note}", file=sys.stderr)
    n = len(result.frames)
    print(f"tracked {n} of {len(job.images[0])} frames in {seconds:.1f} s -> {args.out}",
          file=sys.stderr)
    if result.diverged_frames:
        f = result.diverged_frames[0]
        print(f"stopped: frame {f} diverged ({result.frames[-1].reason}); correct the pose"
              f" there and track again from it", file=sys.stderr)
        return 3
    return 0


def _fit(args) -> int:
    try:
        job = load_fit(args.job)
        res = fit_pose(job.skeleton, job.guess, job.clicks, job.mode, job.fit_lengths)
    except (JobError, FitError) as e:
        print(f"error: {e}", file=sys.stderr)
        return 2
    R, root = world_pose(job.mode, job.cameras[0], res.pose)
    out = job.bvh.with_motion(R[None], root[None])
    out.joints = [dataclasses.replace(j, offset=o) for j, o in zip(out.joints,
                                                                   res.skeleton.offsets)]
    write_bvh(out, args.out)
    print(f"fitted {sum(len(c) for c in job.clicks)} clicks, {res.residual_px:.2f} px RMS"
          f" -> {args.out}", file=sys.stderr)
    print(f"least certain bones: {least_certain(res.direction_uncertainty)}", file=sys.stderr)
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m core", description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    t = sub.add_parser("track", help="track a job's footage and write a BVH")
    t.add_argument("job", help="the job file (JSON)")
    t.add_argument("--out", required=True, help="the tracked BVH to write")
    t.add_argument("--report", help="a JSON report of every frame to write")
    t.add_argument("--quiet", action="store_true", help="no per-frame progress")
    f = sub.add_parser("fit", help="fit the first pose and body proportions to clicked joints")
    f.add_argument("job", help="the fit file (JSON)")
    f.add_argument("--out", required=True, help="the BVH to write: fitted offsets, one frame")
    args = ap.parse_args(argv)
    return _track(args) if args.command == "track" else _fit(args)


if __name__ == "__main__":
    sys.exit(main())

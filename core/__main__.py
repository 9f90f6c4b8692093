"""Command line: ``python -m core track JOB.json --out TRACKED.bvh [--report REPORT.json]``.

Exit status: 0 tracked every frame; 2 the job is malformed (nothing tracked); 3 tracking
stopped at a diverged frame (the frames before it are written).
"""

from __future__ import annotations

import argparse
import sys

from .bvh import write_bvh
from .image import ImageError
from .job import JobError, load_job
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
    n = len(result.frames)
    print(f"tracked {n} of {len(job.images[0])} frames in {seconds:.1f} s -> {args.out}",
          file=sys.stderr)
    if result.diverged_frames:
        f = result.diverged_frames[0]
        print(f"stopped: frame {f} diverged ({result.frames[-1].reason}); correct the pose"
              f" there and track again from it", file=sys.stderr)
        return 3
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m core", description=__doc__.splitlines()[0])
    sub = ap.add_subparsers(dest="command", required=True)
    t = sub.add_parser("track", help="track a job's footage and write a BVH")
    t.add_argument("job", help="the job file (JSON)")
    t.add_argument("--out", required=True, help="the tracked BVH to write")
    t.add_argument("--report", help="a JSON report of every frame to write")
    t.add_argument("--quiet", action="store_true", help="no per-frame progress")
    args = ap.parse_args(argv)
    if args.command == "track":
        return _track(args)
    return 2


if __name__ == "__main__":
    sys.exit(main())

"""twist-mocap's tracker without Blender: footage of a moving body in, a BVH out.

    twist-mocap track JOB.json --out TRACKED.bvh [--report REPORT.json]
    twist-mocap fit FIT.json --out FITTED.bvh
    twist-mocap plate PLATE.png --out FOLDER [--per-row N]
    twist-mocap cameras CALIBRATION --out cameras.json [--scale UNITS_PER_METRE]

(``python -m core`` with the project's Python does the same.) A job names the body (a BVH
and the joints to track), the first frame's pose, each view's footage and camera, and
settings; docs/JOB_FORMAT.md describes every field. ``plate`` cuts a printed plate (cells
in rows with dark gutters) into one image per cell, lined up on the ground line, named
PLATE_01.png, PLATE_02.png, ... in reading order. ``cameras`` converts a calibration
(OpenCV's YAML/XML/JSON, Pose2Sim's TOML, Qualisys' .qca.txt) into pinhole cameras a job's
views take as they are. Exit status: 0 done; 2 the job, its footage or the output paths are
unusable, the clicks cannot determine a fit, or the plate's cells or the calibration cannot
be read (nothing written); 3 tracking stopped at a diverged frame (the frames before it are
written).
"""

from __future__ import annotations

import argparse
import dataclasses
import os
import sys
import time
from pathlib import Path

from .bvh import write_bvh
from .calibration import CalibrationError, read_calibration, write_cameras
from .confidence import begun_list, frame_list
from .errors import InputError
from .init_fit import FitError, fit_pose, least_certain
from .job import JobError, load_fit, load_job
from .plate import unconfirmed, write_frames
from .pose import world_pose
from .run import report, result_bvh, timed_run, write_report
from .tracker import TrackResult


def _writable(path: str, what: str) -> str:
    """'' when ``path`` can be written, else why not (checked before any work is done)."""
    folder = Path(path).resolve().parent
    if not folder.is_dir():
        return f"the folder of the {what} ({folder}) does not exist: create it, or name another"
    if not os.access(folder, os.W_OK):
        return f"the {what} cannot be written into {folder} (no permission)"
    return ""


def _refused(why: str) -> int:
    """Say why nothing was done; the exit status of unusable input (2)."""
    print(f"error: {why}", file=sys.stderr)
    return 2


def _track(args) -> int:
    problems = [p for p in (_writable(args.out, "output BVH"),
                            args.report and _writable(args.report, "report")) if p]
    if problems:
        return _refused(problems[0])
    try:
        job = load_job(args.job)
    except JobError as e:
        return _refused(str(e))

    done_so_far = TrackResult()

    def progress(res, done, total):
        done_so_far.frames.append(res)
        if not args.quiet:
            flag = f"  DIVERGED: {res.reason}" if res.diverged else "".join(
                f"  {name} {why}" for name, why in res.flagged.items())
            print(f"frame {res.frame:4d}  {done}/{total}  residual {res.residual:.4f}"
                  f"  iterations {res.iterations}{flag}", file=sys.stderr)

    t0 = time.perf_counter()
    try:
        result, seconds = timed_run(job, progress)
    except InputError as e:  # a frame that cannot be read, a pose outside a view...
        print(f"error: {e}", file=sys.stderr)
        if len(done_so_far.frames) > 1:  # what was tracked is kept
            write_bvh(result_bvh(job, done_so_far), args.out)
            if args.report:
                write_report(args.report, report(job, done_so_far, time.perf_counter() - t0))
            print(f"the {len(done_so_far.frames)} frames before it are written to {args.out}",
                  file=sys.stderr)
        return 2
    write_bvh(result_bvh(job, result), args.out)
    rep = report(job, result, seconds)
    if args.report:
        write_report(args.report, rep)
    for note in result.notes:
        print(f"note: {note}", file=sys.stderr)
    print(f"tracked {rep['frames_tracked']} of {rep['frames_total']} frames after the first"
          f" in {seconds:.1f} s -> {args.out}", file=sys.stderr)
    check = result.frames_to_check
    if check:
        print(f"check {len(check)} frames where a view disagrees with a limb (its pixels, or "
              f"its bone off the silhouette), no view sees it, or the body tracked side-on "
              f"turned toward or away from the camera: {frame_list(check)}; look first where "
              f"the doubt begins: {begun_list(result.doubts_begun)}", file=sys.stderr)
    if result.diverged_frames:
        f = result.diverged_frames[0]
        print(f"stopped: frame {f} diverged ({result.frames[-1].reason}); correct the pose"
              f" there and track again from it", file=sys.stderr)
        return 3
    return 0


def _fit(args) -> int:
    problem = _writable(args.out, "fitted BVH")
    if problem:
        return _refused(problem)
    try:
        job = load_fit(args.job)
        res = fit_pose(job.skeleton, job.guess, job.clicks, job.mode, job.fit_lengths)
    except (JobError, FitError) as e:
        return _refused(str(e))
    R, root = world_pose(job.mode, job.cameras[0], res.pose)
    out = job.bvh.with_motion(R[None], root[None])
    out.joints = [dataclasses.replace(j, offset=o) for j, o in zip(out.joints,
                                                                   res.skeleton.offsets)]
    write_bvh(out, args.out)
    print(f"fitted {sum(len(c) for c in job.clicks)} clicks, {res.residual_px:.2f} px RMS"
          f" -> {args.out}", file=sys.stderr)
    said = least_certain(res.direction_uncertainty, views=len(job.cameras))
    print(f"least certain bones: {said}", file=sys.stderr)
    return 0


def _plate(args) -> int:
    if not Path(args.plate).is_file():
        return _refused(f"{args.plate}: no such image")
    problem = _writable(args.out, "frames' folder")  # the folder itself is made
    if problem:
        return _refused(problem)
    try:
        cells, paths = write_frames(args.plate, args.out, args.per_row)
    except InputError as e:
        return _refused(f"{args.plate}: {e}")
    rows = len({c.box[1] for c in cells})
    print(f"{len(cells)} cells in {rows} rows -> {paths[0].name} ... {paths[-1].name} in "
          f"{args.out}; each cell's offset down from the first's: "
          f"{', '.join(f'{c.offset[1]:+.1f}' for c in cells)} px",
          file=sys.stderr)
    doubtful = unconfirmed(cells)
    if doubtful:
        print(f"note: {doubtful}", file=sys.stderr)
    return 0


def _cameras(args) -> int:
    problem = _writable(args.out, "cameras file")
    if problem:
        return _refused(problem)
    try:
        cams = read_calibration(args.calibration, args.scale)
    except CalibrationError as e:
        return _refused(str(e))
    write_cameras(cams, args.out)
    for c in cams:
        size = f"{c.size[0]}x{c.size[1]}" if c.size else "size not given"
        centre = ", ".join(f"{x:.3f}" for x in c.camera.centre)
        print(f"{c.name}: {size}, focal length {c.camera.K[0, 0]:.1f} px, centre ({centre}), "
              f"{'lens distortion' if c.dist is not None else 'no distortion'}",
              file=sys.stderr)
    print(f"{len(cams)} cameras -> {args.out}", file=sys.stderr)
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="twist-mocap", description=__doc__,
                                 formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    t = sub.add_parser("track", help="track a job's footage and write a BVH")
    t.add_argument("job", help="the job file (JSON)")
    t.add_argument("--out", required=True, help="the tracked BVH to write")
    t.add_argument("--report", help="a JSON report of every frame to write")
    t.add_argument("--quiet", action="store_true", help="no per-frame progress")
    f = sub.add_parser("fit", help="fit the first pose and body proportions to clicked joints")
    f.add_argument("job", help="the fit file (JSON)")
    f.add_argument("--out", required=True, help="the BVH to write: fitted offsets, one frame")
    pl = sub.add_parser("plate", help="cut a printed plate into its cells, registered, as "
                        "an image sequence")
    pl.add_argument("plate", help="the plate's image")
    pl.add_argument("--out", required=True, help="the folder to write the frames into")
    pl.add_argument("--per-row", type=int, help="cells per row, where the plate's cells "
                    "touch with no gutter between them and their count is not found")
    ca = sub.add_parser("cameras", help="convert a calibration file into the pinhole cameras "
                        "a job takes")
    ca.add_argument("calibration", help="OpenCV .yml/.yaml/.xml/.json, Pose2Sim .toml or "
                    "Qualisys .qca.txt")
    ca.add_argument("--out", required=True, help="the cameras file (JSON) to write")
    ca.add_argument("--scale", type=float, default=1.0, help="world units per metre, for a "
                    "skeleton in other units (100 for centimetres); default 1")
    args = ap.parse_args(argv)
    return {"track": _track, "fit": _fit, "plate": _plate, "cameras": _cameras}[
        args.command](args)


if __name__ == "__main__":
    sys.exit(main())

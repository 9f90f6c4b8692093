"""The benchmark suite: many motions, skeletons and looks, tracked with the default settings
and scored against the capture beside two references on the same frames.

    python bench/suite.py [--quick] [--bandai-namco FOLDER] [--settings JSON] [--starts N]
                          [--clips NAME,...] [--looks NAME,...] [--half-size] [--exposure-drift]
                          [--workers N]
                          [--write PATH]

Each clip (a capture of ``captures.NAMINGS``) is rendered once per look
(``suite_footage.LOOKS``) into ``.cache/suite/``, ``--workers`` looks at once, and tracked
through ``python -m core track``, as a user runs it: three calibrated views (the lower back
free) and one lateral view (the paper's 19 degrees of freedom), at 15 fps, and with the full
suite at 30 fps too.
The tracker's body is what a job gets without blobs of its own (``Skeleton.default_blobs``),
its hinges' axes the capture's own. Scored: the limb-direction error over the eight limbs (a
run that stops keeps its last pose, as a user's keys would), beside the first frame held
still and the best fit of the tracked degrees of freedom to the true joints (in one view the
side-on body's, which cannot turn a limb in depth); for one view also how far the limb ends
stray in its image, in % of the body's height. Tracking is chaotic (a run from the next
frame can end several degrees apart), so each clip, look and run is tracked from the clip's
first three frames (``--starts``), each posed by the capture, and scored by the mean, with
the lowest and highest beside it. ``--quick`` (the check for every change, a few minutes
once the footage is rendered): the CMU clips at 15 fps, from the first frame alone. The
Bandai Namco clips are non-commercial and never stored in the repository: give the folder
that holds them (``bn_*.bvh``) to include them. Two renderers, then two trackers, run at
once, one per core of a two-core machine; the tracking speed of a run alone, as a user's, is
``--workers 1`` (nothing else running). ``--half-size`` tracks every run on its footage
halved (``suite_footage.halve_job``): the body about 100 pixels tall instead of 205.
``--exposure-drift`` tracks every run on its footage with the exposure drifting
(``suite_footage.drift_job``: plus or minus 30 % over one and a half seconds).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import multiprocessing
import statistics
import sys
import threading
import time
from concurrent.futures import ProcessPoolExecutor, ThreadPoolExecutor, as_completed
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import evaluate  # noqa: E402
from captures import Parts  # noqa: E402
from suite_footage import (  # noqa: E402
    LOOKS,
    PIXELS_PER_METRE,
    VIDEO_FPS,
    VIEWS,
    Clip,
    drift_job,
    frame_ext,
    halve_job,
    look_cameras,
    look_rendered,
    render_look,
    stage,
)
from walk_benchmark import track_job  # noqa: E402

from core.bvh import read_bvh  # noqa: E402
from core.job import load_job  # noqa: E402
from core.side_on import line_of_sight, out_of_side_on, side_on_skeleton  # noqa: E402
from core.skeleton import skeleton_from_bvh  # noqa: E402

DATA = ROOT / "bench" / "data"
CACHE = ROOT / ".cache" / "suite"
CLIPS = [  # two seconds each, file frames at the capture's rate
    Clip("CMU 131 walk", DATA / "cmu_131_01_walk.bvh", 540, 780),
    Clip("CMU 05-01 walk", DATA / "cmu05_01_walk.bvh", 0, 240),
    Clip("CMU 01-01 jumps", DATA / "cmu01_01_forward_jumps.bvh", 0, 240),
    Clip("CMU 05-10 dance", DATA / "cmu05_10_dance_arms_high.bvh", 0, 240),
    Clip("CMU 06-10 left turn", DATA / "cmu06_10_walk_left_turns.bvh", 0, 240),
]
BANDAI_NAMCO = [  # (name, file, first, last) at 30 fps
    ("BN brisk walk", "bn_walk_brisk_active.bvh", 0, 60),
    ("BN arm swing", "bn_walk_happy_armswing.bvh", 30, 90),
    ("BN old walk", "bn_walk_old.bvh", 60, 120),
    ("BN left turn", "bn_walk_turn_left.bvh", 60, 120),
    ("BN waving", "bn_wave_both_hands.bvh", 60, 120),
    ("BN dance", "bn_dance_short.bvh", 510, 570),
]
# run: (views, video frames per tracked frame, lower back free)
RUNS = {
    "3 views 15 fps": (list(VIEWS), 2, True),
    "1 lateral view 15 fps": (["lateral"], 2, False),
    "3 views 30 fps": (list(VIEWS), 1, True),
    "1 lateral view 30 fps": (["lateral"], 1, False),
    # one view 30 degrees off the body's front, as a phone's video often is: measured in
    # ``docs/RESEARCH.md``, not run by default
    "1 oblique view 15 fps": (["oblique60"], 2, False),
}
DEFAULT_RUNS = ("3 views 15 fps", "1 lateral view 15 fps", "3 views 30 fps",
                "1 lateral view 30 fps")
QUICK_RUNS = ("3 views 15 fps", "1 lateral view 15 fps")
HALF_LABEL = ", half size"  # after a look's name in the tables, with ``--half-size``
DRIFT_LABEL = ", exposure drifting"  # and with ``--exposure-drift``


def slug(text: str) -> str:
    return "".join(c if c.isalnum() else "_" for c in text.lower())


def settings_digest(settings: dict) -> str:
    """Eight hex digits naming tracker settings: the same for the same settings in any order."""
    return hashlib.sha256(json.dumps(settings, sort_keys=True).encode()).hexdigest()[:8]


def write_job(clip_dir: Path, look: str, run: str, settings: dict, start: int = 0) -> Path:
    """The job tracking one run of one clip in one look (its footage rendered), from the
    clip's frame ``start`` (posed there by the capture) on, every run's step-th frame. A job
    with ``settings`` is named by a digest of them, so that its tracked files sit beside the
    defaults' and another setting's, and screens of different settings can run at once."""
    views, step, lower_back = RUNS[run]
    truth = read_bvh(clip_dir / "truth.bvh")
    sk = skeleton_from_bvh(truth)
    R, _ = truth.poses()
    cams = look_cameras(clip_dir, LOOKS[look])
    ext = frame_ext(LOOKS[look])
    frames = range(start, len(R), step)
    for cam in cams.values():
        if np.ndim(cam["R"]) == 3:  # a camera that moves: its pose on the run's frames
            cam["R"], cam["t"] = cam["R"][start::step], cam["t"][start::step]
    job = {
        "skeleton": {"bvh": "truth.bvh",
                     "joints": Parts.of(sk.names).tracked_joints(sk, R, lower_back)},
        "initial": {"bvh": "truth.bvh", "frame": start},
        "views": [{"images": [f"{slug(look)}/{v}/{f:04d}.{ext}" for f in frames],
                   "camera": cams[v]} for v in views],
        "mode": "calibrated",
        "settings": settings,
        "frame_time": step / VIDEO_FPS,
    }
    # the footage folder is named by the look itself; the job beside it
    tag = f"__settings_{settings_digest(settings)}" if settings else ""
    path = clip_dir / f"{slug(look)}__{slug(run)}{tag}{f'__from_{start}' if start else ''}.json"
    path.write_text(json.dumps(job, indent=1))
    return path


REFERENCES_FILE = "references.json"  # in a clip's folder: its runs' references by digest
_REFERENCES_LOCK = threading.Lock()  # the runs are scored on threads


def references(clip_dir: Path, job, truth: tuple, limbs) -> tuple[float, float]:
    """Held still and the best fit of the tracked degrees of freedom over the run's frames.
    A body tracked side-on (one view) is fitted as the tracker holds it: its depth-blind
    joints hinges about the line of sight (``side_on_skeleton``; a moving camera's mean,
    ``line_of_sight``), its root turning about that line alone; so the best fit is one
    view's floor, not three's. The same for every look whose view looks the same way (a
    panning camera's mean line of sight is its own, and its body's fit with it), and slow
    to fit (seconds a frame), so kept in the clip's ``references.json`` under the digest of
    what they are computed from (``reference_digest``)."""
    sk = job.skeleton
    body, sight = fitted_body(job)
    names = sk.tracked_joint_names()
    key = reference_digest(sk, body, sight, truth, names, limbs)
    path = clip_dir / REFERENCES_FILE
    with _REFERENCES_LOCK:
        known = _kept_references(path)
    if key not in known:
        known[key] = [evaluate.score(sk, names, pose, truth, limbs=limbs).limb_mean_deg
                      for pose in (evaluate.held_still(truth),
                                   evaluate.best_fit(body, truth, sight))]
        with _REFERENCES_LOCK:  # another run's may have landed meanwhile
            tmp = path.with_suffix(".tmp")
            tmp.write_text(json.dumps({**_kept_references(path), key: known[key]}, indent=1))
            tmp.replace(path)
    return tuple(known[key])


def _kept_references(path: Path) -> dict:
    """A clip's ``references.json``: digest -> [held still, best fit]; empty before any."""
    return json.loads(path.read_text()) if path.is_file() else {}


def reference_digest(sk, body, sight, truth: tuple, names: list[str], limbs) -> str:
    """A digest of everything a run's references follow from: the scoring and fitting code
    (``evaluate``'s source), the skeleton scored and the body fitted, the line of sight, the
    true poses on the run's frames, the tracked joints and the limbs."""
    h = hashlib.sha256(Path(evaluate.__file__).read_bytes())
    for skel in (sk, body):
        h.update(json.dumps([skel.names, skel.kinds]).encode())
        for arr in (skel.parents, skel.offsets, skel.axes, skel.limits, skel.hinge_zero):
            h.update(b"-" if arr is None else np.ascontiguousarray(arr, float).tobytes())
    h.update(b"-" if sight is None else np.asarray(sight, float).tobytes())
    for arr in truth:
        h.update(np.ascontiguousarray(arr, float).tobytes())
    h.update(json.dumps([names, limbs]).encode())
    return h.hexdigest()


def fitted_body(job) -> tuple:
    """The body the best fit moves for a suite job, as the tracker holds it, and the line of
    sight it is side-on about (None where it is not tracked side-on)."""
    sight = line_of_sight(job.initial, job.moving[0] if job.moving else None)
    body = side_on_skeleton(job.skeleton, job.initial, sight) if job.settings.side_on \
        else job.skeleton
    return body, (sight if body is not job.skeleton else None)


BAD_LIMB_DEG = 20.0  # a limb this far off the capture is one the flags should catch


def flag_counts(rep: dict, sk, est: tuple, truth: tuple, limbs) -> tuple[int, int, int]:
    """How the report's limb flags match the truth over the eight limbs and the tracked
    frames: (flagged and over ``BAD_LIMB_DEG`` off, over it, flagged). A limb's flag is its
    segment's (the nearest joint above the limb's first joint that the report names), or
    the frame's body turned out of side-on, which puts every limb there in doubt."""
    bad = flagged = caught = 0
    errors = evaluate.limb_errors_deg(sk, est, truth, limbs)
    for fr in rep["frames"]:
        if not fr["limbs"]:
            continue
        f = fr["frame"]
        for label, a, _ in limbs[:8]:
            segment = next(sk.names[j] for j in sk.ancestors(sk.index(a))
                           if sk.names[j] in fr["limbs"])
            off = errors[label][f]
            flag = bool(fr["limbs"][segment]["flag"]) or out_of_side_on(fr.get("turned"))
            bad += off > BAD_LIMB_DEG
            flagged += flag
            caught += flag and off > BAD_LIMB_DEG
    return caught, bad, flagged


def tracked_and_true(job_path: Path, run: str, start: int = 0) -> tuple:
    """A tracked job's (``score_run``'s) job, the limbs it is scored on, and the tracked and
    the true (rotations, root) on the run's frames; a run that stopped keeps its last pose,
    as the keys would hold it."""
    _, step, _ = RUNS[run]
    job = load_job(job_path)
    limbs = Parts.of(job.skeleton.names).limbs()
    R, p = read_bvh(job_path.parent / "truth.bvh").poses()
    truth = (R[start::step], p[start::step])
    est = read_bvh(job_path.with_suffix(".bvh")).poses()
    n = len(truth[0])
    if len(est[0]) < n:
        pad = n - len(est[0])
        est = (np.concatenate([est[0], np.repeat(est[0][-1:], pad, 0)]),
               np.concatenate([est[1], np.repeat(est[1][-1:], pad, 0)]))
    return job, limbs, est, truth


def score_run(job_path: Path, run: str, start: int = 0, size: float = 1.0) -> dict:
    """Track one job (of ``write_job``, from ``start``, on footage ``size`` times the
    rendered one's) and score it beside the references of its clip and run."""
    views = RUNS[run][0]
    out = job_path.with_suffix(".bvh")
    rep_path = job_path.with_suffix(".report.json")
    code, peak_mb = track_job(job_path, out, rep_path)
    if code not in (0, 3):
        raise SystemExit(f"{job_path.name}: the tracker failed (exit {code})")
    rep = json.loads(rep_path.read_text())
    job, limbs, est, truth = tracked_and_true(job_path, run, start)
    sk, n = job.skeleton, len(truth[0])
    tracker = evaluate.score(sk, sk.tracked_joint_names(), est, truth, limbs=limbs)
    still, best = references(job_path.parent, job, truth, limbs)
    row = {"tracker": tracker.limb_mean_deg, "still": still, "best": best,
           "tracked": rep["frames_tracked"], "of": n - 1,
           "diverged": bool(rep["diverged_frames"]), "fps": rep["frames_per_second"],
           "peak_mb": peak_mb, "flags": flag_counts(rep, sk, est, truth, limbs),
           "heading": float(np.mean(np.abs(evaluate.heading_errors_deg(
               np.asarray(est[0])[:, 0], np.asarray(truth[0])[:, 0]))))}
    if len(views) == 1:
        height_px = sk.height() * PIXELS_PER_METRE * size
        px = evaluate.image_error_px(sk, est, truth, [m or c for c, m in zip(
            job.cameras, job.moving)], limbs)
        row["image_pct"] = 100 * px / height_px
    return row


def over_starts(runs: list[dict]) -> dict:
    """One clip, look and run tracked from several starting frames (``score_run``'s rows):
    the means of the errors and references, the tracker's lowest and highest; the frames
    tracked and to track, the runs that stopped and the flags, summed over the runs."""
    err = [r["tracker"] for r in runs]
    row = {"tracker": float(np.mean(err)), "low": min(err), "high": max(err),
           "still": float(np.mean([r["still"] for r in runs])),
           "best": float(np.mean([r["best"] for r in runs])),
           "tracked": sum(r["tracked"] for r in runs), "of": sum(r["of"] for r in runs),
           "stopped": sum(r["diverged"] for r in runs), "starts": len(runs),
           "fps": statistics.median(r["fps"] for r in runs),
           "peak_mb": max(r["peak_mb"] for r in runs),
           "flags": tuple(int(x) for x in np.sum([r["flags"] for r in runs], axis=0)),
           "heading": float(np.mean([r["heading"] for r in runs]))}
    if "image_pct" in runs[0]:
        row["image_pct"] = float(np.mean([r["image_pct"] for r in runs]))
    return row


def share(part: int, whole: int) -> str:
    """``part`` of ``whole`` in whole percent ('-' of none)."""
    return f"{100 * part / whole:.0f} %" if whole else "-"


def table(rows: dict, runs: list[str]) -> list[str]:
    """The per-clip table and the summary, as markdown lines (``rows``: ``over_starts``'s
    per clip, look and run)."""
    out = ["| clip | look | run | tracker | lowest-highest | held still | best fit | frames |"
           " image err |", "|---|---|---|---|---|---|---|---|---|"]
    for (clip, look, run), r in rows.items():
        img = f"{r['image_pct']:.1f} %" if "image_pct" in r else ""
        stopped = f" ({r['stopped']} of {r['starts']} stopped)" if r["stopped"] else ""
        out.append(f"| {clip} | {look} | {run} | {r['tracker']:.1f}° | {r['low']:.1f}-"
                   f"{r['high']:.1f}° | {r['still']:.1f}° | {r['best']:.1f}° |"
                   f" {r['tracked']}/{r['of']}{stopped} | {img} |")
    out += ["", "| run | median | worst | median over best fit | worst over best fit |"
            " beats held still | stopped | median image err | flags catch | flags right |"
            " tracking fps | peak memory |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for run in runs:
        rs = [r for (_, _, rn), r in rows.items() if rn == run]
        if not rs:
            continue
        err = [r["tracker"] for r in rs]
        over = [r["tracker"] - r["best"] for r in rs]
        img = [r["image_pct"] for r in rs if "image_pct" in r]
        caught, bad, flagged = np.sum([r["flags"] for r in rs], axis=0)
        out.append(
            f"| {run} | {statistics.median(err):.1f}° | {max(err):.1f}° |"
            f" {statistics.median(over):+.1f}° | {max(over):+.1f}° |"
            f" {sum(r['tracker'] < r['still'] for r in rs)}/{len(rs)} |"
            f" {sum(r['stopped'] for r in rs)} of {sum(r['starts'] for r in rs)} runs |"
            f" {f'{statistics.median(img):.1f} %' if img else ''} |"
            f" {share(caught, bad)} of {bad} | {share(caught, flagged)} of {flagged} |"
            f" {statistics.median(r['fps'] for r in rs):.1f} |"
            f" {max(r['peak_mb'] for r in rs):.0f} MB |")
    return out


def command_line(argv: list[str]) -> str:
    """The command that wrote a results file, as its reader would type it: the Bandai Namco
    folder, a path on the writer's machine, shown as FOLDER; an argument with spaces
    quoted."""
    shown, folder_next = [], False
    for arg in argv:
        if folder_next:
            arg, folder_next = "FOLDER", False
        elif arg == "--bandai-namco":
            folder_next = True
        elif arg.startswith("--bandai-namco="):
            arg = "--bandai-namco=FOLDER"
        shown.append(f'"{arg}"' if " " in arg else arg)
    return " ".join(["bench/suite.py"] + shown)


def settings_phrase(settings: dict) -> str:
    """How a results file says what the runs were tracked with."""
    if not settings:
        return "the default settings"
    given = ", ".join(f"{k} {json.dumps(v)}" for k, v in settings.items())
    return f"the default settings but {given}"


def render_missing(clips: list[Clip], looks: list[str], workers: int, t0: float) -> None:
    """Render the footage of every clip (staged) in every look that is not rendered yet,
    ``workers`` looks at once, each in a process of its own (Blender renders one scene at a
    time, on one core here)."""
    todo = [(clip.name, CACHE / slug(clip.name), look) for clip in clips for look in looks]
    todo = [(name, clip_dir, look) for name, clip_dir, look in todo
            if not look_rendered(clip_dir, look, clip_dir / slug(look))]
    if not todo:
        return
    with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn")) as pool:
        running = {pool.submit(render_look, clip_dir, look, clip_dir / slug(look)):
                   (name, look) for name, clip_dir, look in todo}
        for done in as_completed(running):
            name, look = running[done]
            print(f"{name}, {look}: rendered {done.result()} images"
                  f" ({time.perf_counter() - t0:.0f} s)", flush=True)


def main(argv=None) -> int:
    argv = sys.argv[1:] if argv is None else list(argv)
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true", help="the CMU clips at 15 fps only")
    ap.add_argument("--bandai-namco", type=Path, metavar="FOLDER",
                    help="the folder holding the Bandai Namco clips (bn_*.bvh), to add them")
    ap.add_argument("--clips", help="comma-separated clip names (default: all)")
    ap.add_argument("--looks", default=",".join(LOOKS), help="comma-separated look names")
    ap.add_argument("--runs", help="comma-separated run names (default: all but the oblique "
                    "view, or --quick's)")
    ap.add_argument("--settings", default="{}", help="tracker settings (JSON) for every run "
                    "(their jobs and tracked files named apart from the defaults')")
    ap.add_argument("--starts", type=int, help="starting frames each clip, look and run is "
                    "tracked from, its scores averaged (default 3, or 1 with --quick)")
    ap.add_argument("--half-size", action="store_true",
                    help="track on the footage halved in size (the body about 100 pixels tall)")
    ap.add_argument("--exposure-drift", action="store_true",
                    help="track on the footage with its exposure drifting (plus or minus 30 %%)")
    ap.add_argument("--workers", type=int, default=2,
                    help="renderers, then trackers, run at once (default 2, one per core; 1 "
                    "for a tracker's speed alone)")
    ap.add_argument("--write", type=Path, help="also write the tables to this markdown file")
    a = ap.parse_args(argv)
    clips = list(CLIPS)
    if a.bandai_namco and not a.quick:
        for name, file, first, last in BANDAI_NAMCO:
            path = a.bandai_namco / file
            if not path.is_file():
                raise SystemExit(f"{path}: no such file (the Bandai Namco clips: "
                                 f"{', '.join(f for _, f, _, _ in BANDAI_NAMCO)})")
            clips.append(Clip(name, path, first, last))
    if a.clips:
        clips = [c for c in clips if c.name in a.clips.split(",")]
    looks = a.looks.split(",")
    runs = a.runs.split(",") if a.runs else list(QUICK_RUNS if a.quick else DEFAULT_RUNS)
    settings = json.loads(a.settings)
    starts = a.starts or (1 if a.quick else 3)
    t0 = time.perf_counter()
    jobs = []
    for clip in clips:
        stage(clip, CACHE / slug(clip.name))
    render_missing(clips, looks, a.workers, t0)
    size = 0.5 if a.half_size else 1.0
    for clip in clips:
        clip_dir = CACHE / slug(clip.name)
        for look in looks:
            for run in runs:
                for k in range(starts):
                    job = write_job(clip_dir, look, run, settings, k)
                    if a.half_size:
                        job = halve_job(job)
                    if a.exposure_drift:
                        job = drift_job(job)
                    label = look + HALF_LABEL * a.half_size + DRIFT_LABEL * a.exposure_drift
                    jobs.append(((clip.name, label, run), k, job))
    scored: dict[tuple, list[dict]] = {}
    with ThreadPoolExecutor(a.workers) as pool:  # each tracker uses one BLAS thread
        for (key, k, _), row in zip(jobs, pool.map(
                lambda j: score_run(j[2], j[0][2], j[1], size), jobs)):
            scored.setdefault(key, []).append(row)
            print(f"{' / '.join(key)} from frame {k}: {row['tracker']:.1f}° (held still "
                  f"{row['still']:.1f}, best fit {row['best']:.1f}), "
                  f"{row['tracked']}/{row['of']}, the root's heading {row['heading']:.1f}° "
                  "off", flush=True)
    lines = table({key: over_starts(rs) for key, rs in scored.items()}, runs)
    lines.append(f"\nsuite time {time.perf_counter() - t0:.0f} s; {len(clips)} clips x"
                 f" {len(looks)} looks x {len(runs)} runs x {starts} starting frames")
    print("\n".join(lines))
    if a.write:
        head = [
            "# Benchmark results", "",
            f"Written by `{command_line(argv)}` on {time.strftime('%Y-%m-%d')}. Each clip is two "
            "seconds of real motion capture rendered in each look"
            f"{', halved in size (the body about 100 pixels tall),' if a.half_size else ''}"
            f"{', its exposure drifting (plus or minus 30 %),' if a.exposure_drift else ''}"
            " and tracked with "
            f"{settings_phrase(settings)} and the default blobs, from each of its first {starts} "
            "frame(s) (posed there by the capture): tracking is chaotic, so *tracker* is the "
            "mean over those runs, with the lowest and highest beside it. *tracker*, *held "
            "still* (the first frame's pose kept) and *best fit* (the tracked degrees of "
            "freedom fitted to the true joints, the floor; in one view the body tracked "
            "side-on, its limbs turning in the image plane and its root about the line of "
            "sight, so what it cannot reach is the limbs' turns in depth) are limb-direction "
            "errors over the eight limbs, each a mean over the runs' frames; *image "
            "err* (one view) is how far the tracked limb ends stray from the true ones in the "
            "image, in % of the body's height. A run that stops keeps its last pose. See "
            "`bench/suite.py` and `bench/suite_footage.py` for the clips and looks.", ""]
        a.write.write_text("\n".join(head + lines) + "\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())

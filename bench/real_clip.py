"""The real four-camera clip (Pose2Sim's demo, ``bench/data/pose2sim``) tracked as a user
would, through its own calibration, and scored against reference 2-D landmarks.

    python bench/real_clip.py [--frames N] [--starts N] [--stiff-back] [--one-view]
                              [--points] [--settings JSON] [--write PATH] [--sheet PATH]

A human template (metres; its lower back free, as the suite's three-view runs have it) is
fitted to the first frame's reference landmarks in all four
views (``python -m core fit``: they stand in for a user's clicks, undistorted through the
calibration's lens model), then every frame of the four movies is tracked with the default
settings (``core.run.run_job``, what ``python -m core track`` runs), each camera the
calibration's pinhole. Score: per view
and frame, the mean image distance of the tracked joints (shoulders, elbows, wrists, hips,
knees, ankles), projected through the calibration's lens, to MediaPipe's landmarks (those
it calls visible), in % of the body's height in that view, left and right taken the way
that matches better (the frontal view's landmarks swap sides on about 30 frames); first and
last five frames apart. Beside it: the fitted first pose held still, and every frame fitted
to its own landmarks with the tracked body's proportions (the floor the landmarks' own noise
and the template's joint centres leave). With ``--one-view``, each camera is also tracked
alone (a phone's one video), from the same first pose, and scored in its own image. With
``--points``, the run from the first frame is also read point by point beside the floor,
over the first and the last five frames: where the last frames lose. ``--settings``
tracks with other tracker settings (a job's ``"settings"``), in a folder of its own.
Writes into ``.cache/real/``; ``make bench`` runs it after the suite (``make bench-real``
alone), into ``docs/REAL_CLIP.md``.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import time
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))

import evaluate  # noqa: E402
from captures import LIMB_ROLES  # noqa: E402
from suite import BAD_LIMB_DEG, flag_counts, settings_digest, share  # noqa: E402

from core import raycast  # noqa: E402
from core.bvh import BvhFile, BvhJoint, read_bvh, write_bvh  # noqa: E402
from core.calibration import read_calibration  # noqa: E402
from core.init_fit import fit_pose  # noqa: E402
from core.job import load_job  # noqa: E402
from core.lens import Undistorted, distort_points, undistort_points  # noqa: E402
from core.pose import BodyPose  # noqa: E402
from core.run import report, result_bvh, run_job  # noqa: E402
from core.skeleton import BALL, HINGE, Skeleton, human_template  # noqa: E402
from core.video import VideoFrames  # noqa: E402

DATA = ROOT / "bench" / "data" / "pose2sim"
WORK = ROOT / ".cache" / "real"
FPS = 60
VISIBLE = 0.5  # MediaPipe visibility above which a landmark is used
# the template's points (a joint, or "<joint>/end") and MediaPipe Pose's landmark indices
POINTS = {"LeftShoulder": 11, "RightShoulder": 12, "LeftElbow": 13, "RightElbow": 14,
          "LeftElbow/end": 15, "RightElbow/end": 16, "LeftHip": 23, "RightHip": 24,
          "LeftKnee": 25, "RightKnee": 26, "LeftKnee/end": 27, "RightKnee/end": 28}
SWAP = {name: name.replace("Left", "Right") if "Left" in name else name.replace("Right", "Left")
        for name in POINTS}
# the template's joint (or end site) for each of the suite's limb roles, and so its eight
# limbs (label, from, to), as the suite scores its flags on them
ROLES = {f"{role}.{side[0]}": f"{side}{joint}" for side in ("Left", "Right")
         for role, joint in (("thigh", "Hip"), ("shank", "Knee"), ("foot", "Knee/end"),
                             ("upper_arm", "Shoulder"), ("forearm", "Elbow"),
                             ("hand", "Elbow/end"))}
LIMBS = [(label, ROLES[a], ROLES[b]) for label, a, b in LIMB_ROLES]


def template_bvh(sk: Skeleton) -> BvhFile:
    """The template as a BVH hierarchy (ZXY rotations, the root translating too)."""
    joints = []
    for j, name in enumerate(sk.names):
        rot = ["Zrotation", "Xrotation", "Yrotation"]
        channels = (["Xposition", "Yposition", "Zposition"] + rot) if j == 0 else rot
        joints.append(BvhJoint(name, int(sk.parents[j]), np.array(sk.offsets[j], float),
                               channels, [np.array(e, float) for e in sk.end_sites[j]]))
    return BvhFile(joints, np.zeros((1, 3 + 3 * sk.n_joints)), 1.0 / FPS)


def joint_spec(sk: Skeleton) -> dict:
    """The job's ``skeleton.joints``: the template's own kinds, axes and limits."""
    out = {}
    for j, name in enumerate(sk.names):
        if sk.kinds[j] == BALL:
            out[name] = "ball"
        elif sk.kinds[j] == HINGE:
            out[name] = {"kind": "hinge", "axis": sk.axes[j].tolist(),
                         "limits": np.degrees(sk.limits[j]).tolist()}
    return out


def triangulate(cams, pixels: np.ndarray) -> np.ndarray:
    """World point (3,) seen at ideal (undistorted) ``pixels`` (views, 2): linear least
    squares over every view."""
    rows = []
    for cam, (u, v) in zip(cams, pixels):
        P = cam.K @ np.hstack([cam.R, cam.t[:, None]])
        rows += [u * P[2] - P[0], v * P[2] - P[1]]
    X = np.linalg.svd(np.array(rows))[2][-1]
    return X[:3] / X[3]


def ideal_points(cams, landmarks: np.ndarray, frame: int) -> dict[str, np.ndarray]:
    """Each scored point's landmark on ``frame`` in every view (views, 2), undistorted
    through that view's lens (visible or not)."""
    return {k: np.array([undistort_points(landmarks[c, frame, i][None], cam.camera.K,
                                          cam.dist)[0] for c, cam in enumerate(cams)])
            for k, i in POINTS.items()}


def guess_pose(sk: Skeleton, cams, ideal: dict[str, np.ndarray]) -> tuple:
    """A first guess of the template's pose from the landmarks (views, 2) of both hips and
    shoulders: the root between the hips, upright along the calibration's z, facing away
    from the hips' left-right line."""
    X = {k: triangulate(cams, ideal[k]) for k in ("LeftHip", "RightHip", "LeftShoulder",
                                                  "RightShoulder")}
    up = np.array([0.0, 0.0, 1.0])
    left = X["LeftHip"] - X["RightHip"]
    left = left - (left @ up) * up
    left /= np.linalg.norm(left)
    forward = np.cross(left, up)
    R = np.repeat(np.eye(3)[None], sk.n_joints, 0)
    R[0] = np.stack([left, up, forward], 1)  # the template's x (left), y (up), z (forward)
    rest = sk.rest_positions
    mid = (rest[sk.index("LeftHip")] + rest[sk.index("RightHip")]) / 2 - rest[0]
    return R, (X["LeftHip"] + X["RightHip"]) / 2 - R[0] @ mid


def _run(*args) -> subprocess.CompletedProcess:
    proc = subprocess.run([sys.executable, "-m", "core", *map(str, args)], cwd=ROOT,
                          capture_output=True, text=True)
    if proc.returncode not in (0, 3):
        raise SystemExit(f"core {args[0]} failed:\n{proc.stderr}")
    return proc


def point_positions(sk: Skeleton, R: np.ndarray, root: np.ndarray) -> dict[str, np.ndarray]:
    """World positions of the scored points of a pose."""
    M = sk.joint_frames(R, root)
    return {name: evaluate.named_point(sk, M, name) for name in POINTS}


def errors_pct(sk: Skeleton, poses: list, cams, landmarks: np.ndarray, visibility: np.ndarray
               ) -> np.ndarray:
    """(frames, views): mean distance of the scored points to the visible landmarks, in %
    of the body's height in that view, left and right matched the better way
    (``point_errors_pct``'s mean over the points; NaN where none is visible)."""
    per_point = point_errors_pct(sk, poses, cams, landmarks, visibility)
    seen = (~np.isnan(per_point)).sum(axis=2)
    return np.where(seen > 0, np.nansum(per_point, axis=2) / np.maximum(seen, 1), np.nan)


def point_errors_pct(sk: Skeleton, poses: list, cams, landmarks: np.ndarray,
                     visibility: np.ndarray) -> np.ndarray:
    """(frames, views, points in ``POINTS``' order): each scored point's distance to its
    landmark in % of the body's height in that view, left and right matched the way whose
    mean over the frame's visible points is lower, NaN where not visible."""
    out = np.full((len(poses), len(cams), len(POINTS)), np.nan)
    for f, (R, root) in enumerate(poses):
        pts = point_positions(sk, R, root)
        for c, cam in enumerate(cams):
            d = _point_distances(pts, cam, landmarks[c, f], visibility[c, f])
            means = _means(d)
            if np.isfinite(min(means)):
                height = sk.height() * cam.camera.scale_at(root)
                out[f, c] = 100 * d[int(np.argmin(means))] / height
    return out


def _point_distances(pts: dict, cam, landmarks: np.ndarray, visibility: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
    """Pixel distances (points,) of the points ``pts`` (world), seen by ``cam``, to one
    frame's landmarks (33, 2) of that view, NaN where the landmark is not visible: as
    labelled, and with left and right swapped."""
    px = {k: distort_points(cam.camera.project(v), cam.camera.K, cam.dist) for k, v in pts.items()}

    def distances(match):
        return np.array([np.linalg.norm(px[k] - landmarks[POINTS[match[k]]])
                         if visibility[POINTS[match[k]]] > VISIBLE else np.nan
                         for k in POINTS])
    return distances({k: k for k in POINTS}), distances(SWAP)


def _distances(pts: dict, cam, landmarks: np.ndarray, visibility: np.ndarray
               ) -> tuple[float, float]:
    """Mean pixel distance of the points ``pts`` (world), seen by ``cam``, to one frame's
    visible landmarks (points, 2) of that view: as labelled, and with left and right
    swapped (inf where none is visible)."""
    return _means(_point_distances(pts, cam, landmarks, visibility))


def _means(distances: tuple[np.ndarray, ...]) -> tuple[float, ...]:
    """The mean of each of ``_point_distances``' arrays over its visible points (inf where
    none is)."""
    return tuple(float(np.mean(d[~np.isnan(d)])) if (~np.isnan(d)).any() else np.inf
                 for d in distances)


def flag_line(sk: Skeleton, rep: dict, tracked: list, floor: list) -> str:
    """The report's limb flags read against each frame fitted to its own landmarks (the
    nearest to a truth the clip has), as the suite reads them against the capture
    (``suite.flag_counts``): how many of the limbs over ``BAD_LIMB_DEG`` off that fit are
    flagged, and how many of the flags are on such limbs. ``tracked`` and ``floor``: per
    frame (rotations, root)."""
    est, truth = ((np.array([R for R, _ in poses]), np.array([p for _, p in poses]))
                  for poses in (tracked, floor))
    caught, bad, flagged = flag_counts(rep, sk, est, truth, LIMBS)
    return (f"Flags against each frame fitted to its landmarks: {share(caught, bad)} of the "
            f"{bad} limbs over {BAD_LIMB_DEG:g}° off that fit flagged, {share(caught, flagged)} "
            f"of the {flagged} flags on such limbs.")


def fitted_each_frame(sk: Skeleton, poses: list, cams, views, mode: str, landmarks: np.ndarray,
                      visibility: np.ndarray) -> list:
    """Every frame's pose fitted to that frame's own landmarks, the body's proportions as
    tracked (``fit_pose`` without lengths), from the tracked pose: the floor that the
    template's joint centres and the landmarks' noise leave. A view whose landmarks lie
    nearer the fit with their sides swapped is fitted again that way, as the score reads it."""
    out = []
    for f, (R, root) in enumerate(poses):
        swap = [False] * len(cams)
        guess = BodyPose(R, root, [v.copy() for v in views])
        for _ in range(2):
            clicks = []
            for c, cam in enumerate(cams):
                names = SWAP if swap[c] else {k: k for k in POINTS}
                clicks.append({k: undistort_points(landmarks[c, f, POINTS[names[k]]][None],
                                                   cam.camera.K, cam.dist)[0]
                               for k in POINTS if visibility[c, f, POINTS[names[k]]] > VISIBLE})
            fit = fit_pose(sk, guess, clicks, mode, fit_lengths=False).pose
            pts = point_positions(sk, fit.rotations, fit.root_position)
            nearer = []
            for c, cam in enumerate(cams):
                labelled, swapped = _distances(pts, cam, landmarks[c, f], visibility[c, f])
                nearer.append(swapped < labelled)
            if nearer == swap:
                break
            swap = nearer
        out.append((fit.rotations, fit.root_position))
    return out


def run(frames: int = 100, lower_back: bool = True, sheet: Path | None = None,
        starts: int = 1, one_view: bool = False, settings: dict | None = None,
        points: bool = False) -> list[str]:
    """Fit, track and score the clip's first ``frames`` frames, from its first frame and, with
    ``starts`` over 1, from each of the next ones too (the spread a difference must beat);
    the result as Markdown (and with ``sheet``, a contact sheet of the first, middle and
    last frames of the run from the first frame there). With ``one_view``, each camera is
    also tracked alone from the same first pose (``one_view_table``); with ``points``, the
    run from the first frame is also read point by point (``point_table``). ``settings``:
    the tracker's settings where not the defaults (tracked in a folder of their own)."""
    settings = settings or {}
    work = WORK / f"settings_{settings_digest(settings)}" if settings else WORK
    work.mkdir(parents=True, exist_ok=True)
    sk = human_template(lower_back=lower_back)
    cams = read_calibration(DATA / "Calib.qca.txt")
    lm = np.load(DATA / "mediapipe_landmarks.npz")
    landmarks, visibility = lm["xy"].astype(float), lm["visibility"]
    assert [str(n) for n in lm["names"]] == [c.name for c in cams]
    write_bvh(template_bvh(sk), work / "template.bvh")
    runs = [_track_from(work, settings, k, frames, sk, cams, landmarks, visibility)
            for k in range(starts)]
    fsk, tracked, job, fit_log, seconds, rep = runs[0]
    e_track = errors_pct(fsk, tracked, cams, landmarks, visibility)
    e_still = errors_pct(fsk, [tracked[0]] * len(tracked), cams, landmarks, visibility)
    floor = fitted_each_frame(fsk, tracked, cams, job.initial.views, job.mode, landmarks,
                              visibility)
    e_floor = errors_pct(fsk, floor, cams, landmarks, visibility)
    if sheet is not None:
        n = len(tracked)
        contact_sheet(fsk, tracked, cams, [0, n // 2, n - 1], sheet)
    lines = _table(e_track, e_still, e_floor, rep, fit_log, seconds, lower_back)
    lines += ["", flag_line(fsk, rep, tracked, floor)]
    if points:
        lines += [""] + point_table(fsk, tracked, floor, cams, landmarks, visibility)
    if starts > 1:
        per_frame = [np.nanmean(errors_pct(r[0], r[1], cams, landmarks[:, k:], visibility[:, k:]),
                                axis=1) for k, r in enumerate(runs)]
        lines += ["", _spread([np.mean(e) for e in per_frame],
                              [np.mean(e[:5]) for e in per_frame],
                              [np.mean(e[-5:]) for e in per_frame])]
    if one_view:
        lines += [""] + one_view_table(work, settings, frames, sk, cams, landmarks,
                                       visibility, floor)
    return lines


def point_table(sk: Skeleton, tracked: list, floor: list, cams, landmarks: np.ndarray,
                visibility: np.ndarray) -> list[str]:
    """Each scored point's distance to its landmarks over the first and the last five
    frames (mean over the cameras), tracked beside every frame fitted to its own landmarks
    (``fitted_each_frame``'s poses, ``floor``): which points the last frames lose on, as
    Markdown."""
    errors = [point_errors_pct(sk, poses, cams, landmarks, visibility)
              for poses in (tracked, floor)]
    lines = ["Each point (mean over the cameras, % of body height): tracked, and each frame "
             "fitted to its landmarks", "",
             "| point | first 5 | fitted | last 5 | fitted |", "|---|---|---|---|---|"]
    for i, name in enumerate(POINTS):
        label = name.replace("Elbow/end", "Wrist").replace("Knee/end", "Ankle")
        lines.append(f"| {label} | " + " | ".join(
            f"{np.nanmean(e[part, :, i]):.1f}" for part in (slice(0, 5), slice(-5, None))
            for e in errors) + " |")
    return lines


def one_view_table(work: Path, settings: dict, frames: int, sk: Skeleton, cams,
                   landmarks: np.ndarray, visibility: np.ndarray, floor: list) -> list[str]:
    """Each camera tracked alone (one view, so side-on), from the first pose fitted in all
    four, and scored in its own image, beside that pose held still and ``floor`` (every frame
    fitted to the four views' landmarks): a phone's one video, with the first pose right."""
    lines = ["Each camera alone (one view, tracked side-on from the same first pose), scored "
             "in that camera's image: mean distance to its landmarks, % of body height", "",
             "| camera | tracked | first 5 | last 5 | first pose held still | each frame "
             "fitted (four views) | frames to check | doubt begins on |",
             "|---|---|---|---|---|---|---|---|"]
    for c, cam in enumerate(cams):
        fsk, tracked, _, _, _, rep = _track_from(work, settings, 0, frames, sk, cams,
                                                 landmarks, visibility, camera=c)
        e, still, best = (np.nanmean(errors_pct(fsk, poses, [cam], landmarks[c:c + 1],
                                                visibility[c:c + 1]), axis=1)
                          for poses in (tracked, [tracked[0]] * len(tracked), floor))
        lines.append(f"| {cam.name} | {np.nanmean(e):.1f} | {np.nanmean(e[:5]):.1f} | "
                     f"{np.nanmean(e[-5:]):.1f} | {np.nanmean(still):.1f} | "
                     f"{np.nanmean(best):.1f} | {len(rep['frames_to_check'])} | "
                     f"{len(rep['doubts_begin'])} |")
    return lines


def _fit_first_pose(work: Path, start: int, sk: Skeleton, cams, landmarks: np.ndarray,
                    visibility: np.ndarray, template: Path) -> str:
    """The template fitted to frame ``start``'s landmarks in all the cameras (``core fit``),
    written to ``work``/fitted.bvh; the fit's log."""
    R0, root0 = guess_pose(sk, [c.camera for c in cams], ideal_points(cams, landmarks, start))
    write_bvh(template_bvh(sk).with_motion(R0[None], root0[None]), work / "guess.bvh")
    clicks = [{k: landmarks[c, start, i].tolist() for k, i in POINTS.items()
               if visibility[c, start, i] > VISIBLE} for c in range(len(cams))]
    skeleton = {"bvh": str(template), "joints": joint_spec(sk)}
    fit = {"skeleton": skeleton, "initial": {"bvh": "guess.bvh"}, "views": _views(cams),
           "mode": "calibrated", "clicks": clicks}
    (work / "fit.json").write_text(json.dumps(fit, indent=1))
    return _run("fit", work / "fit.json", "--out", work / "fitted.bvh").stderr.strip()


def _views(cams) -> list[dict]:
    """A job's views, one per camera of the clip's calibration."""
    return [{"camera": {"calibration": str(DATA / "Calib.qca.txt"), "name": c.name}}
            for c in cams]


def _track_from(root: Path, settings: dict, start: int, frames: int, sk: Skeleton, cams,
                landmarks: np.ndarray, visibility: np.ndarray, camera: int | None = None
                ) -> tuple:
    """The template fitted to frame ``start``'s landmarks (``_fit_first_pose``) and tracked
    from there to frame ``frames`` - 1 with ``settings``, in ``root`` (a folder of
    its own for a later start): (the fitted body, the tracked (rotations, root) per frame,
    the job, the fit's log, seconds tracking, the report). With ``camera``, that camera's
    view alone is tracked, in a folder of its own, from the body the run of all the cameras
    from ``start`` fitted (so that run comes first; the log is then empty)."""
    base = root if start == 0 else root / f"from_{start}"
    base.mkdir(exist_ok=True)
    work, fit_log = base, ""
    if camera is None:
        fit_log = _fit_first_pose(base, start, sk, cams, landmarks, visibility,
                                  root / "template.bvh")
    else:
        work = base / f"only_{cams[camera].name}"
        work.mkdir(exist_ok=True)
    fitted = os.path.relpath(base / "fitted.bvh", work)
    tracked = cams if camera is None else [cams[camera]]
    spec = {"skeleton": {"bvh": fitted, "joints": joint_spec(sk)},
            "initial": {"bvh": fitted}, "mode": "calibrated", "frame_time": 1.0 / FPS,
            "settings": settings,
            "views": [dict(v, images=str(DATA / f"{c.name}.mp4"))
                      for v, c in zip(_views(tracked), tracked)]}
    (work / "job.json").write_text(json.dumps(spec, indent=1))
    job = load_job(work / "job.json")  # the fitted body, with the blobs it tracks
    job.images = [_frames(movie, start, frames) for movie in job.images]
    t0 = time.perf_counter()
    result = run_job(job)
    seconds = time.perf_counter() - t0
    write_bvh(result_bvh(job, result), work / "tracked.bvh")
    rep = report(job, result, seconds)
    (work / "report.json").write_text(json.dumps(rep, indent=1))
    R, p = read_bvh(work / "tracked.bvh").poses()
    return job.skeleton, list(zip(R, p)), job, fit_log, seconds, rep


def _frames(movie, start: int, stop: int):
    """A view's movie frames ``start`` to ``stop`` - 1 (read undistorted as the movie is)."""
    if isinstance(movie, Undistorted):
        return Undistorted(_frames(movie.source, start, stop), movie.K, movie.dist, movie.size)
    return movie.select(list(range(start, min(stop, len(movie)))))


def _spread(means: list[float], first_fives: list[float], last_fives: list[float]) -> str:
    """One line on the runs from several starting frames: each start's mean over all its
    frames, its first and last five, and its last five over its first five (how far the track
    drifts from the user's pose), as the mean over the starts and their range."""
    def stat(x, digits=1):
        return f"{np.mean(x):.{digits}f} ({min(x):.{digits}f}-{max(x):.{digits}f})"
    ratios = [last / first for first, last in zip(first_fives, last_fives)]
    return (f"From frames 0-{len(means) - 1}, each start's first pose fitted to that frame's "
            f"landmarks (mean over the starts, their range): all frames {stat(means)}, first "
            f"five {stat(first_fives)}, last five {stat(last_fives)}, last five over first five "
            f"{stat(ratios, 2)}x: a change inside that range is no change.")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--frames", type=int, default=100, help="frames to track (of 100)")
    ap.add_argument("--stiff-back", action="store_true",
                    help="the paper's 19-DOF template: the lower back not free")
    ap.add_argument("--write", help="a Markdown file to write the result into")
    ap.add_argument("--sheet", type=Path, help="a contact sheet (JPEG) to write")
    ap.add_argument("--starts", type=int, default=1,
                    help="also track from each of the next starts - 1 frames (the spread)")
    ap.add_argument("--one-view", action="store_true",
                    help="also track each camera alone, from the same first pose")
    ap.add_argument("--points", action="store_true",
                    help="also each scored point's first and last five frames, tracked and "
                         "each frame fitted")
    ap.add_argument("--settings", default="{}", help="tracker settings (JSON) for every run")
    args = ap.parse_args(argv)
    lines = run(args.frames, not args.stiff_back, args.sheet, args.starts, args.one_view,
                json.loads(args.settings), args.points)
    print("\n".join(lines))
    if args.write:
        Path(args.write).write_text("\n".join([
            "# The real clip", "",
            f"Written by `make bench-real` (`bench/real_clip.py`) on {time.strftime('%Y-%m-%d')}."
            " Pose2Sim's single-person demo (`bench/data/SOURCES.md`): a man on a lab platform "
            "leaning, lifting a leg sideways and raising his arms, filmed by four calibrated "
            "cameras about 3.3 m away (1088x1920, lens distortion), tracked through its own "
            "Qualisys calibration from a first pose fitted to the first frame's reference "
            "landmarks. The landmarks are MediaPipe's, not ground truth: triangulated, they "
            "reproject within 17 px (median, about 2 % of the body's height) of "
            "themselves." + (f" Tracker settings: `{args.settings}`." if json.loads(
                args.settings) else ""), ""] + lines)
            + "\n")
    return 0


def contact_sheet(sk: Skeleton, poses: list, cams, frames: list[int], path: Path) -> None:
    """The tracked body's blobs (the person's left red, right blue) over the undistorted
    footage of every view (columns) on ``frames`` (rows), a quarter of full size, as JPEG."""
    rows = []
    for f in frames:
        g = sk.segment_motions(sk.joint_frames(*poses[f]))
        tiles = []
        for cam in cams:
            img = Undistorted([], cam.camera.K, cam.dist).remap(
                VideoFrames(DATA / f"{cam.name}.mp4")[f])
            pix, hits, _ = raycast.render_labels(cam.camera, sk.blobs, g, img.shape[:2], 2)
            paint = img.copy()
            left = np.array(["Left" in b.name for b in sk.blobs])[hits.label]
            for colour, on in (((40, 40, 230), left), ((230, 90, 40), ~left)):
                xy = pix[on].astype(int)
                paint[xy[:, 1], xy[:, 0]] = colour
                paint[np.minimum(xy[:, 1] + 1, img.shape[0] - 1), xy[:, 0]] = colour
                paint[xy[:, 1], np.minimum(xy[:, 0] + 1, img.shape[1] - 1)] = colour
            mixed = cv2.addWeighted(img, 0.5, paint, 0.5, 0)
            tiles.append(cv2.resize(mixed[300:1700], None, fx=0.25, fy=0.25,
                                    interpolation=cv2.INTER_AREA))
        rows.append(np.hstack(tiles))
    cv2.imwrite(str(path), np.vstack(rows), [cv2.IMWRITE_JPEG_QUALITY, 80])


def _table(e_track, e_still, e_floor, rep, fit_log, seconds, lower_back) -> list[str]:
    def row(name, e):
        per_frame = np.nanmean(e, axis=1)
        return (f"| {name} | {np.nanmean(e):.1f} | {np.nanmean(per_frame[:5]):.1f} | "
                f"{np.nanmean(per_frame[-5:]):.1f} | "
                + " | ".join(f"{np.nanmean(e[:, c]):.1f}" for c in range(e.shape[1])) + " |")

    n = len(e_track)
    return [
        f"Real clip (Pose2Sim demo, 4 calibrated pinhole cameras, {n} frames at {FPS} fps, "
        f"template {'with' if lower_back else 'without'} the lower back free): mean "
        "distance of 12 tracked points to MediaPipe's landmarks, % of body height", "",
        "| run | all frames | first 5 | last 5 | cam01 | cam02 | cam03 | cam04 |",
        "|---|---|---|---|---|---|---|---|",
        row("tracked", e_track), row("first pose held still", e_still),
        row("each frame fitted to its landmarks", e_floor), "",
        f"first frame's fit: {fit_log.splitlines()[0].split(' -> ')[0]}; tracked "
        f"{rep['frames_tracked']} of {rep['frames_total']} frames in {seconds:.0f} s; frames "
        f"to check: {len(rep['frames_to_check'])}, doubt beginning on "
        f"{len(rep['doubts_begin'])} of them (marked on the timeline)"]


if __name__ == "__main__":
    sys.exit(main())

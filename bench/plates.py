"""Muybridge's printed plates tracked end to end and measured against the animal's outline.

    python bench/plates.py [NAME ...] [--settings JSON] [--write docs/PLATES.md]

For each plate with clicks in ``bench/data/plates/NAME.json``: the plate is cut into its
cells (``core.plate``), a planar quadruped is built from the joints clicked on the first
frame (each bone from its clicked head to the next click; the body lies in the image plane,
the near legs ``side_apart`` pixels in front of the far ones, every joint a hinge about the
line of sight, within a quadruped's ranges), and tracked through every frame with the
default settings, side-on, through one still orthographic camera whose pixels are the
world's units, as the examples in Blender are: Muybridge's cameras stood in a row beside the
track, so the animal is as large in every cell, and a view left to scale itself grew the
body over what it does not model (a rider, a tail) by a fifth. Scored per frame: the
overlap (intersection over union) of the tracked blobs' outline with the animal's
silhouette (the pixels clearly darker than the light backdrop, specks removed, the largest
piece), beside the first frame's pose carried along with the tracked body (its root as
tracked, its joints as clicked). A rider, and most tails, are not modelled, so even the
first frame's overlap is well under 1: the measure is the tracked frames against the
first. ``--settings`` tracks with other tracker settings (a job's ``"settings"``).

Scored too against points clicked by hand on every frame (``"scored"`` in the clicks file):
the snout and the feet that can be told apart, fore and hind. Which foot of a pair is the
near one cannot be read off every frame of a small print, so a pair of clicked feet is
matched to the body's pair of the same end (fore or hind) the way that puts them nearer,
and one clicked foot to the nearer of the two. Distances are in % of the body's length (the
first frame's clicked rump to snout).
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from dataclasses import dataclass
from datetime import date
from pathlib import Path

import cv2
import numpy as np
from scipy.ndimage import median_filter

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # this tree's core, before anything imports another's

from evaluate import named_point  # noqa: E402

from core import raycast, se3  # noqa: E402
from core.camera import View  # noqa: E402
from core.frame_fit import FrameResult  # noqa: E402
from core.image import load_grey, quiet_stderr  # noqa: E402
from core.linearize import Kinematics  # noqa: E402
from core.plate import write_frames  # noqa: E402
from core.pose import CALIBRATED, BodyPose  # noqa: E402
from core.settings import TrackerSettings  # noqa: E402
from core.skeleton import FIXED, HINGE, Skeleton, bone_blob, quadruped_limits  # noqa: E402
from core.tracker import Tracker, track  # noqa: E402

DATA = ROOT / "bench" / "data" / "plates"
DRAWS = 8  # runs per plate: from the clicks as clicked, then nudged (``nudged``)
DARKER = 0.15  # how much darker than the backdrop's light a pixel of the animal is
PARENT = {"Trunk": None, "Neck": "Trunk", "Head": "Neck",
          **{f"{s}{e}{p}": ("Trunk" if p == "Upper" else f"{s}{e}Upper")
             for s in ("Left", "Right") for e in ("Fore", "Hind") for p in ("Upper", "Lower")}}


def planar_body(spec: dict, unit: float = 1.0) -> tuple[Skeleton, BodyPose]:
    """The quadruped of ``spec`` (clicks, radii, side_apart: pixels; near: the side facing
    the camera, Left unless said) and its pose on the first frame: the rest pose, every
    rotation the identity, seen by an orthographic view looking along -z (world y up,
    image y down) at ``unit`` world units per pixel, whose pixel (0, 0) is the world's
    origin. Its hinges keep within ``quadruped_limits`` of the clicked pose. Where the
    clicks name a tail (``Tail``, ``Tail2``, ... from the rump, ``radii["tail"]`` wide), it
    is a chain of hinges too: a tail left out stays foreground no blob covers, and draws
    the hind legs onto it."""
    clicks, near = spec["clicks"], spec.get("near", "Left")
    apart = spec["side_apart"]
    r = {k: np.asarray(v, float) * unit for k, v in spec["radii"].items()}

    def at(name: str) -> np.ndarray:
        x, y = clicks[name]
        side = name.split("/")[0]
        z = (apart if side.startswith(near) else -apart) if side.startswith(
            ("Left", "Right")) else 0
        return np.array([x, -y, z], float) * unit

    tail = sorted((n for n in clicks if n.startswith("Tail") and "/" not in n), key=len)
    parent = {**PARENT, **{n: tail[k - 1] if k else "Trunk" for k, n in enumerate(tail)}}
    names = list(parent)
    pos = {n: at(n) for n in names}
    offsets = np.array([pos[n] - (pos[parent[n]] if parent[n] else 0) for n in names])
    ends = [[at(f"{n}/end") - pos[n]] if f"{n}/end" in clicks else [] for n in names]
    sk = Skeleton(names, [names.index(parent[n]) if parent[n] else -1 for n in names], offsets,
                  [FIXED] + [HINGE] * (len(names) - 1), np.tile([0, 0, 1.0], (len(names), 1)),
                  ends)
    sk.limit_hinges(quadruped_limits(names))
    # the trunk from a little behind and below the rump to a little past the neck's base
    chest = pos["Neck"] - pos["Trunk"]
    sk.blobs = [bone_blob(0, "Trunk", pos["Trunk"] + np.array([-4, -4, 0]) * unit,
                          chest + np.array([8, 0, 0]) * unit, tuple(r["trunk"]))]
    for j, n in enumerate(names[1:], 1):
        kids = sk.children(j)
        tip = ends[j][0] if ends[j] else offsets[kids[0]]
        width = r["neck"] if n in ("Neck", "Head") else r["tail"] if n in tail else r["limb"]
        sk.blobs.append(bone_blob(j, n, pos[n], tip, float(width)))
    view = View(se3.Similarity(1.0 / unit, np.diag([1.0, -1.0, -1.0]),
                               np.array([0, 0, 100.0 * unit])), np.zeros(2))
    return sk, BodyPose(np.tile(np.eye(3), (len(names), 1, 1)), pos["Trunk"].copy(), [view])


def silhouette(grey: np.ndarray) -> np.ndarray:
    """The animal in a frame of light backdrop: pixels ``DARKER`` under the light of their
    part of the frame (each column's 90th percentile, the median over 15 columns: prints
    darken toward a cell's edges), specks and cracks of a pixel removed, the largest piece.
    Where the frame ends in dark ground (the camel's), the rows from the ground's edge down
    are left out (the feet's last pixels with them)."""
    light = median_filter(np.percentile(grey, 90, axis=0), size=15, mode="nearest")
    dark = (grey < light - DARKER).astype(np.uint8)
    light = float(np.median(light))
    rows = np.median(grey, axis=1)
    low = len(rows) // 2
    edge = low + int(np.argmin(np.diff(rows[low:]))) + 1
    if np.median(rows[edge:]) < light - DARKER:
        dark[edge:] = 0
    dark = cv2.morphologyEx(dark, cv2.MORPH_OPEN, np.ones((3, 3), np.uint8))
    dark = cv2.morphologyEx(dark, cv2.MORPH_CLOSE, np.ones((3, 3), np.uint8))
    n, labels, stats, _ = cv2.connectedComponentsWithStats(dark)
    if n < 2:
        return np.zeros(grey.shape, bool)
    return labels == 1 + int(np.argmax(stats[1:, cv2.CC_STAT_AREA]))


def overlap(sk: Skeleton, pose: BodyPose, sil: np.ndarray) -> float:
    """Intersection over union of the pixels the body's blobs cover at ``pose`` in its one
    view with the silhouette ``sil`` (boolean, the frame's size)."""
    pix, _, box = raycast.render_labels(pose.views[0], sk.blobs,
                                        Kinematics(sk, pose).segments, sil.shape, 1)
    covered = np.zeros(sil.shape, bool)
    if box is not None:
        covered[pix[:, 1].astype(int), pix[:, 0].astype(int)] = True
    return float((covered & sil).sum() / max((covered | sil).sum(), 1))


FEET = {"fore": ("LeftForeLower", "RightForeLower"), "hind": ("LeftHindLower", "RightHindLower")}


def body_length(spec: dict) -> float:
    """Pixels from the rump (the trunk's clicked joint) to the snout on the first frame."""
    return float(np.linalg.norm(np.subtract(spec["clicks"]["Head/end"], spec["clicks"]["Trunk"])))


def tips(sk: Skeleton, pose: BodyPose) -> dict[str, np.ndarray]:
    """Where the snout and the four feet (their bones' end sites) fall in the one view."""
    M = sk.joint_frames(pose.rotations, pose.root_position)
    return {name: pose.views[0].project(named_point(sk, M, f"{name}/end")[None])[0]
            for name in ("Head", *FEET["fore"], *FEET["hind"])}


def click_distances(clicked: dict, at: dict[str, np.ndarray]) -> list[float]:
    """Pixel distances of one frame's clicked snout and feet (``"scored"`` entry) to the
    body's ``tips``; each clicked pair of feet matched to the body's pair as puts them
    nearer, a lone clicked foot to the nearer of the two."""
    out = [float(np.linalg.norm(np.subtract(clicked["snout"], at["Head"])))]
    for end, names in FEET.items():
        feet = np.asarray(clicked.get(end, []), float).reshape(-1, 2)
        ours = np.array([at[n] for n in names])
        d = np.linalg.norm(feet[:, None] - ours[None], axis=2)  # clicked x body
        if len(feet) == 2:
            out += list(min((d[0, 0], d[1, 1]), (d[0, 1], d[1, 0]), key=sum))
        elif len(feet) == 1:
            out.append(float(d[0].min()))
    return [float(x) for x in out]


@dataclass
class FrameScore:
    frame: int  # 1-based, the plate's reading order
    tracked: float  # the tracked outline's overlap with the silhouette
    carried: float  # the first frame's pose carried along with the body
    flagged: dict  # the tracker's limb flags there
    diverged: bool
    clicks: float = float("nan")  # the clicked points' mean distance, % of the body's length
    clicks_worst: float = float("nan")  # the farthest clicked point, % of the body's length
    clicks_carried: float = float("nan")  # the mean for the first pose carried along


def cut_frames(spec: dict) -> list[Path]:
    """The frames of a clicks file that names frames already cut (``"frames"``, a folder of
    the repository), in order."""
    return sorted((ROOT / spec["frames"]).glob("*.png"))


def clicks_on_cut(spec: dict, offsets: list[float]) -> dict:
    """The clicks file with its ``"scored"`` points moved onto frames cut with the cells'
    ``offsets`` down (``core.plate``) from the frames they were clicked on (cut with
    ``"scored_cut"``): a point on a cell's row r + cut is on row r + cut - offset now."""
    if "scored_cut" not in spec:
        return spec
    moved = {}
    for frame, pts in spec.get("scored", {}).items():
        dy = spec["scored_cut"][int(frame) - 1] - offsets[int(frame) - 1]
        moved[frame] = {part: (np.asarray(xy, float).reshape(-1, 2) + (0.0, dy)).reshape(
            np.shape(xy)).tolist() for part, xy in pts.items()}
    return dict(spec, scored=moved)


def nudged(spec: dict, draw: int) -> dict:
    """The clicks file with every joint clicked on the first frame moved by -1, 0 or 1
    pixel across and down (seeded by ``draw``; 0: as clicked): where the clicks could as
    well have fallen, to tell the tracker's chaos from a difference."""
    if not draw:
        return spec
    rng = np.random.default_rng(draw)
    return dict(spec, clicks={name: (np.asarray(xy, float) + rng.integers(-1, 2, 2)).tolist()
                              for name, xy in spec["clicks"].items()})


def run(name: str, draw: int = 0, settings: dict | None = None) -> list[FrameScore]:
    """Cut, pose (from the clicks ``nudged`` by ``draw``), track (with the tracker's
    ``settings`` where not the defaults) and score the plate ``name``."""
    spec = nudged(json.loads((DATA / f"{name}.json").read_text()), draw)
    sk, first = planar_body(spec)
    with tempfile.TemporaryDirectory() as tmp:
        if "plate" in spec:
            cells, paths = write_frames(ROOT / spec["plate"], tmp)
            spec = clicks_on_cut(spec, [c.offset[1] for c in cells])
        else:
            paths = cut_frames(spec)
        with quiet_stderr():
            greys = [load_grey(p) for p in paths]
    tracker = Tracker(sk, [greys], CALIBRATED, TrackerSettings(**(settings or {})))
    result = track(tracker, first, list(range(len(greys))))
    scores = []
    for fr in result.frames:
        sil = silhouette(greys[fr.frame])
        turned = first.rotations.copy()
        turned[0] = fr.pose.rotations[0]  # the body's own turn, as tracked
        carried = BodyPose(turned, fr.pose.root_position, fr.pose.views)
        scores.append(_score(sk, fr, sil, carried, spec))
    return scores


def _score(sk: Skeleton, fr: FrameResult, sil: np.ndarray, carried: BodyPose,
           spec: dict) -> FrameScore:
    score = FrameScore(fr.frame + 1, overlap(sk, fr.pose, sil), overlap(sk, carried, sil),
                       fr.flagged, fr.diverged)
    clicked = spec.get("scored", {}).get(str(fr.frame + 1))
    if clicked:
        unit = 100.0 / body_length(spec)
        ours = np.array(click_distances(clicked, tips(sk, fr.pose))) * unit
        score.clicks, score.clicks_worst = float(ours.mean()), float(ours.max())
        score.clicks_carried = float(np.mean(click_distances(clicked, tips(sk, carried))) * unit)
    return score


def summary(runs: list[list[FrameScore]]) -> dict[str, list[float]]:
    """Per run (its frames' scores), beyond the first frame: frames tracked, the worst
    frame's overlap over the first's, and for clicked plates the clicked points' mean and
    worst frame and the first pose carried along's mean."""
    out = {"frames": [], "worst_overlap": [], "clicks": [], "clicks_worst": [],
           "clicks_carried": []}
    for scores in runs:
        later = scores[1:]
        out["frames"].append(len(scores))
        out["worst_overlap"].append(min(s.tracked for s in later) / scores[0].tracked)
        if not np.isnan(scores[0].clicks):
            out["clicks"].append(float(np.nanmean([s.clicks for s in later])))
            out["clicks_worst"].append(float(np.nanmax([s.clicks for s in later])))
            out["clicks_carried"].append(float(np.nanmean([s.clicks_carried for s in later])))
    return out


def _spread(values: list[float], digits: int = 1, unit: str = "") -> str:
    return (f"{np.mean(values):.{digits}f}{unit} ({min(values):.{digits}f}-"
            f"{max(values):.{digits}f})")


def report(name: str, scores: list[FrameScore], runs: list[list[FrameScore]]) -> list[str]:
    """Markdown for one plate: a summary line of the run from the clicks as clicked
    (``scores``) and of every run (``runs``: that one and those from nudged clicks), and
    per frame of the first the outline's overlap, the clicked points' distance and the
    limbs flagged, beside the first pose carried along."""
    later = scores[1:]
    clicked = not np.isnan(scores[0].clicks)
    first = {k: v[0] for k, v in summary([scores]).items() if v}
    lines = [f"**{name}** ({len(scores)} frames tracked): the outline's overlap with the "
             f"silhouette {scores[0].tracked:.2f} on the first frame, then worst "
             f"{min(s.tracked for s in later):.2f} ({first['worst_overlap']:.2f}x the "
             f"first's), mean {np.mean([s.tracked for s in later]):.2f}; the first pose "
             f"carried along: mean {np.mean([s.carried for s in later]):.2f}."]
    if clicked:
        lines[-1] += (f" Clicked snout and feet: mean {first['clicks']:.1f} % of the body's "
                      f"length, worst frame {first['clicks_worst']:.1f} %; the first pose "
                      f"carried along: {first['clicks_carried']:.1f} %.")
    m = summary(runs)
    lines[-1] += (f" Over {len(runs)} runs from the clicks as clicked and nudged by a pixel "
                  f"(mean, range): frames tracked {min(m['frames'])}-{max(m['frames'])}, the "
                  f"worst frame's overlap {_spread(m['worst_overlap'], 2)}x the first's")
    if clicked:
        lines[-1] += (f", clicked points {_spread(m['clicks'], unit=' %')}, their worst frame "
                      f"{_spread(m['clicks_worst'], unit=' %')}, the first pose carried along "
                      f"{_spread(m['clicks_carried'], unit=' %')}")
    lines[-1] += "."
    lines += ["", "| frame | overlap: tracked | first pose carried | clicked points: tracked "
              "(farthest) | first pose carried | limbs flagged |", "|---|---|---|---|---|---|"]
    for s in scores:
        points = (f"{s.clicks:.1f} % ({s.clicks_worst:.1f} %) | {s.clicks_carried:.1f} %"
                  if clicked else " | ")
        lines.append(f"| {s.frame} | {s.tracked:.2f} | {s.carried:.2f} | {points} |"
                     f" {', '.join(s.flagged)}{' (diverged)' if s.diverged else ''} |")
    return lines + [""]


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("names", nargs="*", help="plates (bench/data/plates/NAME.json); all if none")
    ap.add_argument("--write", type=Path, help="also write the results as markdown here")
    ap.add_argument("--settings", default="{}", help="tracker settings (JSON) for every run")
    a = ap.parse_args(argv)
    settings = json.loads(a.settings)
    names = a.names or sorted(p.stem for p in DATA.glob("*.json"))
    lines = [f"# Muybridge's plates\n\nWritten by `make bench-plates` (`bench/plates.py`) on "
             f"{date.today().isoformat()}. {HOW}"
             + (f" Tracker settings: `{a.settings}`." if settings else "") + "\n"]
    for name in names:
        runs = [run(name, draw, settings) for draw in range(DRAWS)]
        lines += report(name, runs[0], runs)
    text = "\n".join(lines)
    print(text)
    if a.write:
        a.write.write_text(text)
    return 0


HOW = ("Each plate is tracked with the default settings, side-on in its one view, from the "
       "planar quadruped standing on the joints clicked on its first frame "
       "(`bench/data/plates/`; the baboon's long tail is clicked and modelled too), through one "
       "still orthographic camera, as the examples in Blender are. The overlap is the "
       "intersection over union of the tracked blobs' outline with the animal's silhouette "
       "(the horse's rider and the other tails are not modelled, so even the first frame's "
       "is well under 1). The clicked points are the snout and the feet clicked "
       "by hand on every frame, a clicked pair of feet matched to the body's fore or hind pair "
       "the nearer way, in % of the body's length (rump to snout on the first frame); on the "
       "first frame they measure the clicking itself. 'First pose carried' is the first "
       "frame's pose moved along with the tracked body (its root as tracked). The "
       "horse's rider and the mule's buck are not modelled; a run stops where it "
       "diverges. The runs are chaotic: each plate is also tracked from its first frame's "
       "clicks nudged by up to a pixel (seven seeded draws), and the summary gives the mean "
       "and range over all eight runs; the table is the run from the clicks as clicked.")


if __name__ == "__main__":
    sys.exit(main())

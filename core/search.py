"""A coarse search of each limb against the silhouette, before Gauss-Newton refines the pose.

Brightness and the chamfer pulls both follow the nearest minimum; a shank that swings 45
degrees between two frames of 15 fps footage is past it. Here each tracked joint, parents
first, is turned over a grid of angles from the current pose and every turn is scored in
all views at once by the outline of the joint's own segment (its blobs that no tracked joint
below it moves) against the foreground: a covered background pixel costs 1, a foreground
pixel that the rest of the body leaves uncovered pays back ``UNCOVERED_GAIN`` (pixels the
rest covers count for nothing, so a limb in front of the trunk scores the same anywhere over
it and stays). A ball joint is turned in the two swings across its bone. A hinge below a
ball is turned about its axis and, with it, the ball's twist about its bone, which decides
the plane the hinge swings in and which no outline of the upper segment shows. The best
turn is refined on a finer grid and kept when it beats the current pose by ``margin`` times
the segment's outline area, and by that again for each ``TURN_SCALE`` degrees of turn
squared (a prior on how far a limb strays from its predicted motion: a forearm predicted
within a few degrees was turned 45-55 about its shoulder onto foreground the trunk's blob
leaves uncovered). Outlines are unions of projected ellipses
(``Camera.ellipses``), so the search needs no depth order. Grids in degrees; pixels on one
pyramid level.
"""

from __future__ import annotations

import itertools
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from . import se3
from .camera import Camera
from .confidence import Limbs
from .image import true_pixels
from .linearize import Kinematics
from .pose import BodyPose
from .raycast import BlobStack, blob_frames
from .silhouette import BACKDROP, FOREGROUND, UNSURE
from .skeleton import BALL, HINGE, Skeleton

SWING = (np.arange(-60, 61, 15), np.arange(-10, 11, 5))  # coarse grid, then around the best
HINGE_TURN = (np.arange(-90, 91, 10), np.arange(-6, 7, 3))
TWIST = (np.arange(-45, 46, 15), np.arange(-10, 11, 5))
# what a newly covered foreground pixel pays back: at the chamfer's 0.3, a foreground with
# holes (a body close to its backdrop's brightness) made hiding a limb behind the trunk pay
UNCOVERED_GAIN = 0.6
SIDE_ON = np.cos(np.radians(25))  # a hinge axis this close to one view's direction turns
MIN_FOREGROUND = 0.7  # share of the body's outline that must be foreground to search a view
TURN_SCALE = 45.0  # degrees: a turn this far on one dof must beat the prediction by 2 margins
# what covering a pixel costs, by its foreground map's code (``LimbSearch._gain_sums``)
_COVER_COST = np.zeros(3)
_COVER_COST[[FOREGROUND, BACKDROP]] = -UNCOVERED_GAIN, 1.0


@dataclass
class _Limb:
    joint: int
    own: np.ndarray  # blobs scored: the joint's own segment
    below: np.ndarray  # every blob the joint moves (left out of the rest of the body)
    dofs: list  # (joint, local axis, (coarse grid, fine grid)), parents first


def outlines(view: Camera, A: np.ndarray, C: np.ndarray):
    """Each ellipsoid's outline as row spans: centres c (..., 2), row range (..., 2) and the
    forms P (..., 2, 2) of ``Camera.ellipses``."""
    c, P = view.ellipses(A, C)
    det = P[..., 0, 0] * P[..., 1, 1] - P[..., 0, 1] * P[..., 1, 0]
    half = np.sqrt(np.stack([P[..., 1, 1], P[..., 0, 0]], -1) / det[..., None])
    return c, half, P


def _box(c: np.ndarray, half: np.ndarray, shape) -> tuple | None:
    """Pixels (x0, y0, x1, y1) of ``shape`` holding every outline given."""
    lo = np.floor((c - half).reshape(-1, 2).min(0)).astype(int)
    hi = np.ceil((c + half).reshape(-1, 2).max(0)).astype(int) + 1
    x0, y0 = max(lo[0], 0), max(lo[1], 0)
    x1, y1 = min(hi[0], shape[1]), min(hi[1], shape[0])
    return None if x0 >= x1 or y0 >= y1 else (x0, y0, x1, y1)


def _inside(box: tuple, outer: tuple) -> bool:
    return (box[0] >= outer[0] and box[1] >= outer[1] and box[2] <= outer[2]
            and box[3] <= outer[3])


def spans(c, half, P, box):
    """Per ellipse and box row: the first and one-past-last box column it covers (start ==
    stop where it covers none). Shapes (..., rows)."""
    x0, y0, x1, y1 = box
    dy = np.arange(y0, y1, dtype=float) - c[..., 1:]  # (..., rows)
    a, b = P[..., 0, 0, None], P[..., 0, 1, None] * dy
    disc = b * b - a * (P[..., 1, 1, None] * dy * dy - 1)
    root = np.sqrt(np.maximum(disc, 0))
    lo = np.ceil(c[..., :1] + (-b - root) / a) - x0
    hi = np.floor(c[..., :1] + (-b + root) / a) - x0 + 1
    lo, hi = np.clip(lo, 0, x1 - x0), np.clip(hi, 0, x1 - x0)
    hi = np.where(disc > 0, np.maximum(hi, lo), lo)
    return lo.astype(int), hi.astype(int)


def paint(mask: np.ndarray, view: Camera, A: np.ndarray, C: np.ndarray, box: tuple) -> None:
    """Set the pixels of ``mask`` (the box's size) that any ellipsoid's outline covers."""
    c, half, P = outlines(view, A, C)
    lo, hi = spans(c, half, P, box)
    e, rows = true_pixels(hi > lo)
    # +1 where a span starts, -1 one past its end: a pixel is covered where the running sum
    # along its row is positive
    width = mask.shape[1] + 1
    at, size = rows * width, mask.shape[0] * width
    edges = (np.bincount(at + lo[e, rows], minlength=size)
             - np.bincount(at + hi[e, rows], minlength=size)).reshape(-1, width)
    mask |= np.cumsum(edges[:, :-1], axis=1) > 0


def span_sums(lo: np.ndarray, hi: np.ndarray, S: np.ndarray) -> np.ndarray:
    """Per candidate (K, B blobs each, spans (K, B, rows) from ``spans``): the sum over its
    outline (the union of its blobs' ellipses) of the box image whose row prefix sums are S
    (rows, cols + 1). Overlaps of two ellipses are taken out once; a pixel under three of one
    candidate's is counted twice. Read from S's flat array: ``take`` beats 2-D indexing."""
    at, flat = np.arange(0, S.size, S.shape[1]), S.ravel()  # each row's start in flat
    total = np.sum(flat.take(hi + at) - flat.take(lo + at), axis=(1, 2))
    for i, k in itertools.combinations(range(lo.shape[1]), 2):
        a = np.maximum(lo[:, i], lo[:, k]) + at  # the overlap's span, empty where b <= a
        b = np.maximum(np.minimum(hi[:, i], hi[:, k]) + at, a)
        total -= np.sum(flat.take(b) - flat.take(a), axis=1)
    return total


def _area(lo: np.ndarray, hi: np.ndarray, shape) -> float:
    """Pixels in one candidate's outline (spans (1, B, rows) in a box whose prefix sums have
    ``shape``): the sum of a ramp's increments."""
    ramp = np.broadcast_to(np.arange(shape[1], dtype=float), shape)
    return float(span_sums(lo, hi, ramp)[0])


class LimbSearch:
    """Searches the limbs of ``skeleton`` against per-view foregrounds on one level."""

    def __init__(self, skeleton: Skeleton, margin: float, limbs: Limbs | None = None):
        """``limbs``: the skeleton's ``core.confidence.Limbs`` (made here if not given),
        whose blobs each limb's outline is scored by."""
        self.sk = skeleton
        self.margin = margin
        moved = skeleton.moved_by()  # [m, j]: j moves m
        self.blobs = BlobStack.of(skeleton.blobs)
        limbs = limbs or Limbs(skeleton, self.blobs)
        self.limbs: list[_Limb] = []
        for i, name in enumerate(limbs.names):
            j = skeleton.index(name)
            if j == 0:
                continue  # the root moves with the body's own pose, not as a limb
            own = limbs.of_blob == i
            below = moved[self.blobs.joint, j]
            frame = skeleton.bone_frame(j)
            if skeleton.kinds[j] == BALL:
                dofs = [(j, frame[1], SWING), (j, frame[2], SWING)]
            else:
                dofs = [(j, np.asarray(skeleton.axes[j], float), HINGE_TURN)]
                p = skeleton.parents[j]
                if skeleton.kinds[p] == BALL:
                    dofs.insert(0, (p, skeleton.bone_frame(p)[0], TWIST))
            self.limbs.append(_Limb(j, np.flatnonzero(own), np.flatnonzero(below), dofs))

    def run(self, pose: BodyPose, views: Sequence[Camera], fgs: Sequence[np.ndarray | None]
            ) -> tuple[BodyPose, list[str]]:
        """The pose with each limb turned to its best place, and the joints that turned.
        ``views`` and ``fgs`` (foreground maps, ``core.silhouette``'s; None for a view
        without one) share one level; a view where under ``MIN_FOREGROUND`` of the body's
        outline is foreground (of what is not unsure) is left out (``usable``), and the
        rest searched (``turn``)."""
        return self.turn(pose, views, self.usable(pose, views, fgs))

    def turn(self, pose: BodyPose, views: Sequence[Camera], fgs: Sequence[np.ndarray | None]
             ) -> tuple[BodyPose, list[str]]:
        """``run`` on the views ``usable`` kept (``fgs`` as it returned them). With one view
        left, only hinges whose axis points along that view turn (a limb seen side-on, an
        animal's): any other turn moves the limb in depth too, and one outline cannot tell a
        limb turned toward the camera from a shorter one."""
        pose = pose.copy()
        kin = Kinematics(self.sk, pose)
        A, C = blob_frames(self.blobs, kin.segments)
        n_views = sum(fg is not None for fg in fgs)
        turned = []
        for limb in self.limbs if n_views else ():
            if n_views == 1:
                view = next(v for v, fg in zip(views, fgs) if fg is not None)
                j, axis, _ = limb.dofs[-1]
                if (self.sk.kinds[j] != HINGE or abs(view.orientation[2] @ kin.frames[j, :3, :3]
                                                      @ axis) < SIDE_ON):
                    continue
                limb = _Limb(limb.joint, limb.own, limb.below, limb.dofs[-1:])
            rest = np.setdiff1d(np.arange(len(self.blobs)), limb.below)
            angles = self._best(limb, kin, A, C, rest, views, fgs)
            if angles is not None:
                for (j, axis, _), a in zip(limb.dofs, angles):
                    pose.rotations[j] = pose.rotations[j] @ se3.exp_so3(axis * np.radians(a))
                turned.append(self.sk.names[limb.joint])
                kin = Kinematics(self.sk, pose)  # the limbs below see it turned
                A, C = blob_frames(self.blobs, kin.segments)
        return pose, turned

    def usable(self, pose: BodyPose, views: Sequence[Camera],
               fgs: Sequence[np.ndarray | None]) -> list[np.ndarray | None]:
        """``fgs`` with None for each view the search leaves out at ``pose``: where under
        ``MIN_FOREGROUND`` of the body's outline is foreground."""
        A, C = blob_frames(self.blobs, Kinematics(self.sk, pose).segments)
        return [None if fg is None or self._foreground_share(view, fg, A, C) < MIN_FOREGROUND
                else fg for view, fg in zip(views, fgs)]

    @staticmethod
    def _foreground_share(view: Camera, fg: np.ndarray, A, C) -> float:
        """How much of the body's outline is foreground: low when the body's brightness is
        close to its backdrop's (then holes in a limb's outline would make hiding it pay) or
        when the body as a whole is far off."""
        body = np.zeros(fg.shape, bool)
        paint(body, view, A, C, (0, 0, fg.shape[1], fg.shape[0]))
        on = fg.ravel().take(np.flatnonzero(body))  # (2-D boolean masks read slowly)
        known = on[on != UNSURE]
        return float(np.mean(known == FOREGROUND)) if len(known) else 0.0

    @staticmethod
    def _gain_sums(view: Camera, fg: np.ndarray, A, C, box) -> np.ndarray:
        """Row prefix sums (rows, cols + 1) over ``box`` of what covering each pixel costs:
        nothing where the ellipsoids A, C (the rest of the body) cover it or the foreground
        map is unsure, else 1 on the background and -``UNCOVERED_GAIN`` on the foreground."""
        x0, y0, x1, y1 = box
        others = np.zeros((y1 - y0, x1 - x0), bool)
        paint(others, view, A, C, box)
        gain = _COVER_COST.take(fg[y0:y1, x0:x1])
        gain[others] = 0.0
        S = np.zeros((gain.shape[0], gain.shape[1] + 1))
        np.cumsum(gain, axis=1, out=S[:, 1:])
        return S

    def view_costs(self, limb: _Limb, poses: Sequence[BodyPose], views: Sequence[Camera],
                   fgs: Sequence[np.ndarray | None]) -> tuple[np.ndarray, np.ndarray]:
        """What the search scores ``limb`` by, per view: its own segment's outline at each
        of ``poses`` (P) against the rest of the body at the first, (P, V), and the outline's
        area (pixels) at the first, (V,); NaN for a view without a foreground map (None in
        ``fgs``) or where the outlines leave the image."""
        frames = [blob_frames(self.blobs, Kinematics(self.sk, p).segments) for p in poses]
        A, C = frames[0]
        rest = np.setdiff1d(np.arange(len(self.blobs)), limb.below)
        Ak = np.stack([Ap[limb.own] for Ap, _ in frames])
        Ck = np.stack([Cp[limb.own] for _, Cp in frames])
        cost = np.full((len(poses), len(views)), np.nan)
        area = np.full(len(views), np.nan)
        for v, (view, fg) in enumerate(zip(views, fgs)):
            scored = None if fg is None else self._view_cost(view, fg, Ak, Ck, A, C, rest)
            if scored is not None:
                cost[:, v], area[v], _ = scored
        return cost, area

    def _view_cost(self, view: Camera, fg: np.ndarray, Ak, Ck, A, C, rest, kept=None,
                   with_area: bool = True) -> tuple | None:
        """Outlines Ak, Ck (K candidates of B blobs each) scored in one view: per candidate
        the cost of covering ``fg``'s pixels where the blobs ``rest`` of A, C (every blob's
        ``blob_frames``) do not, the first candidate's area (None unless ``with_area``),
        and the box with its gains' row prefix sums (``_gain_sums``). ``kept``: such a box
        and sums from an earlier call, reused where the outlines fit in it. None where they
        leave the image."""
        c, half, P = outlines(view, Ak, Ck)
        box = _box(c, half, fg.shape)
        if box is None:
            return None
        if kept is None or not _inside(box, kept[0]):
            kept = box, self._gain_sums(view, fg, A[rest], C[rest], box)
        box, S = kept
        lo, hi = spans(c, half, P, box)
        area = _area(lo[:1], hi[:1], S.shape) if with_area else None
        return span_sums(lo, hi, S), area, kept

    def _allowed(self, limb: _Limb, pose: BodyPose, cands: np.ndarray) -> np.ndarray:
        """Which candidates keep every limited hinge within its range (or no farther out of
        it than it is); the current pose, all zeros, always."""
        ok = np.ones(len(cands), bool)
        for i, (j, _, _) in enumerate(limb.dofs):
            if self.sk.kinds[j] == HINGE:
                lo, hi = np.degrees(self.sk.hinge_turns(j, pose.rotations[j]))
                ok &= (cands[:, i] >= lo) & (cands[:, i] <= hi)
        return ok

    def _best(self, limb: _Limb, kin: Kinematics, A, C, rest, views, fgs
              ) -> np.ndarray | None:
        """The limb's best angles (degrees, one per dof) if they beat the current pose; A, C
        are every blob's (``blob_frames``), ``rest`` the blobs that stay."""
        pivot = kin.frames[limb.joint, :3, 3]
        best = np.zeros(len(limb.dofs))
        sums = {}  # per view: a box and its gains' row prefix sums, kept while they hold
        for stage in (0, 1):
            grids = [best[i] + g[stage] for i, (_, _, g) in enumerate(limb.dofs)]
            cands = np.array(list(itertools.product(*grids)))
            if stage == 0:
                cands = np.vstack([np.zeros(len(limb.dofs)), cands])  # the current pose first
            cands = cands[self._allowed(limb, kin.pose, cands)]
            Rw = np.broadcast_to(np.eye(3), (len(cands), 3, 3))
            for i, (j, axis, _) in enumerate(limb.dofs):  # parents first: a world rotation each
                angles, which = np.unique(cands[:, i], return_inverse=True)  # a grid's few
                turns = se3.exp_so3(np.radians(angles[:, None]) * (kin.frames[j, :3, :3] @ axis))
                Rw = Rw @ turns[which]
            Ck = np.einsum("kab,eb->kea", Rw, C[limb.own] - pivot) + pivot
            Ak = np.einsum("eab,kcb->keac", A[limb.own], Rw)
            cost = np.zeros(len(cands))
            if stage == 0:
                area = 0.0
            for v, (view, fg) in enumerate(zip(views, fgs)):
                scored = None if fg is None else self._view_cost(
                    view, fg, Ak, Ck, A, C, rest, sums.get(v), with_area=stage == 0)
                if scored is None:
                    continue
                view_cost, view_area, sums[v] = scored
                cost += view_cost
                if stage == 0:
                    area += view_area
            if stage == 0:
                current = cost[0]
            cost += self.margin * area * np.sum((cands / TURN_SCALE) ** 2, axis=1)
            best = cands[int(np.argmin(cost))]
        if np.min(cost) < current - self.margin * area and np.any(best):
            return best
        return None

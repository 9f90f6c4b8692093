"""How far to trust each limb of a tracked frame: what each view's pixels and silhouette say.

A limb is a tracked joint with the blobs it moves that no tracked joint below it moves (an
upper arm without the forearm). On a tracked frame, in each view, the limb's body pixels of
the earlier frames, mapped into the new frame, either follow it in brightness (their EM
support posterior near 1) or do not; and where the view has a still backdrop, the limb's
bone (points along its blobs' long axes, so that a blob fatter than the limb costs
nothing) lies on the body's silhouette or off it. A view *sees* the limb when at least
``MIN_LIMB_POINTS`` of its pixels are visible there; its agreement is the mean support of
those pixels (scaled so that a perfect match reads 1) times the share of the bone on the
silhouette. The limb's confidence is its worst seeing view's agreement: every view that
sees a limb must bear it out, as every view's evidence is needed to move it. A limb no view
sees has confidence 0 and is ``unseen`` (its pose is the prediction, held); the tracker
doubts one whose confidence falls under ``DOUBT`` (``unsure``), and goes on doubting it,
frame after frame, until its confidence is back over ``CLEAR``: a limb lost over another
body part reads as agreeing there (its bone is on the silhouette, its pixels follow what it
covers), so one frame's fair agreement does not show that a limb in doubt is found again. A
limb over another body part in every view from the start reads as agreeing: nothing tells.

The flags the report and the add-on show read a limb's own bone: a forearm's or a shank's
agreement leaves out the hand or the foot that hangs from it (``Limbs.own_blob``), which
turns at a wrist or an ankle the tracker holds, so that its misfit says nothing of the
limb's direction. The tracker's own doubt, which holds a limb and lets go of its pixels,
reads everything the limb moves: a foot's disagreeing pixels are no template either. Each
flag reads its own state on the frame before.

With one view no second view can disagree, and a limb turned toward or away from the
camera, which one view shows only as foreshortening, reads as agreeing wherever its outline
lands. What the view does show is the limb's own pixels where the track left them:
foreground that no blob explains, beside the limb (``Limbs.unexplained``: within
``UNEXPLAINED_REACH`` of its length from its joint, past ``UNEXPLAINED_GAP`` of the blobs'
outline, in units of the limb's own outline's area). So with one view the flag reads, at
the tracker's own bars, the own bone's confidence divided by one plus
``UNEXPLAINED_WEIGHT`` times that (``LimbCheck.flag_confidence``); a view with no backdrop
(a camera that moves, the silhouette off) cannot tell it, and its flag reads the own bone's
confidence under the higher bars of ``ONE_VIEW_FLAG``, which the flags had before. Hands,
feet and hair that have no blob add a little near the forearms, shanks and neck on every
frame alike. The tracker's own doubt reads the plain confidence there too: it holds a
doubted limb where it was, which costs more than a look.
"""

from __future__ import annotations

from collections.abc import Collection, Mapping, Sequence
from dataclasses import dataclass

import cv2
import numpy as np

from .camera import Camera
from .linearize import Kinematics
from .raycast import BlobStack
from .skeleton import BALL, HINGE, Skeleton

MIN_LIMB_POINTS = 10  # a view sees a limb when this many of its pixels are visible there
DOUBT = 0.35  # the tracker doubts a limb below this confidence
CLEAR = 0.9  # a limb doubted on the frame before stays in doubt up to this one
AXIS_POINTS = 9  # points along each blob's long axis whose silhouette is read
AXIS_REACH = 0.8  # of the blob's long radius, either side of its centre
UNEXPLAINED_REACH = 1.2  # limb lengths from its joint: where a view's unexplained foreground
# counts against the limb
UNEXPLAINED_GAP = 2.5  # map cells: foreground this near the blobs' outline is its own slack
UNEXPLAINED_WEIGHT = 0.85  # with one view, the flag's discount per limb area unexplained
ONE_VIEW_FLAG = (0.55, 0.99)  # one view's flag's bars where no backdrop shows what is unexplained
UNSEEN, UNSURE_FLAG = "unseen", "unsure"


@dataclass(frozen=True)
class LimbCheck:
    """One limb on one frame: its confidence in [0, 1], per view its agreement in [0, 1]
    (None where the view does not see it), whether the tracker doubted it on the frame
    before (``doubted``) and the report flagged it there (``was_flagged``; None: the same),
    with one view the foreground no blob explains near it (``Limbs.unexplained``; None
    where the view has no backdrop to tell it, and with more views), and per view the
    agreement of the limb's own bone (``own_views``: ``Limbs.view_agreement``'s ``own``;
    None: as ``views``)."""

    confidence: float
    views: tuple[float | None, ...]
    doubted: bool = False
    was_flagged: bool | None = None
    unexplained: float | None = None
    own_views: tuple[float | None, ...] | None = None

    @property
    def flag_views(self) -> tuple[float | None, ...]:
        """Per view, the agreement the flags read: ``own_views`` where a view sees the limb's
        own bone, else ``views`` (no view sees that bone alone, or it was not read)."""
        own = self.own_views
        return own if own and any(v is not None for v in own) else self.views

    @property
    def own_confidence(self) -> float:
        """The confidence the flags read: the worst of ``flag_views`` among the views that
        see the limb (the confidence itself where none does)."""
        seen = [v for v in self.flag_views if v is not None]
        return min(seen) if seen else self.confidence

    @property
    def doubt(self) -> str:
        """The tracker's word: '' when it trusts the limb, else ``unseen`` or ``unsure``."""
        return self._reading(self.doubted, self.confidence)

    @property
    def flag(self) -> str:
        """What the report and the add-on show: '' when the limb can be trusted, else
        ``unseen`` or ``unsure``: ``own_confidence`` at the tracker's bars, but with one view
        ``flag_confidence``, or without a backdrop ``own_confidence`` at ``ONE_VIEW_FLAG``."""
        before = self.doubted if self.was_flagged is None else self.was_flagged
        if len(self.views) > 1:
            return self._reading(before, self.own_confidence)
        if self.unexplained is None:
            return self._reading(before, self.own_confidence, *ONE_VIEW_FLAG)
        return self._reading(before, self.flag_confidence)

    @property
    def flag_confidence(self) -> float:
        """The confidence the one-view flag reads: ``own_confidence`` divided by one plus
        ``UNEXPLAINED_WEIGHT`` times the foreground no blob explains near the limb, in units
        of its own outline's area (``own_confidence`` itself where that is not known)."""
        return discounted(self.own_confidence, self.unexplained)

    def _reading(self, before: bool, confidence: float, enter: float = DOUBT,
                 leave: float = CLEAR) -> str:
        return reading(confidence, any(v is not None for v in self.views), before, enter,
                       leave)


def discounted(confidence: float, unexplained: float | None, weight: float | None = None
               ) -> float:
    """``confidence`` over one plus ``weight`` (None: ``UNEXPLAINED_WEIGHT``) times the
    unexplained foreground (None: not known, so the confidence itself)."""
    weight = UNEXPLAINED_WEIGHT if weight is None else weight
    return confidence / (1.0 + weight * (unexplained or 0.0))


def reading(confidence: float, seen: bool, before: bool, enter: float, leave: float) -> str:
    """A limb's word at bars ``enter`` and ``leave``: ``unseen`` where no view ``seen`` it,
    else ``unsure`` under ``enter``, or under ``leave`` where it was flagged ``before``."""
    if not seen:
        return UNSEEN
    return UNSURE_FLAG if confidence < (leave if before else enter) else ""


def frame_list(frames) -> str:
    """Frame numbers as short text, runs joined: ``3, 5-9, 12``."""
    frames = sorted(frames)
    runs = []
    for f in frames:
        if runs and f == runs[-1][1] + 1:
            runs[-1][1] = f
        else:
            runs.append([f, f])
    return ", ".join(str(a) if a == b else f"{a}-{b}" for a, b in runs)


def begun_list(begun: Mapping[int, Mapping[str, str]]) -> str:
    """Frames and the limbs whose doubt begins there as short text, in frame order:
    ``3 LeftElbow, LeftKnee; 9 Neck``."""
    return "; ".join(f"{f} {', '.join(begun[f])}" for f in sorted(begun))


class Limbs:
    """The limbs of a skeleton and which limb each blob belongs to."""

    def __init__(self, skeleton: Skeleton, blobs: BlobStack):
        blob_joint = blobs.joint
        moved = skeleton.moved_by()
        tracked = [j for j in range(skeleton.n_joints) if skeleton.kinds[j] in (BALL, HINGE)]
        depth = np.array([len(skeleton.ancestors(j)) for j in range(skeleton.n_joints)])
        # per blob, the deepest tracked joint that moves it (-1: only the root does)
        owner = np.full(len(blob_joint), -1)
        for b, m in enumerate(blob_joint):
            above = [j for j in tracked if moved[m, j]]
            if above:
                owner[b] = max(above, key=lambda j: depth[j])
        joints = sorted(set(owner[owner >= 0].tolist()))
        self.names = [skeleton.names[j] for j in joints]
        self.joint = np.array(joints, dtype=int)
        self.joint_ref = skeleton.rest_positions[self.joint].reshape(-1, 3)
        index = {j: i for i, j in enumerate(joints)}
        self.of_blob = np.array([index.get(int(j), -1) for j in owner], dtype=int)
        # the same without the segments that hang from a hinge's own (a hand, a foot), which
        # turn at joints the tracker holds: what the flags read (``LimbCheck.own_confidence``)
        below_hinge = np.array([o >= 0 and skeleton.kinds[o] == HINGE and m != o
                                for m, o in zip(blob_joint, owner)], dtype=bool)
        self.own_blob = np.where(below_hinge, -1, self.of_blob)
        # points along each limb blob's longest axis, in its segment's frame: where the
        # bone runs whatever the blob's girth
        t = np.linspace(-AXIS_REACH, AXIS_REACH, AXIS_POINTS)
        mine = np.flatnonzero(self.of_blob >= 0)
        longest = blobs.radii[mine].argmax(axis=1)
        axis = blobs.Q[mine, :, longest] * blobs.radii[mine, longest, None]
        self.axis_joint = np.repeat(blob_joint[mine], len(t))
        self.axis_ref = (blobs.centre[mine, None] + axis[:, None] * t[:, None]).reshape(-1, 3)
        self.axis_limb = np.repeat(self.of_blob[mine], len(t))
        self.axis_own = np.repeat(self.own_blob[mine], len(t))
        # each point's blob's thickness: twice the mean of its two shorter radii, world units
        self.axis_thickness = np.repeat(2 * np.sort(blobs.radii[mine], axis=1)[:, :2].mean(1),
                                        len(t))

    def __len__(self) -> int:
        return len(self.names)

    def view_agreement(self, point_blob: np.ndarray, support: np.ndarray,
                       axis_on: np.ndarray | None = None, own: bool = False) -> np.ndarray:
        """One view's agreement per limb (L,), NaN where the view does not see the limb.
        ``point_blob`` (N,): each mapped pixel's blob; ``support`` (N,): its support in
        [0, 1], NaN where it is hidden or off the image. ``axis_on``: per point of
        ``axis_ref`` at the frame's pose, 1 where the view's foreground holds it, 0 where
        not, NaN off the image; None without a still backdrop. ``own``: read on each limb's
        own bone alone (``own_blob``), not the hand or foot hanging from a hinge's."""
        L = len(self)
        limb = (self.own_blob if own else self.of_blob)[point_blob]
        use = (limb >= 0) & ~np.isnan(support)
        count = np.bincount(limb[use], minlength=L)
        total = np.bincount(limb[use], weights=support[use], minlength=L)
        agree = np.where(count >= MIN_LIMB_POINTS, total / np.maximum(count, 1), np.nan)
        if axis_on is not None:
            axis_limb = self.axis_own if own else self.axis_limb
            use = ~np.isnan(axis_on) & (axis_limb >= 0)
            area = np.bincount(axis_limb[use], minlength=L)
            hit = np.bincount(axis_limb[use], weights=axis_on[use], minlength=L)
            agree *= np.where(area > 0, hit / np.maximum(area, 1), 1.0)
        return agree

    def unexplained(self, kin: Kinematics, view: Camera, grid: int, foreground: np.ndarray,
                    at: tuple[int, int], labels: np.ndarray, areas: np.ndarray) -> np.ndarray:
        """(L,): per limb, one view's foreground that no blob explains near it, in units of
        the limb's own outline's area: the cells of ``foreground`` (a window of the view's
        foreground map on every ``grid``-th pixel of the level ``view`` projects to, True
        where foreground, its top-left cell ``at``) that no blob covers (``labels``, -1 on
        the same cells) nor lies within ``UNEXPLAINED_GAP`` cells of, and within
        ``UNEXPLAINED_REACH`` times the limb's length (its joint to the far end of its bone)
        of its joint, at the pose ``kin``. ``areas``: each blob's whole outline's area in
        square level pixels (``raycast.outline_areas``). A limb tracked off its place in
        the image leaves its own pixels there, beside it."""
        covered = labels >= 0
        out = np.zeros(len(self))
        if not covered.any():
            return out
        gap = cv2.distanceTransform((~covered).astype(np.uint8), cv2.DIST_L2,
                                    cv2.DIST_MASK_PRECISE)
        ys, xs = np.nonzero(foreground & (gap > UNEXPLAINED_GAP))
        if not len(ys):
            return out
        cells = np.stack([xs, ys], 1) + np.asarray(at)
        joint = view.project(kin.world_points(self.joint, self.joint_ref)) / grid
        axis = view.project(kin.world_points(self.axis_joint, self.axis_ref)) / grid
        length = np.zeros(len(self))
        np.maximum.at(length, self.axis_limb,
                      np.linalg.norm(axis - joint[self.axis_limb], axis=1))
        near = np.sum((cells[None] - joint[:, None]) ** 2, -1) <= (
            UNEXPLAINED_REACH * length[:, None]) ** 2
        mine = self.of_blob >= 0
        own = np.bincount(self.of_blob[mine], weights=areas[mine], minlength=len(self))
        return np.where(own > 0, near.sum(1) * grid**2 / np.maximum(own, 1e-12), 0.0)

    def bone_off_body(self, kin: Kinematics, views: Sequence[Camera],
                      to_body: Sequence[np.ndarray | None]) -> np.ndarray:
        """(L, V): per limb and view, the share of the limb's bone points at the pose ``kin``
        that lie farther from any pixel that may be the body than their blob is thick: where
        the limb cannot be, whatever holes the body's silhouette has. ``to_body``: per view,
        its ``silhouette.distance_to_body`` map on the level of ``views``, or None. NaN
        where a view has no map or shows none of the limb's bone."""
        axis = kin.world_points(self.axis_joint, self.axis_ref)
        out = np.full((len(self), len(views)), np.nan)
        for c, (view, far) in enumerate(zip(views, to_body)):
            if far is None:
                continue
            px = np.rint(view.project(axis)).astype(int)
            inside = ((px >= 0) & (px < (far.shape[1], far.shape[0]))).all(axis=1)
            if not inside.any():
                continue
            thick = self.axis_thickness[inside] * view.scale_at(axis[inside].mean(axis=0))
            off = far[px[inside, 1], px[inside, 0]] > thick
            area = np.bincount(self.axis_limb[inside], minlength=len(self))
            hit = np.bincount(self.axis_limb[inside], weights=off, minlength=len(self))
            out[:, c] = np.where(area > 0, hit / np.maximum(area, 1), np.nan)
        return out

    def checks(self, per_view: Sequence[np.ndarray], doubted: Collection[str] = (),
               flagged: Collection[str] | None = None, unexplained: np.ndarray | None = None,
               own_views: Sequence[np.ndarray] | None = None) -> dict[str, LimbCheck]:
        """Each limb's check from its agreement in every view (``view_agreement``'s);
        ``doubted`` and ``flagged``: the limbs the tracker doubted and the report flagged
        on the frame before (None: those doubted); ``unexplained``: one view's
        ``unexplained`` (None: not known); ``own_views``: every view's agreement of the
        limbs' own bones (``view_agreement``'s ``own``; None: not read)."""
        def at(agreements, i):
            return tuple(None if np.isnan(a[i]) else float(np.clip(a[i], 0, 1))
                         for a in agreements)

        out = {}
        for i, name in enumerate(self.names):
            views = at(per_view, i)
            seen = [v for v in views if v is not None]
            out[name] = LimbCheck(min(seen) if seen else 0.0, views, name in doubted,
                                  None if flagged is None else name in flagged,
                                  None if unexplained is None else float(unexplained[i]),
                                  None if own_views is None else at(own_views, i))
        return out

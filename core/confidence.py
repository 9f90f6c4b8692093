"""How far to trust each limb of a tracked frame: what each view's pixels and outline say.

A limb is a tracked joint with the blobs it moves that no tracked joint below it moves (an
upper arm without the forearm). On a tracked frame, in each view, the limb's body pixels of
the earlier frames, mapped into the new frame, either follow it in brightness (their EM
support posterior near 1) or do not; and where the view has a still backdrop, the limb's
outline (its blobs' pixels that are front-most) lies on the body's silhouette or on the
backdrop. A view *sees* the limb when at least ``MIN_LIMB_POINTS`` of its pixels are
visible there; its agreement is the mean support of those pixels (scaled so that a perfect
match reads 1) times the share of the outline on the silhouette. The limb's confidence is
its worst seeing view's agreement: every view that sees a limb must bear it out, as every
view's evidence is needed to move it. A limb no view sees has confidence 0 and is flagged
``unseen`` (its pose is the prediction, held); one whose confidence is under ``UNSURE`` is
flagged ``unsure``: fewer than half of what it shows agrees with the footage.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .skeleton import BALL, HINGE, Skeleton

MIN_LIMB_POINTS = 10  # a view sees a limb when this many of its pixels are visible there
UNSURE = 0.5  # a limb is flagged below this confidence
UNSEEN, UNSURE_FLAG = "unseen", "unsure"


@dataclass(frozen=True)
class LimbCheck:
    """One limb on one frame: its confidence in [0, 1], and per view its agreement in [0, 1]
    (None where the view does not see it)."""

    confidence: float
    views: tuple[float | None, ...]

    @property
    def flag(self) -> str:
        """'' when the limb can be trusted, else ``unseen`` or ``unsure``."""
        if all(v is None for v in self.views):
            return UNSEEN
        return UNSURE_FLAG if self.confidence < UNSURE else ""


class Limbs:
    """The limbs of a skeleton and which limb each blob belongs to."""

    def __init__(self, skeleton: Skeleton, blob_joint: np.ndarray):
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
        index = {j: i for i, j in enumerate(joints)}
        self.of_blob = np.array([index.get(int(j), -1) for j in owner], dtype=int)

    def __len__(self) -> int:
        return len(self.names)

    def view_agreement(self, point_blob: np.ndarray, support: np.ndarray,
                       labels: np.ndarray | None = None, fg: np.ndarray | None = None
                       ) -> np.ndarray:
        """One view's agreement per limb (L,), NaN where the view does not see the limb.
        ``point_blob`` (N,): each mapped pixel's blob; ``support`` (N,): its support in
        [0, 1], NaN where it is hidden or off the image. ``labels``: the view's label map
        at the frame's pose (front-most blob, -1 where none) and ``fg`` the foreground on
        the same pixels (boolean), or None without a still backdrop."""
        L = len(self)
        limb = self.of_blob[point_blob]
        use = (limb >= 0) & ~np.isnan(support)
        count = np.bincount(limb[use], minlength=L)
        total = np.bincount(limb[use], weights=support[use], minlength=L)
        agree = np.where(count >= MIN_LIMB_POINTS, total / np.maximum(count, 1), np.nan)
        if labels is not None and fg is not None:
            covered = labels >= 0
            lab = self.of_blob[labels[covered]]
            on = lab >= 0
            area = np.bincount(lab[on], minlength=L)
            hit = np.bincount(lab[on], weights=fg[covered][on], minlength=L)
            agree *= np.where(area > 0, hit / np.maximum(area, 1), 1.0)
        return agree

    def checks(self, per_view: Sequence[np.ndarray]) -> dict[str, LimbCheck]:
        """Each limb's check from its agreement in every view (``view_agreement``'s)."""
        out = {}
        for i, name in enumerate(self.names):
            views = tuple(None if np.isnan(a[i]) else float(np.clip(a[i], 0, 1))
                          for a in per_view)
            seen = [v for v in views if v is not None]
            out[name] = LimbCheck(min(seen) if seen else 0.0, views)
        return out

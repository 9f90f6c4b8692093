"""One frame's fit: Gauss-Newton coarse to fine against the new frame's images.

The pose predicted for a new frame is refined on an image pyramid from the coarsest level
to the finest. Each iteration maps the body's pixels of two earlier frames -- the previous
frame and the key frame (the first, user-posed one, or the last the user corrected; it
holds the track against drift) -- to the new frame under the current estimate, samples the
new image there, and solves one linear system for all views (paper section 2.5), as a
Levenberg-Marquardt step that is kept only if it lowers the robust cost on the pixels
visible before and after it, and shortened so that no joint turns more than a few degrees
at once. A joint is solved only on levels where its blob is thick enough to see. Pixels
whose front-most blob in the new frame is not the blob they came from are left out (a leg
passing behind the other); pixel weights are the blob's rim weight times the EM support
posterior. With still cameras, the blobs' outline is also held against the body's
silhouette (``silhouette``): chamfer pulls in both directions whose reach is a limb's
length, not a blob's width, so that a fast limb is caught and a lost one found again; and
before refining, each limb is searched over a grid of turns against the silhouette
(``core.search``), a turn kept where every view's pixels bear it out (the earlier frame's,
or in two views or more the key frame's), or where two or more views' backdrops show that
the limb cannot be where it is and can be where it turned. The finished frame's limbs are
checked against every view (``core.confidence``); a limb in doubt there leaves out, on the
next frame, its pixels that the backdrop showed to be backdrop (``release_lost_limbs``).
Sizes in pixels are meant for a body about ``REFERENCE_BODY_PIXELS`` tall; where a view
shows it several times that, that view's pyramid gets finer levels on top, sampled as
sparsely, and each tracker level reads every view where the body is about as large
(``auto_scale``, ``core.scales``).
"""

from __future__ import annotations

import time
from collections.abc import Collection, Sequence
from dataclasses import dataclass, field

import numpy as np

from . import image as imagelib
from . import raycast
from . import silhouette as sil
from .confidence import MIN_LIMB_POINTS, LimbCheck, Limbs
from .errors import InputError
from .linearize import Kinematics, rows
from .pose import (
    CALIBRATED,
    INDEPENDENT,
    ROOT_PARAMS,
    ROOT_TURN,
    BodyPose,
    apply_update,
    n_root_params,
)
from .scales import Scales
from .search import LimbSearch
from .sequence import ImageSequence
from .settings import TrackerSettings
from .side_on import BODY, TURNED, out_of_side_on
from .skeleton import Skeleton
from .solver import (
    NormalEquations,
    channel_rows,
    mixture_cost,
    point_noise,
    robust_scale,
    solve,
    support_posterior,
    support_weights,
)

SIL_MAX_ROWS = 300  # silhouette mismatches per view that enter the normal equations
EXPOSURE_NOTE = "exposure: "  # how the run's note on the exposures it followed begins
# level pixels from any pixel that may be the body past which a lost limb's pixel of the
# frame before is taken for backdrop (``release_lost_limbs``)
LOST_REACH = 1.5
# views whose outlines, all bearing a limb's turn out, keep it without its pixels' word
# (``_outlines_bear_out``): two views' silhouettes fitted a wrong turn on a busy or noisy
# backdrop, or in hard sunlight, about as often as the right one on a plain backdrop, unless
# both also showed the limb off the body where it was
OUTLINE_VIEWS = 3


@dataclass(kw_only=True)
class FrameResult:
    """One tracked frame: its pose and the facts the UI, the report and the benchmark read."""

    frame: int
    pose: BodyPose
    residual: float  # support-weighted RMS brightness error on the finest level, image units
    iterations: int
    converged: bool
    diverged: bool = False
    reason: str = ""
    seconds: float = 0.0
    given: bool = False  # the user's pose (the initial one or a correction), not tracked
    limbs: dict[str, LimbCheck] = field(default_factory=dict)  # tracked frames: each limb's
    turned: float | None = None  # side-on: degrees the body turned in depth since the key
    # joints the limb search turned on this frame on two or more views' evidence: their step
    # from the frame before is mostly the error the turn took out, not motion
    searched: list[str] = field(default_factory=list)

    @property
    def flagged(self) -> dict[str, str]:
        """What to check on this frame and why: the limbs (``LimbCheck.flag``), and, tracked
        side-on, the body (``side_on.BODY``) where it turned more than
        ``side_on.OUT_OF_SIDE_ON_DEG`` toward or away from the camera (one view shows that only by
        foreshortening, and the limbs' hinges then no longer turn in the image plane)."""
        out = {name: c.flag for name, c in self.limbs.items() if c.flag}
        if out_of_side_on(self.turned):
            out[BODY] = TURNED
        return out

    @property
    def doubts(self) -> dict[str, str]:
        """The limbs the tracker doubts on this frame and why (``LimbCheck.doubt``)."""
        return {name: c.doubt for name, c in self.limbs.items() if c.doubt}


@dataclass
class PointSet:
    """Body pixels of earlier frames in one view, ready to be mapped to the new frame: one
    frame's, or several frames' one after the other (``lengths``: how many each; each has
    its own noise scale)."""

    view: int
    seg_joint: np.ndarray  # (N,) joint whose segment holds the point
    blob: np.ndarray  # (N,) blob index, for the visibility test
    ref: np.ndarray  # (N, 3) reference-frame point
    value: np.ndarray  # (N, C) each channel's value in that frame (C = 1: brightness alone)
    weight: np.ndarray  # (N,) rim weight times the set's weight
    slope: np.ndarray  # (N, C) each channel's squared gradient there, per level pixel squared
    lengths: tuple[int, ...] = ()  # points per frame, when several frames are joined

    def key_points(self) -> np.ndarray:
        """(N,) which points are the key frame's: those after the first frame's when the
        previous frame's and the key frame's points are joined (none otherwise)."""
        out = np.zeros(len(self.value), bool)
        if len(self.lengths) > 1:
            out[self.lengths[0]:] = True
        return out

    @staticmethod
    def joined(sets: list[PointSet]) -> PointSet:
        """One set of the points of ``sets`` (all of one view), in order."""
        if len(sets) == 1:
            return sets[0]
        return PointSet(sets[0].view, *(np.concatenate([getattr(ps, f) for ps in sets])
                                        for f in ("seg_joint", "blob", "ref", "value",
                                                  "weight", "slope")),
                        tuple(len(ps.value) for ps in sets))


def _views_seeing(sets: list[PointSet], n_joints: int) -> np.ndarray:
    """How many views' point sets hold points of each joint's segment, (n_joints,)."""
    seen = np.zeros((max((ps.view for ps in sets), default=-1) + 1, n_joints), dtype=bool)
    for ps in sets:
        seen[ps.view] |= np.bincount(ps.seg_joint, minlength=n_joints) > 0
    return seen.sum(0)


@dataclass
class _Samples:
    """One pose's look at the point sets on one level."""

    costs: np.ndarray  # (all points,) robust cost, NaN where hidden or off the image
    parts: list  # per set: (indices of usable points, world points, image gradients, residuals,
    # their noise scales: ``solver.point_noise``)
    inside: np.ndarray  # (views,) fraction of each view's points inside its image
    sigmas: list  # per set, its points' noise scales (N,)
    shape_cost: float = 0.0  # the silhouette term's cost
    shape_parts: list = field(default_factory=list)  # per view: its _ShapePull, or None


@dataclass
class _ShapePull:
    """One view's silhouette mismatch at a sampled pose, its rows made when asked for (a
    pose that is only costed needs none): ``mm`` on the crop of the label map ``grid``
    whose top-left map pixel is ``at``, ``full`` full-resolution pixels per map pixel."""

    mm: sil.Mismatch
    grid: raycast.LabelGrid
    at: tuple[int, int]
    full: int

    def rows(self, every: int) -> tuple[np.ndarray, ...]:
        """Every ``every``-th pair's blob (N,), the world point under its covered pixel
        (N, 3), its target in full-resolution pixels (N, 2) and its weight (N,)."""
        model = self.mm.model[::every] + self.at
        target = (self.mm.target[::every] + self.at) * self.full
        hits = self.grid.hits_on_full(model[:, 1].astype(int), model[:, 0].astype(int))
        return hits.label, hits.world, target, self.mm.weight[::every]



def _with_turns(est: BodyPose, searched: BodyPose, limbs) -> BodyPose:
    """``est`` with the degrees of freedom of the search's ``limbs`` as ``searched`` has them."""
    out = est.copy()
    for limb in limbs:
        for j, _, _ in limb.dofs:
            out.rotations[j] = searched.rotations[j]
    return out


def _clearly_lower(new: np.ndarray, old: np.ndarray) -> bool:
    """Whether paired costs ``new`` are clearly lower than ``old``: the mean of their
    differences over twice its standard error."""
    d = old - new
    return bool(d.mean() > 2 * d.std() / np.sqrt(len(d)))


class FrameFit:
    """Fits a body (a skeleton with blobs) to one new frame at a time in the footage of one
    or more views, holding what the frames share: the key frame's pixels, the silhouette's
    backdrops, the pyramids' scale for the body's size."""

    def __init__(
        self,
        skeleton: Skeleton,
        images: Sequence[Sequence],
        mode: str = INDEPENDENT,
        settings: TrackerSettings | None = None,
        moving: Sequence[Sequence | None] | None = None,
        clean_plates: Sequence | None = None,
    ):
        """``moving``: per view, its camera on every frame where the camera moves, else None
        (the backdrop moves with it: ``SilhouetteCue``). ``clean_plates``: per view, an image
        (path or array) of its scene without the body, the backdrop of its silhouette, or
        None."""
        if mode not in (CALIBRATED, INDEPENDENT):
            raise InputError(f"mode must be '{CALIBRATED}' or '{INDEPENDENT}', not '{mode}'")
        if not skeleton.blobs:
            raise InputError("the skeleton has no blobs: give its segments ellipsoids")
        self.mode = mode
        self.settings = settings or TrackerSettings()
        self.seq = ImageSequence(images, self.settings.levels, self.settings.highpass,
                                 self.settings.colour)
        # each view's pixel sizes for the body's size there (``scale_to``), as seq is built
        self.scales = Scales.unscaled(self.seq.n_views, self.settings)
        # the key frame's points by (frame, view, level), kept while the key frame is
        self.key_sets: dict[tuple[int, int, int], PointSet] = {}
        # the backdrops, once the key frame is known
        self.clean_plates = list(clean_plates or [None] * self.seq.n_views)
        self._cue = sil.SilhouetteCue(self.seq, moving, [
            None if p is None else imagelib.grey_and_colour(p) for p in self.clean_plates])
        self.notes: list[str] = []  # what the user should know about the run
        # side-on: the root's turns toward and away from the line of sight are held
        self.hold_turn_in_depth = False
        self._use(skeleton)

    def _use(self, skeleton: Skeleton) -> None:
        """Track ``skeleton``: its degrees of freedom and what depends on them."""
        self.skeleton = skeleton
        self._dof_joint, self._dof_axis = skeleton.dof_joints_and_axes()
        self.n_dof = len(self._dof_joint)
        self.n_params = n_root_params(self.mode, self.seq.n_views) + self.n_dof
        self._blobs = raycast.BlobStack.of(skeleton.blobs)  # as they are now, stacked
        # thinnest blob each degree of freedom turns directly, world units (inf: none)
        thin = np.full(skeleton.n_joints, np.inf)
        np.minimum.at(thin, self._blobs.joint, self._blobs.radii[:, 1:].min(axis=1))
        self.dof_thickness = thin[self._dof_joint]
        self._limited = [k for k, j in enumerate(self._dof_joint) if skeleton.limited_hinge(j)]
        self._limbs = Limbs(skeleton, self._blobs)
        self._search = LimbSearch(skeleton, self.settings.limb_search, self._limbs)

    def _foregrounds(self, frame: int, level: int, key: BodyPose, key_frame: int,
                     est: BodyPose, kin: Kinematics) -> list | None:
        """Per view, the foreground of ``frame`` around the body at ``est`` on the view's
        level for tracker level ``level`` (None when the term is off): (crop of its map, the
        crop's top-left level pixel, its foreground's ``NearestPixel``)."""
        s = self.settings
        if s.silhouette <= 0:
            return None
        self._start_cue(key, key_frame)
        out = []
        for c in range(self.seq.n_views):
            if not self._cue.has(c):
                out.append(None)
                continue
            lv = self.scales.view_level(c, level)
            g = self.scales.grid(c, lv)
            margin = self.scales.cap(c) / 2**lv + 2 * g
            shape = self.seq.pyramid(c, frame)[lv].shape
            boxes = raycast.blob_boxes(est.views[c].at_level(lv), self._blobs,
                                       kin.segments)
            # on the label map's grid (every g-th level pixel)
            x0, y0 = np.maximum(np.floor((boxes[:, :2].min(0) - margin) / g), 0).astype(int)
            x1 = int(min(np.ceil((boxes[:, 2].max() + margin) / g), -(-shape[1] // g)))
            y1 = int(min(np.ceil((boxes[:, 3].max() + margin) / g), -(-shape[0] // g)))
            fg = self._cue.foreground(c, frame, lv)[::g, ::g]
            crop = fg[y0:max(y1, y0), x0:max(x1, x0)]
            out.append((crop, (x0, y0), sil.NearestPixel(crop == sil.FOREGROUND)))
        return out

    def _start_cue(self, key: BodyPose, key_frame: int) -> None:
        """Each view's backdrop from the key frame, the first time one is needed (none for a
        view whose backdrop moves, with a note saying so)."""
        if self._cue.started:
            return
        kin_key = Kinematics(self.skeleton, key)
        bodies = [self._body_mask(key, kin_key, c, self.seq.grey(c, key_frame).shape)
                  for c in range(self.seq.n_views)]
        self.notes += self._cue.start(key_frame, bodies, [
            max(1, round(sil.BODY_MARGIN * self.scales.magnification(c)))
            for c in range(self.seq.n_views)],
            key.root_position)

    def exposure_note(self) -> str | None:
        """What to tell the user of the exposures the run followed (``SilhouetteCue.exposure``):
        each view whose footage was read at another exposure than its backdrop's, and how
        far; None where every frame's was the backdrop's."""
        moved = [f"view {c + 1} {span[0]:.2f}-{span[1]:.2f}x" for c in range(self.seq.n_views)
                 if (span := self._cue.exposure_span(c)) not in (None, (1.0, 1.0))]
        if not moved:
            return None
        return (f"{EXPOSURE_NOTE}the footage's exposure changed ({', '.join(moved)} the key "
                "frame's), as a camera's automatic exposure does: each frame's silhouette "
                "was read against the backdrop brought to its exposure")

    def _search_limbs(self, est: BodyPose, frame: int, key: BodyPose, key_frame: int
                      ) -> tuple[BodyPose, list[str], tuple]:
        """``est`` with every limb turned to where the silhouette wants it (``LimbSearch``),
        on the level below full resolution, the joints that turned, and the views the search
        read with each one's foreground map (None for a view it left out)."""
        if self.settings.silhouette <= 0:
            return est, [], ()
        self._start_cue(key, key_frame)
        lvs = self.scales.view_levels(self.scales.search_level())
        fgs = [self._cue.foreground(c, frame, lv) if self._cue.has(c) else None
               for c, lv in enumerate(lvs)]
        if all(f is None for f in fgs):
            return est, [], ()
        views = [v.at_level(lv) for v, lv in zip(est.views, lvs)]
        fgs = self._search.usable(est, views, fgs)
        return *self._search.turn(est, views, fgs), (views, fgs)

    def _refuted_chain(self, est: BodyPose, searched: BodyPose, limb, backdrops: tuple,
                       searched_on: tuple) -> tuple[BodyPose, list] | None:
        """``est`` with the search's turns of ``limb`` and of the limbs below it (which the
        search placed for it), and their degrees of freedom, where the backdrops refute
        those limbs at ``est`` and bear them out so turned, and no view's outline of them
        is against the turn; else None. Of two or more views with a backdrop
        (``backdrops``: the search's views and their ``silhouette.distance_to_body`` maps,
        None for a view it left out), one must show a point of their bones where the body
        cannot be now (``Limbs.bone_off_body``), and none one there once turned. A still
        backdrop's pixel is a plain negative: the body is not there. But one view's
        negative is not every view's evidence: where another view sees a limb of the chain
        on its silhouette and scores it worse turned (``_seen_outlines``), that view's
        silhouette may be what is short of the limb, and the limb keeps its predicted
        motion unless the other gates bear the turn out. A joint several limbs hang from
        (the trunk's) is not a limb's. ``searched_on``: as ``_seen_outlines``."""
        chain = self._chain(limb)
        if not backdrops or chain is None:
            return None
        turned = _with_turns(est, searched, chain)
        rows = [self._limbs.names.index(self.skeleton.names[lb.joint]) for lb in chain]
        now, then = (self._limbs.bone_off_body(Kinematics(self.skeleton, p), *backdrops)[rows]
                     for p in (est, turned))
        have = np.all(~np.isnan(now) & ~np.isnan(then), axis=0)
        if not (have.sum() >= 2 and np.all(then[:, have] == 0) and np.any(now[:, have] > 0)):
            return None
        for lb in chain:
            now_cost, then_cost, margin = self._seen_outlines(est, turned, lb, searched_on)
            if np.any(then_cost - now_cost > margin):
                return None
        return turned, [d for lb in chain for d in lb.dofs]

    def _seen_outlines(self, est: BodyPose, turned: BodyPose, limb, searched_on: tuple
                       ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """In each view that sees ``limb``, its outline's score at ``est`` and at ``turned``
        and the search's margin (``LimbSearch.view_costs``; ``searched_on``: the search's
        views and foreground maps). A view sees the limb where its score at either pose is
        larger than the margin: the pixels the rest of the body leaves free score, those
        under it or unsure do not, and a limb that lies on them both ways is not seen
        there."""
        cost, area = self._search.view_costs(limb, [est, turned], *searched_on)
        margin = self.settings.limb_search * area
        sees = ~np.isnan(area) & (np.abs(cost).max(axis=0) > margin)
        return cost[0, sees], cost[1, sees], margin[sees]

    def _chain(self, limb) -> list | None:
        """The search's limbs that ``limb``'s joint moves, itself first, where they hang in
        one line; None where they branch (the trunk's joints, several limbs hang from)."""
        moved = self.skeleton.moved_by()
        chain = [lb for lb in self._search.limbs if moved[lb.joint, limb.joint]]
        if all(moved[a.joint, b.joint] or moved[b.joint, a.joint] for a in chain for b in chain):
            return chain
        return None

    def _outlines_bear_out(self, est: BodyPose, searched: BodyPose, limb, searched_on: tuple
                           ) -> BodyPose | None:
        """``est`` with ``limb`` turned as in ``searched`` where the outlines of at least
        ``OUTLINE_VIEWS`` views see the limb and every view that sees it scores the turn
        better than the search's margin (``LimbSearch.view_costs``), or where two or more
        see it and every one of them finds it off the body now and on the body turned (its
        score over the margin, then under minus the margin: more of the outline on the
        backdrop than on the silhouette, then the other way round); else None. Which views
        see the limb: ``_seen_outlines``. ``searched_on``: the search's views and foreground
        maps (``_search_limbs``). Not for a joint several limbs hang from: its own
        segment's outline is scored with the limbs below it taken out, and would turn onto
        their silhouettes."""
        if not searched_on or self._chain(limb) is None:
            return None
        turned = _with_turns(est, searched, [limb])
        now, then, m = self._seen_outlines(est, turned, limb, searched_on)
        if len(m) >= OUTLINE_VIEWS and np.all(now - then > m):
            return turned
        if len(m) >= 2 and np.all(now > m) and np.all(then < -m):
            return turned
        return None

    def _pixels_bear_out(self, base: _Samples, cand: BodyPose, limb, sets: list[PointSet],
                         keys: list[np.ndarray], levels: list, level: int) -> int:
        """How many views see ``limb`` where their pixels bear out its turn to ``cand``
        (from ``base``'s pose), else 0 (``_evidenced``); ``keys``: each set's
        ``PointSet.key_points``."""
        trial = self.sample(cand, Kinematics(self.skeleton, cand), sets, levels, level,
                            base.sigmas)
        moved = self.skeleton.moved_by()
        bounds = np.cumsum([0] + [len(ps.value) for ps in sets])
        seen = clear = vouched = 0
        for c, ps in enumerate(sets):
            on = moved[ps.seg_joint, limb.joint]
            old, new = (x[bounds[c]:bounds[c + 1]][on] for x in (base.costs, trial.costs))
            both = ~np.isnan(old) & ~np.isnan(new)
            if both.sum() < MIN_LIMB_POINTS:
                continue  # this view does not see the limb (hidden, or too small)
            seen += 1
            if _clearly_lower(new[both], old[both]):
                clear += 1
                vouched += 1
                continue
            key = both & keys[c][on]
            vouched += bool(key.sum() >= MIN_LIMB_POINTS
                            and _clearly_lower(new[key], old[key]))
        return seen if seen and (clear == seen or (seen > 1 and vouched == seen)) else 0

    def _evidenced(self, est: BodyPose, searched: BodyPose, turned: list[str],
                   sets: list[PointSet], levels: list, level: int, frame: int,
                   searched_on: tuple = ()) -> tuple[BodyPose, list[str]]:
        """``est`` with the turns of ``searched`` that the footage bears out on ``frame``, and
        the joints so turned where two or more views bore the turn out
        (``FrameResult.searched``); ``searched_on``: the views the search read on tracker
        level ``level`` and their foreground maps (``_search_limbs``').
        Parents first, a limb's turn is kept when the backdrops refute the limb where it is
        and bear it out turned, with the limbs below it (``_refuted_chain``), when the
        outlines of three or more views see the limb and every one of them scores the turn
        better, or two or more see it off the body and on it turned (``_outlines_bear_out``:
        a wrong turn seldom fits three silhouettes seen from apart, nor takes a limb off
        the backdrop in two, where the limb's pixels of the earlier frames may be what it
        wrongly covered and hold it there), or when, in every view that sees the limb, its
        pixels of the earlier frames match the new image clearly better turned than not
        (``_clearly_lower``); else the limb keeps its predicted motion. The silhouette
        proposes, brightness decides: an outline alone also fits shadows, clutter and the
        gaps between other limbs. But the pixels of a limb already lost are what it wrongly
        covered, and they hold it there: where a backdrop shows the limb cannot be where it
        is, or the views' outlines agree as above, the outlines decide. Where two or
        more views see the limb, a view may bear the turn out by the key frame's pixels
        alone (they are the user's pose); one view's key pixels alone are not enough (a
        limb's shading changes as it turns under a hard light). A limb no view's earlier
        pixels show (it was hidden) is not turned by brightness: its outline alone fits a
        shadow, or foreground another limb left uncovered, as well as the limb, and what
        the footage does not show is held."""
        base = None  # ``est``'s look at the point sets, taken when brightness is first asked
        keys = [ps.key_points() for ps in sets]
        backdrops = ()  # the search's views (``searched_on``) with their distance maps
        if searched_on:
            views, fgs = searched_on
            lvs = self.scales.view_levels(level)
            backdrops = (views, [None if fg is None else self._cue.distance_to_body(c, frame, lv)
                                 for c, (fg, lv) in enumerate(zip(fgs, lvs))])
        out, kept = est, []
        for limb in self._search.limbs:
            if self.skeleton.names[limb.joint] not in turned:
                continue
            refuted = self._refuted_chain(out, searched, limb, backdrops, searched_on)
            if refuted is not None:
                out, dofs = refuted
            elif (outlined := self._outlines_bear_out(out, searched, limb,
                                                      searched_on)) is not None:
                out, dofs = outlined, limb.dofs
            else:
                cand = _with_turns(out, searched, [limb])
                if base is None:
                    base = self.sample(est, Kinematics(self.skeleton, est), sets, levels, level)
                seen = self._pixels_bear_out(base, cand, limb, sets, keys, levels, level)
                if not seen:
                    continue
                out, dofs = cand, limb.dofs if seen > 1 else []
            for j, _, _ in dofs:  # a ball's two swings name its joint once
                name = self.skeleton.names[j]
                if name not in kept and not np.allclose(out.rotations[j], est.rotations[j]):
                    kept.append(name)
        return out, kept

    def scale_to(self, pose: BodyPose) -> None:
        """Fit each view's pyramid to the body's size there at ``pose`` (``auto_scale``);
        what was built for another size is dropped."""
        scales = Scales.of(self.skeleton, pose, self.settings)
        if scales != self.scales:
            self.scales = scales
            self.seq.set_levels(scales.pyramid_levels())
            self.key_sets.clear()
            self._cue.reset()

    def _body_mask(self, pose: BodyPose, kin: Kinematics, view: int, shape) -> np.ndarray:
        """Full-resolution pixels the blobs cover at ``pose`` in ``view``: for a large body
        (``auto_scale``) each square of 2^octaves pixels takes its top-left pixel's value,
        an error the backdrop's margin (as many times wider) covers."""
        g = max(1, int(self.scales.magnification(view)))
        covered = self._label_maps(pose, kin, [shape], [0], [g], [view])[0][0] >= 0
        return np.repeat(np.repeat(covered, g, 0), g, 1)[:shape[0], :shape[1]]

    def key_sets_made(self, key_frame: int) -> bool:
        """Whether the key frame's point sets are made in every view on every level the
        tracker reads (``key_sets``): then tracking reads none of its images again (its
        backdrops are made on the first frame after it), and they need not be kept (read
        again if the body's scale changes and they are needed)."""
        return all((key_frame, c, lv) in self.key_sets
                   for level in range(self.scales.n_levels())
                   for c, lv in enumerate(self.scales.view_levels(level)))

    def _learn_backdrops(self, res: FrameResult) -> None:
        """Let each view's backdrop see behind where the body was on an earlier frame, now
        that the tracked pose says where it is not."""
        views = [c for c in range(self.seq.n_views) if self._cue.unseen(c)]
        if not views:
            return
        kin = Kinematics(self.skeleton, res.pose)
        for c in views:
            shape = self.seq.grey(c, res.frame).shape
            self._cue.learn(c, res.frame, self._body_mask(res.pose, kin, c, shape))

    @property
    def _level_iterations(self) -> int:
        """Gauss-Newton iterations a level, at most: ``settings.iterations``, and half as many
        (rounded up) where each view carries its own scaled camera (independent mode). There
        a view's own scale and turn take up what its pixels do not pin, and drift further
        with each step: with six a level, a plate's baboon (60 pixels tall) grew to 2.8 times
        its size by the last of its twelve frames; with three, 1.2 times."""
        n = self.settings.iterations
        return n if self.mode == CALIBRATED else -(-n // 2)

    def _active(self, pose: BodyPose, level: int) -> np.ndarray:
        """Unknowns solved on tracker level ``level``: the root always; a joint only where its
        blob is at least ``min_blob_pixels`` thick in the largest view's level, so that
        coarse levels do not fling thin limbs they cannot see."""
        root = pose.root_position
        scale = max(v.scale_at(root) for v in pose.views) / 2**level
        nr = self.n_params - self.n_dof
        roots = np.ones(nr, bool)
        if self.hold_turn_in_depth:  # the turns across the image (``_unknowns``)
            across = np.arange(0, nr, ROOT_PARAMS) + ROOT_TURN.start
            roots[across] = roots[across + 1] = False
        return np.concatenate([roots,
                               self.dof_thickness * scale >= self.settings.min_blob_pixels])

    def _unknowns(self, pose: BodyPose) -> np.ndarray | None:
        """The orthogonal change T (P, P) from the unknowns the system is solved in to the
        pose's parameters (``apply_update``: step = T x), or None for the parameters
        themselves. Side-on, each root turn is solved about the first view's camera axes (its
        x and y across the image, then its line of sight) so that ``_active`` can hold the
        turns toward and away from the camera, which one line of sight shows only as
        foreshortening, the same for either sign. A view's own root (independent mode) turns
        in its camera's frame already."""
        if not self.hold_turn_in_depth or self.mode != CALIBRATED:
            return None
        T = np.eye(self.n_params)
        T[ROOT_TURN, ROOT_TURN] = pose.views[0].orientation.T  # camera axes, world vectors
        return T

    # --- point sets ---------------------------------------------------------------------
    def point_set(self, pose: BodyPose, kin: Kinematics, view: int, frame: int, lv: int,
                  set_weight: float, lost: Collection[str] = ()) -> PointSet:
        """The body's pixels of ``frame`` in ``view`` at ``pose`` on the view's pyramid level
        ``lv`` (every grid-th pixel), each with its segment's frame point, brightness and
        weight. ``lost``: limbs whose pixels the view's still backdrop shows to be backdrop on
        ``frame`` are left out (``_backdrop_pixels``)."""
        level = self.seq.pyramid(view, frame)[lv]
        step = self.scales.grid(view, lv)
        v_l = pose.views[view].at_level(lv)
        pix_l, hits, _ = raycast.render_labels(
            v_l, self._blobs, kin.segments, level.shape, step
        )
        ok = hits.label >= 0
        if lost and self._cue.has(view):
            ok &= ~self._backdrop_pixels(view, frame, lv, pix_l, hits.label, lost)
        pix_l, label = pix_l[ok].astype(int), hits.label[ok]
        seg_joint = self._blobs.joint[label]
        g = kin.segments.take(seg_joint, 0)
        d = hits.world[ok] - g[:, :3, 3]
        ref = np.einsum("nba,nb->na", g[:, :3, :3], d)
        at = level.values(pix_l, derivatives=True).astype(float)
        C = level.channels
        rim = np.clip(np.sqrt(hits.rim[ok]) / self.settings.rim_width, 0, 1)
        return PointSet(view, seg_joint, label, ref, at[:, :C], rim * set_weight,
                        at[:, C:2 * C] ** 2 + at[:, 2 * C:] ** 2)

    def _backdrop_pixels(self, view: int, frame: int, lv: int, pix: np.ndarray,
                         blob: np.ndarray, lost: Collection[str]) -> np.ndarray:
        """Which level pixels ``pix`` (N, 2) of blobs ``blob`` (N,; -1: none) belong to a limb
        in ``lost`` and lie over ``LOST_REACH`` level pixels from any pixel of ``frame`` that
        may be the body (foreground or unsure on its map): a limb lost onto a textured
        backdrop would be held there by those pixels, which do not move."""
        limb = np.append(np.isin(self._limbs.names, list(lost)), False)[
            np.where(blob >= 0, self._limbs.of_blob[blob], -1)]
        if not limb.any():
            return limb
        out = np.zeros(len(blob), bool)
        px = pix[limb].astype(int)
        out[limb] = ~self._cue.near_body(view, frame, lv, px[:, 0], px[:, 1], LOST_REACH)
        return out

    def _label_maps(self, pose: BodyPose, kin: Kinematics, shapes: list, lvs: list[int],
                    grids: list[int], views: list[int] | None = None
                    ) -> list[tuple[np.ndarray, raycast.LabelGrid]]:
        """Per view (``views``, default all), the front-most blob (-1: none) at every
        ``grids[i]``-th pixel of its level ``lvs[i]`` (of ``shapes[i]``), as a map whose pixel
        (i, j) is level pixel (grid i, grid j), and the z-buffer it came from; the views'
        z-buffers made together (``raycast.label_grids``)."""
        views = range(len(pose.views)) if views is None else views
        cams = [pose.views[c].at_level(lv) for c, lv in zip(views, lvs)]
        made = raycast.label_grids(cams, self._blobs, kin.segments, shapes, grids)
        return [(labels.full(shape), labels) for labels, shape in zip(made, shapes)]

    # --- one level -----------------------------------------------------------------------
    def sample(self, est: BodyPose, kin: Kinematics, sets: list[PointSet], levels: list,
               level: int, sigmas: list[np.ndarray] | None = None, fgs: list | None = None
               ) -> _Samples:
        """Map every point set into the new frame under ``est``: per-point robust costs (NaN
        where the point is hidden by another blob or off the image) and what the rows need.
        ``levels`` holds each view's pyramid level for tracker level ``level``. Without
        ``sigmas`` the points' noise scales are measured here (``_sigmas``): a level's
        starting pose sets them, and its candidates are costed with them. The previous
        frame's points of segments two or more views see are noisier by the blobs' misfit
        (``solver.point_noise``, ``registration_noise``); the key frame's points, the anchor
        against drift, and a segment one view alone sees keep their set's noise."""
        s = self.settings
        costs, parts = [], []
        n_pts, n_inside = np.zeros(self.seq.n_views), np.zeros(self.seq.n_views)
        lvs = self.scales.view_levels(level)
        gs = [self.scales.grid(c, lv) for c, lv in enumerate(lvs)]
        maps = self._label_maps(est, kin, [lv.shape for lv in levels], lvs, gs)
        labels = [m[0] for m in maps]
        shape_cost, shape_parts = 0.0, []
        if fgs is not None:
            for c, ((lab, grid), view_fg) in enumerate(zip(maps, fgs)):
                if view_fg is None:
                    shape_parts.append(None)
                    continue
                fg, (x0, y0), nearest_fg = view_fg
                crop = (slice(y0, y0 + fg.shape[0]), slice(x0, x0 + fg.shape[1]))
                full = 2**lvs[c] * gs[c]  # full-resolution pixels per map pixel
                mm = sil.mismatch(lab[crop], fg, self.scales.cap(c) / full,
                                  nearest_fg=nearest_fg)
                shape_cost += s.silhouette * mm.cost
                shape_parts.append(_ShapePull(mm, grid, (x0, y0), full))
        measured = []
        several = _views_seeing(sets, self.skeleton.n_joints) > 1
        for k, ps in enumerate(sets):
            world = kin.world_points(ps.seg_joint, ps.ref)
            pix = est.views[ps.view].project(world)
            vals, inside = imagelib.sample(levels[ps.view], pix)
            C = levels[ps.view].channels
            if sigmas is None:
                measured.append(self._sigmas(ps, vals[:, :C] - ps.value, inside))
            sigma = measured[-1] if sigmas is None else sigmas[k]
            p_l = np.rint(imagelib.to_level(pix, levels[ps.view]) / gs[ps.view]).astype(int)
            lab = labels[ps.view]
            H, W = lab.shape
            x, y = p_l.T
            inb = np.flatnonzero((x >= 0) & (x < W) & (y >= 0) & (y < H))
            visible = np.zeros(len(pix), dtype=bool)  # the map's flat array, read with take
            visible[inb] = lab.ravel().take(y.take(inb) * W + x.take(inb)) == ps.blob.take(inb)
            ok = np.flatnonzero(inside & visible)
            n_pts[ps.view] += len(pix)
            n_inside[ps.view] += int(inside.sum())
            vals = vals.take(ok, 0)
            r = vals[:, :C] - ps.value[ok]
            c = np.full(len(pix), np.nan)
            misfit = several.take(ps.seg_joint) & ~ps.key_points()
            misplaced = s.registration_noise * misfit.take(ok)
            noise = point_noise(sigma[ok], ps.slope[ok], misplaced[:, None])
            c[ok] = ps.weight[ok] * mixture_cost(r, noise, s.outlier_density)
            costs.append(c)
            grad = np.stack([vals[:, C:2 * C], vals[:, 2 * C:]], -1)  # (M, C, 2)
            parts.append((ok, world.take(ok, 0), grad, r, noise))
        return _Samples(np.concatenate(costs), parts, n_inside / np.maximum(n_pts, 1),
                        measured if sigmas is None else sigmas, shape_cost, shape_parts)

    def _pixel_weights(self, ps: PointSet, ok: np.ndarray, r: np.ndarray, noise: np.ndarray
                       ) -> np.ndarray:
        """Weights (M, C) of a point set's usable points ``ok`` with residuals ``r`` (M, C)
        and noise scales ``noise`` (M, C): their rim weight times the EM support posterior
        over each channel's noise scale squared."""
        return ps.weight[ok][:, None] * support_weights(r, noise,
                                                        self.settings.outlier_density)

    def _pixel_rows(self, ps: PointSet, part: tuple) -> tuple:
        """A point set's usable points (``_Samples.parts``) as rows, one per point and
        channel: their segments' joints, world points (., 3), image gradients (., 2),
        residuals and weights."""
        ok, world, grad, r, noise = part
        C = r.shape[1]
        return (np.repeat(ps.seg_joint[ok], C), np.repeat(world, C, axis=0),
                grad.reshape(-1, 2), r.ravel(), self._pixel_weights(ps, ok, r, noise).ravel())

    def _solver_rows(self, ps: PointSet, part: tuple) -> tuple:
        """``_pixel_rows`` as the normal equations take them: a grey pixel's one row, a
        colour pixel's channels as two rows that add the same (``solver.channel_rows``)."""
        ok, world, grad, r, noise = part
        if r.shape[1] == 1:
            return self._pixel_rows(ps, part)
        joints = ps.seg_joint[ok]
        return (np.concatenate([joints, joints]), np.concatenate([world, world]),
                *channel_rows(grad, r, self._pixel_weights(ps, ok, r, noise)))

    def _normal_equations(self, kin: Kinematics, sets: list[PointSet], smp: _Samples,
                          level: int) -> NormalEquations:
        """Rows of every point set at the sampled pose, weighted by the EM support posterior,
        and the silhouette's rows (each mismatched pixel's two coordinates); one block of
        rows per view."""
        pieces = [[] for _ in range(self.seq.n_views)]  # per view: (joints, X, grad, r, w)
        for ps, part in zip(sets, smp.parts):
            if len(part[0]):
                pieces[ps.view].append(self._solver_rows(ps, part))
        s = self.settings
        for c, pull in enumerate(smp.shape_parts):
            if pull is None or not len(pull.mm.weight):
                continue
            lv = self.scales.view_level(c, level)
            g = 2**lv * self.scales.grid(c, lv)  # full-resolution pixels per map pixel
            every = -(-len(pull.mm.weight) // SIL_MAX_ROWS)  # thinned evenly, weights scaled up
            blob, world, target, pair_w = pull.rows(every)
            joints = self._blobs.joint[blob]
            n = len(world)
            unit = np.zeros((2 * n, 2))  # x rows, then y rows
            unit[:n, 0] = unit[n:, 1] = 1.0
            r = (kin.pose.views[c].project(world) - target).T.ravel()
            w = np.tile(pair_w, 2) * (s.silhouette * every / g**2)
            pieces[c].append((np.tile(joints, 2), np.tile(world, (2, 1)), unit, r, w))
        ne = NormalEquations.zeros(self.n_params)
        for c, view_pieces in enumerate(pieces):
            if view_pieces:
                joints, world, grad, r, w = (np.concatenate(x) for x in zip(*view_pieces))
                ne.add(rows(kin, c, self.mode, joints, world, grad), r, w)
        return ne

    def _sigmas(self, ps: PointSet, r: np.ndarray, inside: np.ndarray) -> np.ndarray:
        """Residual scale (N, C) of a point set's points from their residuals ``r`` (N, C)
        and which fell inside the image: one scale per frame the set joins and channel."""
        lengths = ps.lengths or (len(r),)
        cuts = np.cumsum(lengths)[:-1]
        scales = [[robust_scale(part_r[part_in, ch], self.settings.noise_floor)
                   for ch in range(r.shape[1])]
                  for part_r, part_in in zip(np.split(r, cuts), np.split(inside, cuts))]
        return np.repeat(np.array(scales).reshape(len(lengths), r.shape[1]), lengths, axis=0)

    def _residual(self, sets: list[PointSet], smp: _Samples, sigmas: list[np.ndarray]) -> float:
        """RMS brightness error of the pixels that follow the body (support-weighted), in
        image units: what the report calls a frame's residual (colour footage's chroma
        channels left out, so that it reads the same with colour or without), each pixel
        weighed at its set's noise scale (``_sigmas``), a steep edge's as any other's."""
        num = den = 0.0
        for ps, sigma, (ok, _, _, r, _) in zip(sets, sigmas, smp.parts):
            w = self._pixel_weights(ps, ok, r, sigma[ok])[:, 0]
            r = r[:, 0]
            num += float(np.sum(w * r * r))
            den += float(np.sum(w))
        return float(np.sqrt(num / den)) if den > 0 else float("nan")

    def _limb_checks(self, kin: Kinematics, sets: list[PointSet], smp: _Samples,
                     fgs: list | None, doubted: Collection[str],
                     flagged: Collection[str] | None) -> dict[str, LimbCheck]:
        """Each limb's confidence at the finest level's pose ``kin`` (``core.confidence``):
        per view, its mapped pixels' support (1 for a perfect match) and how much of its
        bone lies on the silhouette; with one view, the foreground no blob explains near
        it; ``doubted`` and ``flagged``: the limbs doubted and flagged on the frame before."""
        top = 1 + self.settings.outlier_density
        axis = kin.world_points(self._limbs.axis_joint, self._limbs.axis_ref)
        per_view, own_views = [], []
        for c, (ps, sigma, (ok, _, _, r, _)) in enumerate(zip(sets, smp.sigmas, smp.parts)):
            support = np.full(len(ps.value), np.nan)
            support[ok] = np.minimum(
                top * support_posterior(r, sigma[ok], self.settings.outlier_density), 1.0)
            on = None
            if fgs is not None and fgs[c] is not None:
                crop, (x0, y0), _ = fgs[c]  # on every g-th pixel of the view's level
                lv = self.scales.view_level(c, 0)
                g = self.scales.grid(c, lv)
                px = np.rint(kin.pose.views[c].at_level(lv).project(axis) / g).astype(int)
                px -= (x0, y0)
                inside = ((px >= 0) & (px < (crop.shape[1], crop.shape[0]))).all(axis=1)
                on = np.full(len(px), np.nan)
                code = crop[px[inside, 1], px[inside, 0]]
                on[inside] = np.where(code == sil.UNSURE, np.nan, code == sil.FOREGROUND)
            per_view.append(self._limbs.view_agreement(ps.blob, support, on))
            own_views.append(self._limbs.view_agreement(ps.blob, support, on, own=True))
        return self._limbs.checks(per_view, doubted, flagged,
                                  self._unexplained(kin, smp, fgs) if self.seq.n_views == 1
                                  else None, own_views)

    def _unexplained(self, kin: Kinematics, smp: _Samples, fgs: list | None
                     ) -> np.ndarray | None:
        """One view's ``Limbs.unexplained`` at the finest level's pose ``kin`` (its samples
        ``smp``, its foreground crops ``fgs``), or None where the view has no backdrop."""
        if fgs is None or fgs[0] is None:
            return None
        crop, at, _ = fgs[0]
        lv = self.scales.view_level(0, 0)
        view = kin.pose.views[0].at_level(lv)
        labels = smp.shape_parts[0].grid.window(*at, crop.shape)
        return self._limbs.unexplained(
            kin, view, self.scales.grid(0, lv), crop == sil.FOREGROUND, at, labels,
            raycast.outline_areas(view, self._blobs, kin.segments))

    def _trust(self, delta: np.ndarray) -> np.ndarray:
        """The step shortened so that no joint turns more than ``max_step`` degrees: far from
        the linearisation point the rows no longer describe the motion, and a thin limb would
        otherwise be flipped by one step."""
        turn = np.max(np.abs(delta[self.n_params - self.n_dof:]), initial=0.0)
        cap = np.radians(self.settings.max_step)
        return delta * (cap / turn) if turn > cap else delta

    def _within_limits(self, est: BodyPose, delta: np.ndarray) -> np.ndarray:
        """The step with every limited hinge's new angle clipped into its range (a hinge
        found outside it may only move back toward it)."""
        nr = self.n_params - self.n_dof
        for k in self._limited:
            j = self._dof_joint[k]
            delta[nr + k] = np.clip(delta[nr + k], *self.skeleton.hinge_turns(j, est.rotations[j]))
        return delta

    def _left_views(self, smp: _Samples) -> str:
        """'' while enough of the body is inside every image, else which views it left."""
        gone = np.flatnonzero(smp.inside < self.settings.min_inside)
        if not len(gone):
            return ""
        return "the body left the image of view " + ", ".join(str(c + 1) for c in gone)

    def _blob_pixels(self, kin: Kinematics) -> np.ndarray:
        """Image positions (views, blobs, 2) of the blob centres, for the convergence test."""
        centres = kin.world_points(self._blobs.joint, self._blobs.centre)
        return np.array([v.project(centres) for v in kin.pose.views])

    def frame_pixels(self, prev: BodyPose, prev_frame: int, est: BodyPose, frame: int
                     ) -> list[tuple]:
        """The body's pixels of ``prev_frame`` (at pose ``prev``, full resolution, every
        ``pixel_step``-th) mapped into ``frame`` under ``est``, those visible there: per view
        (view, then per pixel and channel (``_pixel_rows``) segment joints (N,), world points
        (N, 3), image gradients (N, 2), residuals (N,), EM support weights (N,)). For
        estimates made outside the tracker's own system (the skeleton's refinement)."""
        self.scale_to(prev)
        kin_prev, kin = Kinematics(self.skeleton, prev), Kinematics(self.skeleton, est)
        levels = [self.seq.pyramid(c, frame)[0] for c in range(self.seq.n_views)]
        sets = [self.point_set(prev, kin_prev, c, prev_frame, 0, 1.0)
                for c in range(self.seq.n_views)]
        smp = self.sample(est, kin, sets, levels, 0)
        return [(ps.view, *self._pixel_rows(ps, part)) for ps, part in zip(sets, smp.parts)]

    def track_frame(self, prev: BodyPose, prev_frame: int, key: BodyPose, key_frame: int,
                    predicted: BodyPose, frame: int, doubted: Collection[str] = (),
                    flagged: Collection[str] | None = None) -> FrameResult:
        """One frame: refine ``predicted`` against the previous frame (``prev`` on
        ``prev_frame``) and the key frame, coarse to fine; ``doubted`` and ``flagged``: the
        limbs doubted and flagged on the previous frame (``LimbCheck``; None: those
        doubted). Raises DegenerateSystem."""
        s = self.settings
        t0 = time.perf_counter()
        self.scale_to(key)
        est = predicted
        offset = np.zeros(self.n_params)
        total_iters = 0
        searched_joints: list[str] = []
        converged = False
        kin_prev, kin_key = Kinematics(self.skeleton, prev), Kinematics(self.skeleton, key)
        for level in reversed(range(self.scales.n_levels())):
            lvs = self.scales.view_levels(level)
            levels = [self.seq.pyramid(c, frame)[lv] for c, lv in enumerate(lvs)]
            sets = []  # per view, the previous frame's points then the key frame's
            for c, lv in enumerate(lvs):
                view_sets = [self.point_set(prev, kin_prev, c, prev_frame, lv, 1.0,
                                            doubted if s.release_lost_limbs else ())]
                if s.key_weight > 0 and key_frame != prev_frame:
                    k = (key_frame, c, lv)
                    if k not in self.key_sets:
                        self.key_sets[k] = self.point_set(key, kin_key, c, key_frame, lv,
                                                          s.key_weight)
                    view_sets.append(self.key_sets[k])
                sets.append(PointSet.joined(view_sets))
            kin = Kinematics(self.skeleton, est)
            if s.limb_search > 0 and level == self.scales.search_level():
                searched, turned, searched_on = self._search_limbs(est, frame, key, key_frame)
                if turned:
                    searched, searched_joints = self._evidenced(est, searched, turned, sets,
                                                                levels, level, frame,
                                                                searched_on)
                if searched is not est:  # the prediction from here on (what prior holds to)
                    est, offset = searched, np.zeros(self.n_params)
                    kin = Kinematics(self.skeleton, est)
            active = self._active(est, level)
            fgs = self._foregrounds(frame, level, key, key_frame, est, kin)
            smp = self.sample(est, kin, sets, levels, level, None, fgs)
            sigmas = smp.sigmas
            left = self._left_views(smp)
            if left:
                return FrameResult(frame=frame, pose=est, residual=float("nan"),
                                   iterations=total_iters, converged=False, diverged=True,
                                   reason=left, seconds=time.perf_counter() - t0)
            T = self._unknowns(est)
            ne = self._normal_equations(kin, sets, smp, level).changed(T)
            prior = s.prior * np.diag(ne.H)
            lam = s.damping
            converged = False
            for it in range(self._level_iterations):
                total_iters += 1
                x = solve(ne, lam, prior, offset, active)
                step = self._within_limits(est, self._trust(x if T is None else T @ x))
                delta = step if T is None else T.T @ step  # in the solved unknowns
                cand = apply_update(self.skeleton, est, step, self.mode)
                kin_c = Kinematics(self.skeleton, cand)
                c_smp = self.sample(cand, kin_c, sets, levels, level, sigmas, fgs)
                # compare on the pixels seen in both poses: a step must not win by hiding pixels
                both = ~np.isnan(smp.costs) & ~np.isnan(c_smp.costs)
                old = float(np.sum(smp.costs[both]) + smp.shape_cost + prior @ offset**2)
                new = float(np.sum(c_smp.costs[both]) + c_smp.shape_cost
                            + prior @ (offset + delta) ** 2)
                if new <= old:
                    moved = np.max(np.linalg.norm(self._blob_pixels(kin_c)
                                                  - self._blob_pixels(kin), axis=-1))
                    est, kin, smp = cand, kin_c, c_smp
                    offset = offset + delta
                    lam = max(lam / 3, 1e-6)
                    if moved / 2**level < s.converge_pixels:
                        converged = True
                        break
                    if it + 1 < self._level_iterations:
                        ne = self._normal_equations(kin, sets, smp, level).changed(T)
                else:
                    lam *= 4
                    if lam > 1e4:
                        converged = True  # no step lowers the cost: a minimum at this level
                        break
        result = FrameResult(frame=frame, pose=est, residual=self._residual(sets, smp, sigmas),
                             iterations=total_iters, converged=converged,
                             limbs=self._limb_checks(kin, sets, smp, fgs, doubted, flagged),
                             searched=searched_joints)
        left = self._left_views(smp)
        if left:
            result.diverged, result.reason = True, left
        result.seconds = time.perf_counter() - t0
        return result

    # --- the sequence ----------------------------------------------------------------------

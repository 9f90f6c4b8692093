"""The tracking run: frame after frame, predict the pose and fit it (``core.frame_fit``).

Each new frame's pose is predicted from the last two (constant velocity; a limited hinge
that its speed would carry past its limits, or a limb no view saw, or one in doubt tracked
side-on, is held where it was), then fitted to the frame. The first frame's pose is the
user's and the first key frame; a frame the user corrected takes the user's pose and
becomes the key frame after it. Where every view looks along one line the body is tracked
side-on (``core.side_on``; its root's turn toward or away from the camera held), decided
from the first pose. A frame whose residual jumps, whose body leaves the images or whose
system is degenerate is reported as diverged instead of being accepted; a residual that
climbs over several frames (the body turning sides to the cameras that the key frame does
not show) is no jump, and the limbs' checks report it. A camera that moves (a pan, a
handheld phone solved in Blender) is given per frame; each frame is seen through its
cameras as they stood then, and the root's motion stays the body's own, in the world; a
camera that only turns about its centre keeps its silhouette (``core.silhouette``).
"""

from __future__ import annotations

from collections.abc import Callable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field

import numpy as np

from . import image as imagelib
from . import raycast, se3
from .blas import one_blas_thread
from .camera import Camera
from .confidence import UNSEEN, UNSURE_FLAG
from .errors import InputError
from .frame_fit import EXPOSURE_NOTE, FrameFit, FrameResult
from .linearize import Kinematics
from .pose import CALIBRATED, INDEPENDENT, BodyPose, extrapolate
from .settings import TrackerSettings
from .side_on import depth_blind_joints, line_of_sight, side_on_skeleton, turned_from
from .skeleton import Skeleton
from .solver import DegenerateSystem

MIN_LEVEL_PIXELS = 16  # the coarsest pyramid level keeps images at least this large
READ_REACH = 0.2  # of the body's larger side in a view: how far round its outline on the
# last tracked frame a frame read ahead has its pyramids' stacks made (the rest when read)
WHOLE_SHARE = 0.6  # of a view's image: a window over more than this is the whole image
WINDOW_FROM = 1_000_000  # pixels: smaller images are made whole (their pyramids cost less
# than checking every read against a window: 480x360 views track 0.97 times as fast)


def frames_tracked(results: Sequence[FrameResult]) -> int:
    """How many of a run's results, in tracking order, were tracked: those after the first
    (the given pose) that did not diverge. The report and the add-on count the same way."""
    return sum(not r.diverged for r in results[1:])


def frames_to_check(results: Sequence[FrameResult]) -> dict[int, dict[str, str]]:
    """The tracked frames of a run's results with limbs flagged, and those limbs' flags
    (``FrameResult.flagged``). The report and the add-on list the same frames."""
    return {r.frame: r.flagged for r in results if r.flagged and not r.diverged}


def newly_flagged(before: FrameResult | None, now: FrameResult) -> dict[str, str]:
    """The flags of ``now`` (``FrameResult.flagged``) on limbs that ``before``, the result
    tracked just before it (None for the first), did not flag: where those limbs' doubt
    begins. A diverged frame flags nothing, and a frame given by the user has no checks."""
    if now.diverged:
        return {}
    held = {} if before is None or before.diverged else before.flagged
    return {name: why for name, why in now.flagged.items() if name not in held}


def doubts_begun(results: Sequence[FrameResult]) -> dict[int, dict[str, str]]:
    """The tracked frames of a run's results, in tracking order, where a limb's flag begins,
    and those flags (``newly_flagged``). A limb in doubt stays flagged until every view that
    sees it agrees again (``core.confidence``), so a long run of frames to check comes down
    to the few where something first went wrong: where to look, and correct, first."""
    begun = (newly_flagged(before, now) for before, now in zip([None, *results], results))
    return {r.frame: flags for r, flags in zip(results, begun) if flags}



@dataclass
class TrackResult:
    frames: list[FrameResult] = field(default_factory=list)
    cancelled: bool = False
    notes: list[str] = field(default_factory=list)  # the tracker's notes on the run

    @property
    def diverged_frames(self) -> list[int]:
        return [f.frame for f in self.frames if f.diverged]

    @property
    def frames_to_check(self) -> dict[int, dict[str, str]]:
        return frames_to_check(self.frames)

    @property
    def doubts_begun(self) -> dict[int, dict[str, str]]:
        return doubts_begun(self.frames)



class Tracker(FrameFit):
    """Tracks a skeleton through the frames of one or more views: the per-frame fit, driven
    over a sequence."""

    def __init__(self, skeleton: Skeleton, images: Sequence[Sequence], mode: str = INDEPENDENT,
                 settings: TrackerSettings | None = None,
                 moving: Sequence[Sequence[Camera] | None] | None = None,
                 clean_plates: Sequence | None = None):
        """``moving``: per view, its camera on every frame where the camera moves (None for
        a view whose camera stands still); calibrated mode only. ``clean_plates``: per
        view, an image of its scene without the body, or None (``FrameFit``)."""
        moving = list(moving) if moving is not None else [None] * len(images)
        super().__init__(skeleton, images, mode, settings, moving, clean_plates)
        self.given_skeleton = skeleton  # as the caller gave it (``side_on`` changes joints)
        self.moving = moving
        # set by ``track``: the line side-on's hinges turn about (a world direction) and the
        # pose they were set up at
        self.sight: np.ndarray | None = None
        self._side_on_key: BodyPose | None = None
        if any(m is not None for m in self.moving) and mode != CALIBRATED:
            raise InputError("cameras that move need the calibrated mode: the body's root is "
                             "tracked in the world, each camera is where it was filmed from")
        for c, path in enumerate(self.moving):
            if path is not None and len(path) < self.seq.n_frames():
                raise InputError(f"view {c + 1}'s camera is given on {len(path)} frames, its "
                                 f"footage has {self.seq.n_frames()}")
            if path is not None and self.clean_plates[c] is not None:
                raise InputError(f"view {c + 1}'s camera moves, so one still image of its "
                                 "scene cannot be its clean plate: clear the clean plate (its "
                                 "backdrop is then drawn from the footage)")

    def _filmed_from(self, pose: BodyPose, frame: int) -> BodyPose:
        """``pose`` seen through each view's camera as it stood on ``frame``."""
        if all(m is None for m in self.moving):
            return pose
        out = pose.copy()
        out.views = [v if m is None else m[frame].copy() for v, m in zip(pose.views, self.moving)]
        return out

    def _check_start(self, initial: BodyPose, frame: int) -> None:
        """InputError unless every view's image files can be read and share one size (its
        clean plate's too), that size fits the pyramid asked for, and the first pose puts
        the body inside every view's image (a camera looking away, or a pose far off, would
        otherwise read as a divergence on the next frame)."""
        for c in range(self.seq.n_views):
            imagelib.check_footage(self.seq.images[c], f"view {c + 1}'s footage")
        kin = Kinematics(self.skeleton, initial)
        centres = kin.world_points(self._blobs.joint, self._blobs.centre)
        for c, view in enumerate(initial.views):
            h, w = self.seq.grey(c, frame).shape
            plate = self._cue.plates[c]
            if plate is not None and plate[0].shape != (h, w):
                source = self.clean_plates[c]
                where = "" if isinstance(source, np.ndarray) else f"{source}: "
                raise InputError(f"{where}view {c + 1}'s clean plate is "
                                 f"{plate[0].shape[1]}x{plate[0].shape[0]}, its footage "
                                 f"{w}x{h}: give the plate from the same camera, uncropped")
            most = int(np.log2(min(h, w) / MIN_LEVEL_PIXELS)) + 1
            if self.settings.levels > most:
                raise InputError(
                    f"settings.levels: {self.settings.levels} pyramid levels shrink view "
                    f"{c + 1}'s {w}x{h} images below {MIN_LEVEL_PIXELS} pixels; use at most "
                    f"{max(most, 1)}")
            px = view.project(centres)
            inside = np.mean((px[:, 0] >= 0) & (px[:, 0] < w) & (px[:, 1] >= 0)
                             & (px[:, 1] < h))
            if inside < self.settings.min_inside:
                raise InputError(
                    f"on the first frame only {inside:.0%} of the body is inside view {c + 1}'s "
                    "image: check where that view's camera looks and that the pose lines up "
                    "with the footage")

    def predict(self, before: BodyPose, last: BodyPose, held: Sequence[str] = ()) -> BodyPose:
        """Constant-velocity prediction from the poses of the two frames before, except that a
        limited hinge whose turn would carry it past its limits is predicted where it was:
        carried on, an elbow the limb search had just turned 75 degrees wrapped round past
        180 and came out bent backward; stopped at the limit, it was 30 degrees off. The
        joints ``held`` are predicted where they were: limbs no view saw on the last frame
        (the footage did not show their motion; tracked side-on, those in doubt too:
        ``held_joints``), and those the limb search turned there on two or more views'
        evidence (views that agree a limb was off: its last step was mostly the error the
        turn took out, and carried on it threw the limb as far off the other way on the
        next frame, as a user's correction would). A turn one view bore out keeps its
        speed: a plate's leg turns 20-40 degrees a cell, past the differential step, and
        the search is how its motion is followed at all."""
        pred = extrapolate(before, last, self.settings.prediction_gain)
        held_joints = {self.skeleton.index(name) for name in held}
        for j in held_joints:
            pred.rotations[j] = last.rotations[j]
        for k in self._limited:
            j, axis = self._dof_joint[k], self._dof_axis[k]
            if j in held_joints:
                continue
            step = se3.log_so3(before.rotations[j].T @ last.rotations[j]) @ axis
            lo, hi = self.skeleton.hinge_turns(j, last.rotations[j])
            turn = self.settings.prediction_gain * step
            turn = turn if lo <= turn <= hi else 0.0
            pred.rotations[j] = last.rotations[j] @ se3.exp_so3(axis * turn)
        return pred

    def iter_track(self, initial: BodyPose, frames: Sequence[int],
                   corrections: Mapping[int, BodyPose] | None = None) -> Iterator[FrameResult]:
        """Track through ``frames`` (indices into every view's images, in tracking order,
        forward or backward; the first is the frame ``initial`` is posed on). Yields one result
        per frame, the first being the initial pose itself; stops after a divergence if the
        settings say so. A frame in ``corrections`` (poses the user set) takes that pose as its
        result and becomes the key frame that later frames are held against."""
        corrections = corrections or {}
        frames = list(frames)
        n = self.seq.n_frames()
        for f in frames:
            if not 0 <= f < n:
                raise IndexError(f"frame {f} is outside the footage's 0..{n - 1}")
        if len(initial.views) != self.seq.n_views:
            raise InputError(
                f"the pose has {len(initial.views)} views, the footage {self.seq.n_views}"
            )
        initial = self._filmed_from(initial, frames[0])
        self._check_start(initial, frames[0])
        key_frame, key = frames[0], initial
        self.key_sets.clear()  # the key pose may differ from an earlier run's
        self._cue.reset()  # learned from it
        self.notes = []
        path = self.moving[0]
        self.sight = line_of_sight(initial, None if path is None else [path[f] for f in frames])
        self._side_on_key = initial  # the pose the side-on hinges were set up at
        blind = depth_blind_joints(self.given_skeleton, initial, self.sight)
        self.hold_turn_in_depth = bool(blind) and self.settings.side_on  # tracked side-on
        if self.settings.side_on:
            self._use(side_on_skeleton(self.given_skeleton, initial, self.sight))
            if blind:
                self.notes.append(f"side-on: {', '.join(blind)} tracked as hinges about the "
                                  "line of sight, turning in the image plane only")
        elif blind:
            self.notes.append(
                f"every view looks along one line, so {', '.join(blind)} can turn toward or "
                "away from the camera unseen (only foreshortening shows it): add a view from "
                "another side, or track side-on, as hinges about the line of sight (Side on "
                "in the Track settings; side_on in a job)")
        outside = self.skeleton.outside_limits(initial.rotations)
        if outside:
            self.notes.append(
                f"{', '.join(outside)} start{'s' if len(outside) == 1 else ''} bent outside "
                "the joint's limits and can only turn back toward them: pose "
                f"{'it' if len(outside) == 1 else 'them'} within the limits (Fit Pose to "
                "Markers and core fit do) to let the tracker follow every bend")
        self.scale_to(initial)
        first = FrameResult(frame=key_frame, pose=initial.copy(), residual=0.0, iterations=0,
                            converged=True, given=True)
        yield first
        history = [first]
        residuals: list[float] = []
        for i, frame in enumerate(frames[1:], 1):
            prev = history[-1]
            if i + 1 < len(frames):
                self.seq.read_ahead(frames[i + 1], self._read_windows(prev.pose, prev.frame))
            if frame in corrections:
                key_frame, key = frame, self._filmed_from(corrections[frame], frame).copy()
                self.key_sets.clear()
                res = FrameResult(frame=frame, pose=key.copy(), residual=0.0, iterations=0,
                                  converged=True, given=True)
                self.seq.keep_only({(c, frame) for c in range(self.seq.n_views)})
                yield res
                # the step from a given pose is a velocity; from a tracked one it is mostly
                # the error the correction takes out, which carried on flung the next frames
                history = history[-1:] + [res] if prev.given else [res]
                continue
            with one_blas_thread():
                res = self._next_frame(history, key, key_frame, frame, residuals)
            self.notes = [n for n in self.notes if not n.startswith(EXPOSURE_NOTE)]
            if note := self.exposure_note():
                self.notes.append(note)
            if np.isfinite(res.residual):
                residuals.append(res.residual)
            kept = (prev.frame, frame) if self.key_sets_made(key_frame) else \
                (key_frame, prev.frame, frame)
            self.seq.keep_only({(c, f) for c in range(self.seq.n_views) for f in kept})
            yield res
            if res.diverged and self.settings.stop_on_divergence:
                return
            history = history[-1:] + [res]

    def _read_windows(self, pose: BodyPose, frame: int) -> list[tuple | None]:
        """Per view, where the body should lie on a frame read ahead of ``frame`` (tracked
        at ``pose``): its blobs' outline there widened by ``READ_REACH`` of its larger side,
        as a full-resolution box (x0, y0, x1, y1); None for a view whose camera moves, or
        where the image is small (``WINDOW_FROM``) or the box covers most of it
        (``WHOLE_SHARE``)."""
        sizes = [self.seq.grey(c, frame).shape for c in range(len(pose.views))]
        windowed = [self.moving[c] is None and H * W >= WINDOW_FROM
                    for c, (H, W) in enumerate(sizes)]
        if not any(windowed):  # small footage (the common case): no pose to work out
            return [None] * len(pose.views)
        kin = Kinematics(self.skeleton, pose)
        out: list[tuple | None] = []
        for view, (H, W), on in zip(pose.views, sizes, windowed):
            if not on:
                out.append(None)
                continue
            boxes = raycast.blob_boxes(view, self._blobs, kin.segments)
            lo, hi = boxes[:, :2].min(0), boxes[:, 2:].max(0)
            reach = READ_REACH * float(np.max(hi - lo))
            (x0, y0), (x1, y1) = np.maximum(lo - reach, 0), np.minimum(hi + reach, (W, H))
            if not np.all(np.isfinite([x0, y0, x1, y1])) or x1 <= x0 or y1 <= y0 or \
                    (x1 - x0) * (y1 - y0) > WHOLE_SHARE * W * H:
                out.append(None)
            else:
                out.append((int(x0), int(y0), int(np.ceil(x1)), int(np.ceil(y1))))
        return out

    def _next_frame(self, history: list[FrameResult], key: BodyPose, key_frame: int,
                    frame: int, residuals: list[float]) -> FrameResult:
        """Track ``frame`` from the results before it (``history``, the last one or two),
        judge it diverged against the residuals so far, and let the backdrops learn from
        it."""
        prev = history[-1]
        held = held_joints(prev, self.hold_turn_in_depth)
        pred = self._filmed_from(
            self.predict(history[-2].pose, prev.pose, held) if len(history) >= 2
            else prev.pose.copy(), frame)
        try:
            res = self.track_frame(prev.pose, prev.frame, key, key_frame, pred, frame,
                                   set(prev.doubts), set(prev.flagged))
        except DegenerateSystem as e:
            return FrameResult(frame=frame, pose=pred, residual=float("nan"), iterations=0,
                               converged=False, diverged=True, reason=str(e))
        if res.diverged:
            return res
        if not all(np.isfinite(res.pose.rotations).flat):
            res.diverged, res.reason = True, "the solution is not finite"
        elif why := residual_jump(res.residual, residuals, self.settings):
            res.diverged, res.reason = True, why
        else:
            if self.hold_turn_in_depth:
                res.turned = turned_from(self._side_on_key, res.pose, self.sight)
            self._learn_backdrops(res)
        return res


def residual_jump(residual: float, residuals: list[float], settings: TrackerSettings) -> str:
    """Why a frame's ``residual`` says the fit broke, given the residuals of the tracked
    frames before it (finite ones, in order), or "" if it does not: over
    ``divergence_ratio`` times their median (floored at ``noise_floor``) and over
    ``divergence_jump`` times the lower of the last two. A lost fit breaks within a frame or
    two (a plate's camel slid off over two: 0.039, 0.068, 0.121); a residual that climbs
    over more is the body turning sides to the cameras that the key frame does not show (a
    walker turning on the spot: 0.017, 0.034, 0.038, 0.051)."""
    if not residuals:
        return ""
    median, before = float(np.median(residuals)), min(residuals[-2:])
    if residual <= settings.divergence_ratio * max(median, settings.noise_floor) or \
            residual <= settings.divergence_jump * before:
        return ""
    jump = (f" and {settings.divergence_jump:g}x the lower of the two frames' before "
            f"({before:.4f})") if settings.divergence_jump > 0 else ""
    return (f"residual {residual:.4f} is over {settings.divergence_ratio:g}x the median so far "
            f"({median:.4f}){jump}")


def held_joints(prev: FrameResult, side_on: bool) -> list[str]:
    """The joints the next frame predicts where they were on ``prev`` (``Tracker.predict``):
    its limbs no view saw, and those the limb search turned there on two or more views'
    evidence; tracked ``side_on``, the limbs it doubts there too. One view that disagrees with a
    limb (most often the far one, half behind the body) has given it no speed worth carrying
    on. With views from several sides a doubted limb keeps its speed: a shank swinging at 15
    fps is often in doubt and needs it."""
    doubt = (UNSEEN, UNSURE_FLAG) if side_on else (UNSEEN,)
    return [n for n, why in prev.doubts.items() if why in doubt] + prev.searched


def track(
    tracker: Tracker,
    initial: BodyPose,
    frames: Sequence[int],
    progress: Callable[[FrameResult, int, int], None] | None = None,
    cancel: Callable[[], bool] | None = None,
    corrections: Mapping[int, BodyPose] | None = None,
) -> TrackResult:
    """Run ``Tracker.iter_track`` to the end, calling ``progress(result, done, total)`` after
    each frame and stopping (keeping what was tracked) when ``cancel()`` returns True."""
    out = TrackResult()
    total = len(frames)
    for res in tracker.iter_track(initial, frames, corrections):
        out.frames.append(res)
        if progress:
            progress(res, len(out.frames), total)
        if cancel and cancel():
            out.cancelled = len(out.frames) < total
            break
    out.notes = list(tracker.notes)
    return out

"""Tracking on the scene: a run gathers the armature, views and footage, steps the core tracker
frame by frame and keys each tracked frame; the Track operator drives it (all at once from a
script, one frame per timer tick in the UI). Key Correction and Clear Track act on its keys.

Operator ids are a public contract: ``twist.track``, ``twist.key_correction``,
``twist.clear_track``."""

from __future__ import annotations

from dataclasses import dataclass, field

import bpy

from ..core.confidence import begun_list, frame_list
from ..core.frame_fit import FrameResult
from ..core.pose import BodyPose, world_pose
from ..core.tracker import (
    Tracker,
    doubts_begun,
    frames_to_check,
    frames_tracked,
    newly_flagged,
)
from . import checks, keyframes
from .armature_action import ArmatureAction
from .bridge import (
    BridgeError,
    camera_path,
    pose_from_armature,
    skeleton_from_armature,
    tracked_skeleton,
    tracking_mode,
    view_from_camera,
)
from .clip_lens import undistorted
from .errors import INPUT_ERRORS
from .properties import settings_from_properties
from .views import clean_plate, footage_frames


@dataclass
class TrackSession:
    """Everything one run needs, checked before the first frame is tracked. A frame after the
    first where the user keyed a tracked bone is a correction: its pose (as the scene shows
    it there) is taken as that frame's result and becomes the key frame later frames are held
    against, and the user's keys stay as they are."""

    armature: bpy.types.Object
    frames: list[int]
    tracker: Tracker
    initial: BodyPose
    user_keys: dict[int, frozenset[str]] = field(default_factory=dict)  # frame -> bones
    corrections: dict[int, BodyPose] = field(default_factory=dict)  # by index in ``frames``
    tracked: list[FrameResult] = field(default_factory=list)
    scene_notes: list[str] = field(default_factory=list)  # what the scene holds that the
    # tracker cannot use, or reads its own way (``clip_lens.undistorted``)

    @property
    def notes(self) -> list[str]:
        """What the user should know about the run: the scene's notes, then the tracker's."""
        return self.scene_notes + self.tracker.notes

    @classmethod
    def from_scene(cls, scene) -> TrackSession:
        tw = scene.twist
        arm = tw.armature
        if arm is None:
            raise BridgeError("no armature is set to track (Twist Mocap > Armature)")
        if not tw.views:
            raise BridgeError("there are no views; add a camera with its footage")
        cur = scene.frame_current
        if tw.direction == "FORWARD":
            frames = list(range(cur, scene.frame_end + 1))
        else:
            frames = list(range(cur, scene.frame_start - 1, -1))
        if len(frames) < 2:
            raise BridgeError(f"nothing to track {tw.direction.lower()} from frame {cur}")
        views, images, moving, plates, notes = [], [], [], [], []
        for v in tw.views:
            if v.camera is None:
                raise BridgeError("a view has no camera; pick its camera or remove the view")
            views.append(view_from_camera(v.camera, scene))
            footage, note = undistorted(v, footage_frames(v, frames))
            images.append(footage)
            notes += [note] if note else []
            moving.append(camera_path(v.camera, scene, frames))
            plates.append(clean_plate(v))
        mode = tracking_mode(scene, views, moving)
        sk = tracked_skeleton(arm)
        settings = settings_from_properties(tw.tracker)
        # the tracker indexes frames 0..n-1 in tracking order, the cameras' paths too
        tracker = Tracker(sk, images, mode, settings, moving, plates)
        user_keys = keyframes.user_keys(arm, sk)
        corrections = {}
        for i, f in enumerate(frames[1:], 1):
            if f in user_keys:
                scene.frame_set(f)
                corrections[i] = BodyPose(*pose_from_armature(arm, sk), views)
        scene.frame_set(cur)
        R, root = pose_from_armature(arm, sk)
        return cls(arm, frames, tracker, BodyPose(R, root, views), user_keys, corrections,
                   scene_notes=notes)

    def keep_start_pose(self, scene) -> None:
        """Key the first frame's pose (the user's) there, on the bones with no key there yet,
        and start from it as read back from those keys: the frame shows the user's pose
        after the run, and a second Track from it starts from the very same (float32) pose.
        The pose bones' own values are remembered for Clear Track."""
        arm, sk, cur = self.armature, self.tracker.given_skeleton, self.frames[0]
        keyframes.remember_pose(arm)
        keyed = keyframes.user_keys(arm, sk, any_type=True).get(cur, frozenset())
        keyframes.write_pose(arm, sk, cur, self.initial.rotations, self.initial.root_position,
                             keyed)
        scene.frame_set(cur)
        R, root = pose_from_armature(arm, sk)
        self.initial = BodyPose(R, root, self.initial.views)

    def frames_to_check(self) -> list[int]:
        """Scene frames tracked with a limb flagged."""
        return [self.frames[f] for f in frames_to_check(self.tracked)]

    def doubts_begun(self) -> dict[int, dict[str, str]]:
        """Scene frames where a limb's flag begins, and those flags (``doubts_begun``)."""
        return {self.frames[f]: flags for f, flags in doubts_begun(self.tracked).items()}

    def run(self, scene):
        """Yield after each frame is tracked and keyed, and marked on the timeline where a
        limb's flag begins (an earlier run's marker on the frame replaced): a limb in doubt
        stays flagged frame after frame, and a marker on each would bury the one to look
        at."""
        sk = self.tracker.given_skeleton  # the armature's joints, whatever side-on tracks
        steps = self.tracker.iter_track(self.initial, range(len(self.frames)),
                                        self.corrections)
        for res in steps:
            frame = self.frames[res.frame]
            if res.frame and not res.diverged:
                R, root = world_pose(self.tracker.mode, self.initial.views[0], res.pose)
                keyframes.write_pose(self.armature, sk, frame, R, root,
                                     self.user_keys.get(frame, frozenset()))
                checks.mark(scene, frame,
                            newly_flagged(self.tracked[-1] if self.tracked else None, res))
            self.tracked.append(res)
            yield res


def _summary(session: TrackSession, cancelled: bool) -> tuple[set, str]:
    diverged = [session.frames[r.frame] for r in session.tracked if r.diverged]
    msg = f"tracked {frames_tracked(session.tracked)} of {len(session.frames) - 1} frames"
    if cancelled:
        msg += " (stopped; the tracked frames are kept)"
    kept = [session.frames[i] for i in session.corrections
            if any(r.frame == i for r in session.tracked)]
    if kept:
        listed = ", ".join(map(str, kept)) if len(kept) <= 5 else \
            f"{', '.join(map(str, kept[:3]))} ... {kept[-1]}"
        msg += f"; {len(kept)} frame{'s' * (len(kept) > 1)} ({listed}) held at the pose you " \
               "keyed"
    notes = session.notes
    if notes:
        msg += "; " + "; ".join(notes)
    check = session.frames_to_check()
    if check:
        msg += (f"; check frame{'s' * (len(check) > 1)} {frame_list(check)}: a view disagrees "
                "with a limb (its pixels, or its bone off the silhouette) or no view sees it; "
                f"look first where the doubt begins (marked on the timeline): "
                f"{begun_list(session.doubts_begun())}")
    if diverged:
        last = session.tracked[-1]
        msg += f"; stopped at frame {diverged[0]}: {last.reason}. Pose the armature there, " \
               "Key Correction, and track again"
        return {"WARNING"}, msg
    return ({"WARNING"} if notes or check else {"INFO"}), msg


class TWIST_OT_track(ArmatureAction, bpy.types.Operator):
    """Track the armature through the footage of every view, keying each tracked frame"""

    bl_idname = "twist.track"
    bl_label = "Track"

    _timer = None
    _session = None
    _steps = None

    def _start(self, context) -> bool:
        try:
            self._session = TrackSession.from_scene(context.scene)
        except INPUT_ERRORS as e:
            self.report({"ERROR"}, str(e))
            return False
        self._session.keep_start_pose(context.scene)
        self._steps = self._session.run(context.scene)
        return True

    def _finish(self, context, cancelled: bool = False, error: str = "") -> set:
        """Report the run, fill the Results panel; FINISHED only when the run went through
        its frames (a diverged frame stops it with a warning). Stopped by Esc or by an input
        error, the frames tracked so far stay keyed, as one undo step of their own."""
        level, msg = _summary(self._session, cancelled or bool(error))
        self.report(level, msg)
        if error:
            self.report({"ERROR"}, error)
        result, tracked = context.scene.twist.result, self._session.tracked
        result.frames_tracked = frames_tracked(tracked)
        result.last_residual = tracked[-1].residual if len(tracked) > 1 else 0.0
        result.diverged_frames = ", ".join(
            f"{self._session.frames[r.frame]} ({r.reason})" for r in tracked if r.diverged)
        result.notes = "\n".join(self._session.notes)
        result.frames_to_check = frame_list(self._session.frames_to_check())
        result.doubts_begin = begun_list(self._session.doubts_begun())
        context.scene.frame_set(context.scene.frame_current)
        if not (cancelled or error):
            return {"FINISHED"}
        if len(tracked) > 1 and bpy.ops.ed.undo_push.poll():
            bpy.ops.ed.undo_push(message="Track (stopped)")
        return {"CANCELLED"}

    def execute(self, context):
        if not self._start(context):
            return {"CANCELLED"}
        try:
            for _ in self._steps:
                pass
        except INPUT_ERRORS as e:
            return self._finish(context, error=str(e))
        return self._finish(context)

    def invoke(self, context, event):
        if not self._start(context):
            return {"CANCELLED"}
        wm = context.window_manager
        wm.progress_begin(0, len(self._session.frames))
        self._timer = wm.event_timer_add(0.001, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type == "ESC":
            return self._end_modal(context, cancelled=True)
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        try:
            res = next(self._steps)
        except StopIteration:
            return self._end_modal(context)
        except INPUT_ERRORS as e:
            return self._end_modal(context, error=str(e))
        n = len(self._session.tracked)
        context.window_manager.progress_update(n)
        context.workspace.status_text_set(
            f"Tracking frame {self._session.frames[res.frame]} ({n} of "
            f"{len(self._session.frames)}), residual {res.residual:.3f} - Esc to stop")
        return {"RUNNING_MODAL"}

    def _end_modal(self, context, cancelled: bool = False, error: str = "") -> set:
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)
        return self._finish(context, cancelled, error)


class TWIST_OT_key_correction(ArmatureAction, bpy.types.Operator):
    """Key the armature's pose on this frame as a correction: Track holds the frame at this
    pose and holds the frames after it against it"""

    bl_idname = "twist.key_correction"
    bl_label = "Key Correction"

    def run(self, context) -> str:
        arm, frame = context.scene.twist.armature, context.scene.frame_current
        keyframes.key_correction(arm, tracked_skeleton(arm), frame)
        return f"keyed the pose of '{arm.name}' on frame {frame} as a correction; track again"


class TWIST_OT_clear_track(ArmatureAction, bpy.types.Operator):
    """Remove the keyframes tracking wrote on the armature, and no other, and its frames-to-
    check markers, and give the bones back the pose they had before Track"""

    bl_idname = "twist.clear_track"
    bl_label = "Clear Track"

    def run(self, context) -> str:
        arm = context.scene.twist.armature
        n = keyframes.clear(arm, skeleton_from_armature(arm))
        keyframes.restore_pose(arm)
        checks.unmark(context.scene)
        context.scene.twist.result.frames_to_check = ""
        context.scene.twist.result.doubts_begin = ""
        context.scene.frame_set(context.scene.frame_current)  # user keys decide where left
        return f"removed {n} tracked keyframes from '{arm.name}'"


def draw_pose_menu_entry(self, context):
    """Key Correction in pose mode's right-click menu, beside Insert Keyframe, for the
    armature being tracked."""
    if context.object is not None and context.object == context.scene.twist.armature:
        self.layout.separator()
        self.layout.operator(TWIST_OT_key_correction.bl_idname, icon="KEY_HLT")


def register():
    bpy.types.VIEW3D_MT_pose_context_menu.append(draw_pose_menu_entry)


def unregister():
    bpy.types.VIEW3D_MT_pose_context_menu.remove(draw_pose_menu_entry)


CLASSES = (TWIST_OT_track, TWIST_OT_key_correction, TWIST_OT_clear_track)

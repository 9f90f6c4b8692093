"""Operators: Track (modal on a timer in the UI, synchronous from scripts) and Clear Track.

Operator ids are a public contract: ``twist.track`` and ``twist.clear_track``.
"""

from __future__ import annotations

import bpy

from ..core.image import ImageError
from ..core.job import JobError
from .bridge import BridgeError, skeleton_from_armature
from .keyframes import clear
from .track import TrackSession

_EXPECTED = (BridgeError, ImageError, JobError, ValueError)


def _summary(session: TrackSession, cancelled: bool) -> tuple[set, str]:
    done = [r for r in session.tracked[1:] if not r.diverged]
    diverged = [session.frames[r.frame] for r in session.tracked if r.diverged]
    msg = f"tracked {len(done)} of {len(session.frames) - 1} frames"
    if cancelled:
        msg += " (cancelled; the tracked frames are kept)"
    if diverged:
        last = session.tracked[-1]
        msg += f"; stopped at frame {diverged[0]}: {last.reason}. Correct the pose there " \
               "and track again from it"
        return {"WARNING"}, msg
    return {"INFO"}, msg


class TWIST_OT_track(bpy.types.Operator):
    """Track the armature through the footage of every view, keying each tracked frame"""

    bl_idname = "twist.track"
    bl_label = "Track"
    bl_options = {"REGISTER", "UNDO"}

    _timer = None
    _session = None
    _steps = None

    @classmethod
    def poll(cls, context):
        return context.scene is not None and context.scene.twist.armature is not None

    def _start(self, context) -> bool:
        try:
            self._session = TrackSession.from_scene(context.scene)
        except _EXPECTED as e:
            self.report({"ERROR"}, str(e))
            return False
        self._steps = self._session.run()
        return True

    def _finish(self, context, cancelled: bool) -> set:
        level, msg = _summary(self._session, cancelled)
        self.report(level, msg)
        context.scene.frame_set(context.scene.frame_current)
        return {"FINISHED"}

    def execute(self, context):
        if not self._start(context):
            return {"CANCELLED"}
        try:
            for _ in self._steps:
                pass
        except _EXPECTED as e:
            self.report({"ERROR"}, str(e))
        return self._finish(context, cancelled=False)

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
            return self._end_modal(context, cancelled=False)
        except _EXPECTED as e:
            self.report({"ERROR"}, str(e))
            return self._end_modal(context, cancelled=True)
        n = len(self._session.tracked)
        context.window_manager.progress_update(n)
        context.workspace.status_text_set(
            f"Tracking frame {self._session.frames[res.frame]} ({n} of "
            f"{len(self._session.frames)}), residual {res.residual:.3f} - Esc to stop")
        return {"RUNNING_MODAL"}

    def _end_modal(self, context, cancelled: bool) -> set:
        wm = context.window_manager
        wm.event_timer_remove(self._timer)
        wm.progress_end()
        context.workspace.status_text_set(None)
        return self._finish(context, cancelled)


class TWIST_OT_clear_track(bpy.types.Operator):
    """Remove the keyframes tracking wrote on the armature, and no other"""

    bl_idname = "twist.clear_track"
    bl_label = "Clear Track"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return context.scene is not None and context.scene.twist.armature is not None

    def execute(self, context):
        arm = context.scene.twist.armature
        try:
            n = clear(arm, skeleton_from_armature(arm))
        except BridgeError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        self.report({"INFO"}, f"removed {n} tracked keyframes from '{arm.name}'")
        return {"FINISHED"}


CLASSES = (TWIST_OT_track, TWIST_OT_clear_track)

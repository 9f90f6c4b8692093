"""Operators: Track (modal on a timer in the UI, synchronous from scripts), Clear Track, and
adding views and template armatures.

Operator ids are a public contract: ``twist.track``, ``twist.clear_track``,
``twist.add_template_armature``, ``twist.add_view`` and ``twist.remove_view``.
"""

from __future__ import annotations

import glob
from pathlib import Path

import bpy

from ..core.video import is_video
from .bridge import armature_from_skeleton, skeleton_from_armature, tracked_skeleton
from .keyframes import clear, key_correction
from .properties import first_frame_property
from .reporting import EXPECTED, ArmatureAction
from .track import TrackSession


def _summary(session: TrackSession, cancelled: bool) -> tuple[set, str]:
    done = [r for r in session.tracked[1:] if not r.diverged]
    diverged = [session.frames[r.frame] for r in session.tracked if r.diverged]
    msg = f"tracked {len(done)} of {len(session.frames) - 1} frames"
    if cancelled:
        msg += " (cancelled; the tracked frames are kept)"
    kept = [session.frames[i] for i in session.corrections
            if any(r.frame == i for r in session.tracked)]
    if kept:
        listed = ", ".join(map(str, kept)) if len(kept) <= 5 else \
            f"{', '.join(map(str, kept[:3]))} ... {kept[-1]}"
        msg += f"; {len(kept)} frame{'s' * (len(kept) > 1)} ({listed}) held at the pose you " \
               "keyed"
    notes = session.tracker.notes
    if notes:
        msg += "; " + "; ".join(notes)
    if diverged:
        last = session.tracked[-1]
        msg += f"; stopped at frame {diverged[0]}: {last.reason}. Pose the armature there, " \
               "Key Correction, and track again"
        return {"WARNING"}, msg
    return ({"WARNING"} if notes else {"INFO"}), msg


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
        except EXPECTED as e:
            self.report({"ERROR"}, str(e))
            return False
        self._steps = self._session.run()
        return True

    def _finish(self, context, cancelled: bool) -> set:
        level, msg = _summary(self._session, cancelled)
        self.report(level, msg)
        result, tracked = context.scene.twist.result, self._session.tracked
        result.frames_tracked = sum(1 for r in tracked[1:] if not r.diverged)
        result.last_residual = tracked[-1].residual if len(tracked) > 1 else 0.0
        result.diverged_frames = ", ".join(
            f"{self._session.frames[r.frame]} ({r.reason})" for r in tracked if r.diverged)
        result.notes = "\n".join(self._session.tracker.notes)
        context.scene.frame_set(context.scene.frame_current)
        return {"FINISHED"}

    def execute(self, context):
        if not self._start(context):
            return {"CANCELLED"}
        try:
            for _ in self._steps:
                pass
        except EXPECTED as e:
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
        except EXPECTED as e:
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


class TWIST_OT_key_correction(ArmatureAction, bpy.types.Operator):
    """Key the armature's pose on this frame as a correction: Track holds the frame at this
    pose and holds the frames after it against it"""

    bl_idname = "twist.key_correction"
    bl_label = "Key Correction"

    def run(self, context) -> str:
        arm, frame = context.scene.twist.armature, context.scene.frame_current
        key_correction(arm, tracked_skeleton(arm), frame)
        return f"keyed the pose of '{arm.name}' on frame {frame} as a correction; track again"


class TWIST_OT_clear_track(ArmatureAction, bpy.types.Operator):
    """Remove the keyframes tracking wrote on the armature, and no other"""

    bl_idname = "twist.clear_track"
    bl_label = "Clear Track"

    def run(self, context) -> str:
        arm = context.scene.twist.armature
        n = clear(arm, skeleton_from_armature(arm))
        return f"removed {n} tracked keyframes from '{arm.name}'"


# name: (label, description, core template function, its arguments)
TEMPLATES = {
    "HUMAN": ("Human (19 degrees of freedom)", "The paper's body: ball hips, shoulders and "
              "neck; hinge knees and elbows, bending one way", "human_template", {}),
    "HUMAN_LOWER_BACK": ("Human, lower back free (22)", "The human with its spine a ball too, "
                         "so that the pelvis turns against the chest: better for a walker "
                         "seen in several views, worse in one", "human_template",
                         {"lower_back": True}),
    "WALKER": ("Walker (6, from the side)", "Hinge hips, knees and ankles turning in the view's "
               "plane", "walker_template", {}),
    "QUADRUPED": ("Quadruped (planar)", "Trunk, neck, head and four two-joint legs, all "
                  "turning in the view's plane", "planar_quadruped_template", {}),
}


class TWIST_OT_add_template_armature(bpy.types.Operator):
    """Add an armature for tracking, its bones locked to the template's hinges and balls"""

    bl_idname = "twist.add_template_armature"
    bl_label = "Add Template Armature"
    bl_options = {"REGISTER", "UNDO"}

    template: bpy.props.EnumProperty(
        name="Template", description="The body to track",
        items=[(k, v[0], v[1]) for k, v in TEMPLATES.items()])

    def execute(self, context):
        from ..core import skeleton

        _, _, build, kwargs = TEMPLATES[self.template]
        sk = getattr(skeleton, build)(**kwargs)
        if context.object and context.object.mode != "OBJECT":
            bpy.ops.object.mode_set(mode="OBJECT")
        arm = armature_from_skeleton(sk, self.template.replace("_", " ").title(),
                                     context.collection)
        context.scene.twist.armature = arm
        self.report({"INFO"}, f"added '{arm.name}': {len(sk.dof_names())} degrees of freedom")
        return {"FINISHED"}


class TWIST_OT_add_view(bpy.types.Operator):
    """Add a view: an orthographic camera with the footage behind it, one image per frame"""

    bl_idname = "twist.add_view"
    bl_label = "Add View"
    bl_options = {"REGISTER", "UNDO"}

    filepath: bpy.props.StringProperty(
        name="Footage", subtype="FILE_PATH",
        description="A movie, or any image of the footage: its folder's images of the same "
                    "kind are read in name order")
    first_frame: first_frame_property()

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        path = Path(bpy.path.abspath(self.filepath))
        if not path.is_file():
            self.report({"ERROR"}, f"{self.filepath}: no such image or movie file")
            return {"CANCELLED"}
        movie = is_video(path)
        pattern = str(path) if movie else str(path.parent / f"*{path.suffix}")
        scene = context.scene
        n = len(scene.twist.views) + 1
        cam_data = bpy.data.cameras.new(f"View {n}")
        cam_data.type = "ORTHO"
        cam_data.show_background_images = True
        cam = bpy.data.objects.new(f"View {n}", cam_data)
        context.collection.objects.link(cam)
        cam.location = (0.0, -10.0, 1.0)
        cam.rotation_euler = (1.5707963, 0.0, 0.0)  # looking along +y, z up: a side view
        bg = cam_data.background_images.new()
        bg.frame_method = "FIT"
        if movie:
            clip = bpy.data.movieclips.load(str(path), check_existing=True)
            clip.frame_start = self.first_frame
            bg.source, bg.clip = "MOVIE_CLIP", clip
            count, (img_w, img_h) = clip.frame_duration, clip.size
        else:
            count = len(glob.glob(pattern))
            image = bpy.data.images.load(str(path), check_existing=True)
            img_w, img_h = image.size  # a sequence reports no size until it is shown
            image.source = "SEQUENCE" if count > 1 else "FILE"
            bg.image = image
            bg.image_user.frame_start = self.first_frame
            bg.image_user.frame_duration = count
        if img_w and img_h and n == 1:
            scene.render.resolution_x, scene.render.resolution_y = img_w, img_h
        view = scene.twist.views.add()
        view.camera = cam
        view.images = bpy.path.relpath(pattern) if bpy.data.filepath else pattern
        view.first_frame = self.first_frame
        scene.twist.active_view = len(scene.twist.views) - 1
        self.report({"INFO"}, f"added '{cam.name}' with {count} frames")
        return {"FINISHED"}


class TWIST_OT_remove_view(bpy.types.Operator):
    """Remove the selected view (its camera stays in the scene)"""

    bl_idname = "twist.remove_view"
    bl_label = "Remove View"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return len(context.scene.twist.views) > 0

    def execute(self, context):
        tw = context.scene.twist
        tw.views.remove(tw.active_view)
        tw.active_view = max(0, min(tw.active_view, len(tw.views) - 1))
        return {"FINISHED"}


def _pose_menu(self, context):
    """Key Correction in pose mode's right-click menu, beside Insert Keyframe, for the
    armature being tracked."""
    if context.object is not None and context.object == context.scene.twist.armature:
        self.layout.separator()
        self.layout.operator(TWIST_OT_key_correction.bl_idname, icon="KEY_HLT")


def register():
    bpy.types.VIEW3D_MT_pose_context_menu.append(_pose_menu)


def unregister():
    bpy.types.VIEW3D_MT_pose_context_menu.remove(_pose_menu)


CLASSES = (TWIST_OT_track, TWIST_OT_key_correction, TWIST_OT_clear_track,
           TWIST_OT_add_template_armature,
           TWIST_OT_add_view, TWIST_OT_remove_view)

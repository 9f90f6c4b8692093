"""Joint markers: placed by clicking on a view's footage (the paper's initialisation from
clicked joints), stored per view and frame, and drawn over the viewport.

A marker is the pixel (x right, y down, origin at the top-left pixel's centre) of a bone's
head on one view's footage at one frame, or of the tail of a bone that ends a limb (no bone
hangs from it: a hoof, a hand), stored under the name ``"<bone>/end"``. Placing markers
goes through the bones in order, and from a bone that ends a limb to its tail before the
next bone.
"""

from __future__ import annotations

import bpy
import numpy as np

from .bridge import BridgeError, view_from_camera


def set_marker(view, bone: str, frame: int, x: float, y: float) -> None:
    """Place (or move) ``bone``'s marker of ``frame`` in ``view`` (a scene view item)."""
    m = next((m for m in view.markers if m.bone == bone and m.frame == frame), None)
    if m is None:
        m = view.markers.add()
        m.bone, m.frame = bone, frame
    m.x, m.y = x, y


def markers_at(view, frame: int) -> dict[str, np.ndarray]:
    """Bone -> pixel (2,) of the view's markers on ``frame``."""
    return {m.bone: np.array([m.x, m.y]) for m in view.markers if m.frame == frame}


def view_of_camera(scene, cam):
    """The scene's view item seen through ``cam``, or None."""
    return next((v for v in scene.twist.views if v.camera == cam), None)


def pixel_of_point(cam, scene, point) -> np.ndarray:
    """The footage pixel under a world point seen through the orthographic ``cam`` (a click
    turned into the 3D point under the mouse lands on the pixel it was made on)."""
    return view_from_camera(cam, scene).project(np.asarray(point, float))


def point_of_pixel(cam, scene, pixels, depth_point) -> np.ndarray:
    """The world points (..., 3) on the rays of ``pixels`` (..., 2) through ``cam`` nearest
    to ``depth_point`` (where to draw markers so that they sit among the bones)."""
    origin, d = view_from_camera(cam, scene).ray(np.asarray(pixels, float))
    along = np.sum((np.asarray(depth_point, float) - origin) * d, axis=-1, keepdims=True)
    return origin + d * along


def next_bone(arm, bone: str) -> str:
    """The bone after ``bone`` in the armature's order (wrapping round)."""
    names = [b.name for b in arm.data.bones]
    return names[(names.index(bone) + 1) % len(names)] if bone in names else names[0]


def marker_name(bone: str, tip: bool) -> str:
    """What a marker of ``bone``'s head (or its tail, ``tip``) is stored as."""
    return f"{bone}/end" if tip else bone


def next_target(arm, bone: str, tip: bool) -> tuple[str, bool]:
    """What the click after marking ``bone`` (its head, or its tail when ``tip``) marks: the
    tail of a bone that ends a limb after its head, else the next bone's head."""
    b = arm.data.bones.get(bone)
    if not tip and b is not None and not b.children:
        return bone, True
    return next_bone(arm, bone), False


class TWIST_OT_place_markers(bpy.types.Operator):
    """Click joints on the footage: looking through a view's camera, each click places the
    marker of the bone chosen in the panel (its head, or its tip) on the current frame and
    moves on: to the tip of a bone that ends a limb, else to the next bone. Right-click or
    Esc finishes, Backspace skips one"""

    bl_idname = "twist.place_markers"
    bl_label = "Place Markers"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        tw = context.scene.twist
        return tw.armature is not None and context.area is not None and \
            context.area.type == "VIEW_3D"

    def _status(self, context):
        tw = context.scene.twist
        context.workspace.status_text_set(
            f"Click the {'tip' if tw.marker_tip else 'head'} of '{tw.marker_bone}' on the "
            "footage - Backspace: skip, Right-click or Esc: finish")

    @staticmethod
    def _advance(tw) -> None:
        tw.marker_bone, tw.marker_tip = next_target(tw.armature, tw.marker_bone,
                                                    tw.marker_tip)

    def invoke(self, context, event):
        scene = context.scene
        tw = scene.twist
        rv3d = context.region_data
        if rv3d is None or rv3d.view_perspective != "CAMERA" or \
                view_of_camera(scene, scene.camera) is None:
            self.report({"ERROR"}, "look through a view's camera (set it active, Numpad 0) "
                                   "to place markers on its footage")
            return {"CANCELLED"}
        if tw.marker_bone not in tw.armature.data.bones:
            tw.marker_bone = tw.armature.data.bones[0].name
        self._status(context)
        context.window_manager.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        from bpy_extras import view3d_utils

        scene = context.scene
        tw = scene.twist
        if event.type in {"RIGHTMOUSE", "ESC"} and event.value == "PRESS":
            context.workspace.status_text_set(None)
            return {"FINISHED"}
        if event.type == "BACK_SPACE" and event.value == "PRESS":
            self._advance(tw)
            self._status(context)
            return {"RUNNING_MODAL"}
        if event.type == "LEFTMOUSE" and event.value == "PRESS":
            cam = scene.camera
            view = view_of_camera(scene, cam)
            if view is None or context.region_data.view_perspective != "CAMERA":
                return {"PASS_THROUGH"}
            point = view3d_utils.region_2d_to_location_3d(
                context.region, context.region_data, (event.mouse_region_x,
                                                      event.mouse_region_y),
                cam.matrix_world.translation)
            try:
                x, y = pixel_of_point(cam, scene, point)
            except BridgeError as e:
                self.report({"ERROR"}, str(e))
                return {"CANCELLED"}
            set_marker(view, marker_name(tw.marker_bone, tw.marker_tip), scene.frame_current,
                       x, y)
            self._advance(tw)
            self._status(context)
            context.area.tag_redraw()
            return {"RUNNING_MODAL"}
        return {"PASS_THROUGH"}  # navigate, change frames, scroll


class TWIST_OT_clear_markers(bpy.types.Operator):
    """Remove the markers of the current frame from every view"""

    bl_idname = "twist.clear_markers"
    bl_label = "Clear Markers"
    bl_options = {"REGISTER", "UNDO"}

    def execute(self, context):
        scene = context.scene
        removed = 0
        for v in scene.twist.views:
            for i in reversed(range(len(v.markers))):
                if v.markers[i].frame == scene.frame_current:
                    v.markers.remove(i)
                    removed += 1
        self.report({"INFO"}, f"removed {removed} markers of frame {scene.frame_current}")
        return {"FINISHED"}


CLASSES = (TWIST_OT_place_markers, TWIST_OT_clear_markers)

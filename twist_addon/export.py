"""Exporting the tracked motion: BVH and FBX through Blender's own exporters, also from
File > Export. Scripted, they take ``filepath`` and act on the active armature (or, when the
active object is not one, the scene's tracked armature) over the scene's frame range."""

from __future__ import annotations

import os
from pathlib import Path

import bpy
from bpy_extras.io_utils import ExportHelper

from .bridge import BridgeError
from .keyframes import channelbag


def _armature(context, name: str = ""):
    """The armature named, else the active object if an armature (as Blender's exporters
    act on what is selected), else the tracked one."""
    if name:
        obj = bpy.data.objects.get(name)
        return obj if obj is not None and obj.type == "ARMATURE" else None
    active = context.active_object
    if active is not None and active.type == "ARMATURE":
        return active
    return context.scene.twist.armature


def _frame_range(arm, scene, only_cycle: bool) -> tuple[int, int]:
    """The scene's frame range, or with ``only_cycle`` the span of the armature's keys that
    Make Walk Cycle left (the cycle repeats past them)."""
    if not only_cycle:
        return scene.frame_start, scene.frame_end
    bag = channelbag(arm)
    if bag is None:
        raise BridgeError(f"'{arm.name}' has no animation to export")
    cycled = [fc for fc in bag.fcurves if any(m.type == "CYCLES" for m in fc.modifiers)]
    if not cycled:
        raise BridgeError(f"'{arm.name}' has no cycle: use Make Walk Cycle first")
    keys = [kp.co[0] for fc in cycled for kp in fc.keyframe_points]
    return int(round(min(keys))), int(round(max(keys))) - 1  # the last key closes the loop



def _check_path(filepath: str, ext: str) -> None:
    """BridgeError unless ``filepath`` names a file in a folder that exists and can be
    written (checked before the scene is touched)."""
    if not filepath:
        raise BridgeError(f"no file to export to: give a file path ending in {ext}")
    path = Path(bpy.path.abspath(filepath))
    if path.is_dir() or not path.name:
        raise BridgeError(f"{filepath} is a folder: give a file name ending in {ext}")
    if not path.parent.is_dir():
        raise BridgeError(f"the folder {path.parent} does not exist: create it, or export "
                          "to another")
    if not os.access(path.parent, os.W_OK):
        raise BridgeError(f"cannot write into {path.parent} (no permission)")


def _select_only(context, obj) -> None:
    if context.object and context.object.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")
    for o in context.view_layer.objects:
        o.select_set(False)
    obj.select_set(True)
    context.view_layer.objects.active = obj


class _Export(ExportHelper):
    bl_options = {"REGISTER"}

    armature: bpy.props.StringProperty(
        name="Armature", description="The armature to export, by name (empty: the active "
                                     "armature, else the tracked one)")
    only_cycle: bpy.props.BoolProperty(
        name="Only One Cycle", default=False,
        description="Export just the walk cycle's frames instead of the scene's range")

    @classmethod
    def poll(cls, context):
        return _armature(context) is not None

    def execute(self, context):
        arm = _armature(context, self.armature)
        if arm is None:
            self.report({"ERROR"}, f"no armature '{self.armature}' to export" if self.armature
                        else "no armature to export: select one, or set Twist Mocap > "
                        "Armature")
            return {"CANCELLED"}
        try:
            _check_path(self.filepath, self.filename_ext)
            first, last = _frame_range(arm, context.scene, self.only_cycle)
        except BridgeError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        layer = context.view_layer
        selected, active = [o for o in layer.objects if o.select_get()], layer.objects.active
        _select_only(context, arm)
        scene = context.scene
        kept = scene.frame_start, scene.frame_end
        scene.frame_start, scene.frame_end = first, last
        try:
            result = self.export(context, scene)
        finally:  # the user's frame range and selection, as they were
            scene.frame_start, scene.frame_end = kept
            for o in layer.objects:
                o.select_set(o in selected)
            layer.objects.active = active
        if result == {"FINISHED"}:
            self.report({"INFO"}, f"exported '{arm.name}' frames {first}-{last} to "
                                  f"{self.filepath}")
        return result


class TWIST_OT_export_bvh(_Export, bpy.types.Operator):
    """Export the tracked armature's motion as BVH, one frame per scene frame"""

    bl_idname = "twist.export_bvh"
    bl_label = "Export Tracked Motion (.bvh)"
    filename_ext = ".bvh"
    filter_glob: bpy.props.StringProperty(default="*.bvh", options={"HIDDEN"})

    def export(self, context, scene):
        return bpy.ops.export_anim.bvh(filepath=self.filepath, frame_start=scene.frame_start,
                                       frame_end=scene.frame_end, rotate_mode="NATIVE")


class TWIST_OT_export_fbx(_Export, bpy.types.Operator):
    """Export the tracked armature as FBX the way game engines expect: deform bones only, the
    animation baked into one action at the scene's frame rate and range, no leaf bones"""

    bl_idname = "twist.export_fbx"
    bl_label = "Export Tracked Motion (.fbx)"
    filename_ext = ".fbx"
    filter_glob: bpy.props.StringProperty(default="*.fbx", options={"HIDDEN"})

    def export(self, context, scene):
        return bpy.ops.export_scene.fbx(
            filepath=self.filepath, use_selection=True, object_types={"ARMATURE"},
            use_armature_deform_only=True, add_leaf_bones=False, bake_anim=True,
            bake_anim_use_all_actions=False, bake_anim_use_nla_strips=False,
            bake_anim_simplify_factor=0.0,
            bake_anim_force_startend_keying=True)


def _menu(self, context):
    self.layout.operator(TWIST_OT_export_bvh.bl_idname, text="Twist Mocap Motion (.bvh)")
    self.layout.operator(TWIST_OT_export_fbx.bl_idname, text="Twist Mocap Motion (.fbx)")


CLASSES = (TWIST_OT_export_bvh, TWIST_OT_export_fbx)


def register():
    bpy.types.TOPBAR_MT_file_export.append(_menu)


def unregister():
    bpy.types.TOPBAR_MT_file_export.remove(_menu)

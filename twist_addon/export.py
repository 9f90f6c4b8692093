"""Exporting the tracked motion: BVH and FBX through Blender's own exporters, also from
File > Export. Scripted, they take ``filepath`` and act on the scene's tracked armature (or the
active armature) over the scene's frame range."""

from __future__ import annotations

import bpy
from bpy_extras.io_utils import ExportHelper


def _armature(context):
    arm = context.scene.twist.armature
    if arm is None and context.active_object and context.active_object.type == "ARMATURE":
        arm = context.active_object
    return arm


def _select_only(context, obj) -> None:
    if context.object and context.object.mode != "OBJECT":
        bpy.ops.object.mode_set(mode="OBJECT")
    for o in context.view_layer.objects:
        o.select_set(False)
    obj.select_set(True)
    context.view_layer.objects.active = obj


class _Export(ExportHelper):
    bl_options = {"REGISTER"}

    @classmethod
    def poll(cls, context):
        return _armature(context) is not None

    def execute(self, context):
        arm = _armature(context)
        if arm is None:
            self.report({"ERROR"}, "no armature to export: set Twist Mocap > Armature")
            return {"CANCELLED"}
        _select_only(context, arm)
        result = self.export(context, context.scene)
        if result == {"FINISHED"}:
            self.report({"INFO"}, f"exported '{arm.name}' to {self.filepath}")
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

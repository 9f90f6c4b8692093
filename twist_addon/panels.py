"""The sidebar tab in the 3D viewport, in the order of the work: footage and views, armature,
track (settings folded away), results, and what to make of them (animation, with the
retargeting bone map folded away)."""

from __future__ import annotations

import dataclasses
import textwrap

import bpy

from ..core.settings import TrackerSettings

_MAIN_SETTINGS = ("side_on", "levels", "iterations", "key_weight")  # side-on: one view
NOTE_WIDTH = 40  # characters a line of the Results panel's notes (the sidebar's own width)


class TWIST_UL_views(bpy.types.UIList):
    """One row per view: its camera and footage."""

    def draw_item(self, context, layout, data, item, icon, active_data, active_propname):
        row = layout.row(align=True)
        row.prop(item, "camera", text="", icon="CAMERA_DATA")
        row.prop(item, "images", text="")


class TWIST_UL_bone_map(bpy.types.UIList):
    """One row per bone pair: tracked bone, then the target bone that copies it."""

    def draw_item(self, context, layout, data, item, icon, active_data, active_propname):
        row = layout.row(align=True)
        row.prop(item, "source", text="", emboss=False, icon="BONE_DATA")
        row.label(icon="FORWARD")
        row.prop(item, "target", text="", emboss=False)


class _TwistPanel:
    bl_space_type = "VIEW_3D"
    bl_region_type = "UI"
    bl_category = "Twist Mocap"


class TWIST_PT_views(_TwistPanel, bpy.types.Panel):
    bl_label = "Footage & Views"

    def draw(self, context):
        tw = context.scene.twist
        layout = self.layout
        row = layout.row()
        row.template_list("TWIST_UL_views", "", tw, "views", tw, "active_view", rows=3)
        col = row.column(align=True)
        col.operator("twist.add_view", icon="ADD", text="")
        col.operator("twist.remove_view", icon="REMOVE", text="")
        col.separator()
        col.operator("twist.add_plate_view", icon="IMAGE_DATA", text="")
        col.operator("twist.add_calibrated_views", icon="OUTLINER_OB_CAMERA", text="")
        if tw.views:
            view = tw.views[tw.active_view]
            layout.prop(view, "first_frame")
            layout.prop(view, "backdrop")
        layout.prop(tw, "mode")


class TWIST_PT_armature(_TwistPanel, bpy.types.Panel):
    bl_label = "Armature"

    def draw(self, context):
        tw = context.scene.twist
        layout = self.layout
        layout.prop(tw, "armature")
        layout.prop(tw, "show_overlay")
        box = layout.box()
        if tw.armature is not None:
            row = box.row(align=True)
            row.prop_search(tw, "marker_bone", tw.armature.data, "bones")
            row.prop(tw, "marker_tip", toggle=True)
        row = box.row(align=True)
        row.operator("twist.place_markers", icon="RESTRICT_SELECT_OFF")
        row.operator("twist.clear_markers", icon="X", text="")
        row = box.row(align=True)
        row.operator("twist.import_markers", icon="IMPORT")
        row.operator("twist.fit_pose", icon="CON_KINEMATIC")
        box.operator("twist.fit_pose", text="Fit Pose and Bone Lengths",
                        icon="CON_KINEMATIC").fit_lengths = True
        layout.operator_menu_enum("twist.add_template_armature", "template", icon="ARMATURE_DATA")
        row = layout.row(align=True)
        row.operator("twist.make_hinges", icon="CON_ROTLIMIT")
        row.operator("twist.size_blobs", icon="MESH_UVSPHERE")


class TWIST_PT_track(_TwistPanel, bpy.types.Panel):
    bl_label = "Track"

    def draw(self, context):
        tw = context.scene.twist
        layout = self.layout
        layout.prop(tw, "direction", expand=True)
        row = layout.row(align=True)
        row.scale_y = 1.4
        row.operator("twist.track", icon="TRACKING")
        row = layout.row(align=True)
        row.operator("twist.key_correction", icon="KEY_HLT")
        row.operator("twist.clear_track", icon="X")
        layout.operator("twist.refine_skeleton", icon="BONE_DATA")


class TWIST_PT_track_settings(_TwistPanel, bpy.types.Panel):
    bl_label = "Settings"
    bl_parent_id = "TWIST_PT_track"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        settings = context.scene.twist.tracker
        layout = self.layout
        layout.use_property_split = True
        for name in _MAIN_SETTINGS:
            layout.prop(settings, name)
        col = layout.column(heading="Advanced")
        for f in dataclasses.fields(TrackerSettings):
            if f.name not in _MAIN_SETTINGS:
                col.prop(settings, f.name)


class TWIST_PT_results(_TwistPanel, bpy.types.Panel):
    bl_label = "Results"

    def draw(self, context):
        result = context.scene.twist.result
        layout = self.layout
        layout.prop(result, "frames_tracked")
        layout.prop(result, "last_residual")
        if result.diverged_frames:
            layout.label(text="Stopped at frame " + result.diverged_frames, icon="ERROR")
        if result.frames_to_check:
            col = layout.column(align=True)
            for i, line in enumerate(textwrap.wrap("Check frames " + result.frames_to_check,
                                                   NOTE_WIDTH)):
                col.label(text=line, icon="ERROR" if i == 0 else "BLANK1")
            for line in textwrap.wrap("Look first where doubt begins: " + result.doubts_begin,
                                      NOTE_WIDTH):
                col.label(text=line, icon="BLANK1")
            row = layout.row(align=True)
            row.operator("screen.marker_jump", text="Previous", icon="TRIA_LEFT").next = False
            row.operator("screen.marker_jump", text="Next", icon="TRIA_RIGHT").next = True
        for note in result.notes.splitlines():
            col = layout.column(align=True)
            for i, line in enumerate(textwrap.wrap(note, NOTE_WIDTH, break_on_hyphens=False)):
                col.label(text=line, icon="INFO" if i == 0 else "BLANK1")


class TWIST_PT_animation(_TwistPanel, bpy.types.Panel):
    bl_label = "Animation"

    def draw(self, context):
        layout = self.layout
        col = layout.column(align=True)
        col.operator("twist.smooth_track", icon="SMOOTHCURVE")
        col.operator("twist.make_cycle", icon="FILE_REFRESH")
        layout.operator("twist.add_volumetric_body", icon="MESH_UVSPHERE")
        layout.operator("twist.retarget", icon="ARMATURE_DATA")
        row = layout.row(align=True)
        row.operator("twist.export_bvh", text="BVH", icon="EXPORT")
        row.operator("twist.export_fbx", text="FBX", icon="EXPORT")


class TWIST_PT_bone_map(_TwistPanel, bpy.types.Panel):
    bl_label = "Bone Map"
    bl_parent_id = "TWIST_PT_animation"
    bl_options = {"DEFAULT_CLOSED"}

    def draw(self, context):
        tw = context.scene.twist
        layout = self.layout
        row = layout.row()
        row.template_list("TWIST_UL_bone_map", "", tw, "bone_map", tw, "active_bone_pair",
                          rows=4)
        col = row.column(align=True)
        col.operator("twist.edit_bone_map", icon="ADD", text="").action = "ADD"
        col.operator("twist.edit_bone_map", icon="REMOVE", text="").action = "REMOVE"
        layout.operator("twist.load_bone_map", icon="PRESET")


CLASSES = (TWIST_UL_views, TWIST_UL_bone_map, TWIST_PT_views, TWIST_PT_armature,
           TWIST_PT_track, TWIST_PT_track_settings, TWIST_PT_results, TWIST_PT_animation,
           TWIST_PT_bone_map)

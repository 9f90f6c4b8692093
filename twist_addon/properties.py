"""What the scene keeps for tracking: the armature, the views, the direction, the settings.

The tracker settings mirror ``core.settings.TrackerSettings`` field by field, with its
documentation as tooltips, so that a new setting in core appears here without a second list.
"""

from __future__ import annotations

import dataclasses

import bpy

from ..core.pose import CALIBRATED, INDEPENDENT
from ..core.settings import TrackerSettings

_LIMITS = {  # soft ranges for the sliders; core validates the hard ones
    "levels": (1, 6), "iterations": (1, 50), "pixel_step": (1, 8), "max_step": (0.5, 90.0),
}


def _property(f: dataclasses.Field):
    kw = {"name": f.name.replace("_", " ").capitalize(), "description": f.metadata["doc"],
          "default": f.default}
    if isinstance(f.default, bool):
        return bpy.props.BoolProperty(**kw)
    lo, hi = _LIMITS.get(f.name, (0, None))
    if isinstance(f.default, int):
        return bpy.props.IntProperty(min=lo, soft_max=hi or 100, **kw)
    return bpy.props.FloatProperty(min=lo, soft_max=hi or 100.0, precision=3, **kw)


TWIST_PG_tracker_settings = type(
    "TWIST_PG_tracker_settings",
    (bpy.types.PropertyGroup,),
    {"__annotations__": {f.name: _property(f) for f in dataclasses.fields(TrackerSettings)},
     "__doc__": "Tracker settings (see core.settings.TrackerSettings)"},
)


def settings_from_properties(pg) -> TrackerSettings:
    """The core settings held by a TWIST_PG_tracker_settings."""
    return TrackerSettings(**{f.name: getattr(pg, f.name)
                              for f in dataclasses.fields(TrackerSettings)})


def _is_armature(_self, obj) -> bool:
    return obj.type == "ARMATURE"


def _is_camera(_self, obj) -> bool:
    return obj.type == "CAMERA"


def first_frame_property():
    return bpy.props.IntProperty(
        name="First Frame", default=1,
        description="The scene frame that shows the footage's first image")


class TWIST_PG_marker(bpy.types.PropertyGroup):
    """A joint placed on a view's footage: the head of ``bone`` at pixel (x, y) on scene
    frame ``frame``."""

    bone: bpy.props.StringProperty(name="Bone", description="The bone whose head this marks")
    frame: bpy.props.IntProperty(name="Frame", description="The scene frame it was placed on")
    x: bpy.props.FloatProperty(name="X", description="Pixels from the left")
    y: bpy.props.FloatProperty(name="Y", description="Pixels from the top")


class TWIST_PG_view(bpy.types.PropertyGroup):
    """One view: a camera and the footage it sees, one image per scene frame."""

    camera: bpy.props.PointerProperty(
        type=bpy.types.Object, poll=_is_camera, name="Camera",
        description="The camera the footage was seen through (orthographic, or "
                    "perspective with Views set to Calibrated)")
    images: bpy.props.StringProperty(
        name="Footage", subtype="FILE_PATH", options={"PATH_SUPPORTS_BLEND_RELATIVE"},
        description="The footage's frames: a glob such as //walk/side_*.png (// is the .blend's "
                    "folder), read in name order")
    first_frame: first_frame_property()
    backdrop: bpy.props.StringProperty(
        name="Clean Plate", subtype="FILE_PATH", options={"PATH_SUPPORTS_BLEND_RELATIVE"},
        description="Optional: an image of this camera's scene without the body, the "
                    "footage's size. The silhouette's backdrop is then this image, not the "
                    "first frame with the body painted out: give one where the body never "
                    "leaves its place")
    markers: bpy.props.CollectionProperty(type=TWIST_PG_marker)


class TWIST_PG_bone_pair(bpy.types.PropertyGroup):
    """One line of the retargeting bone map."""

    source: bpy.props.StringProperty(
        name="Source", description="A bone of the tracked armature (the motion's source)")
    target: bpy.props.StringProperty(
        name="Target", description="The bone of the target armature that copies its motion")


class TWIST_PG_result(bpy.types.PropertyGroup):
    """What the last Track run did, for the Results panel."""

    frames_tracked: bpy.props.IntProperty(
        name="Frames Tracked", description="Frames the last run tracked and keyed")
    last_residual: bpy.props.FloatProperty(
        name="Last Residual", precision=4,
        description="RMS brightness error of the last tracked frame (0 to 1)")
    diverged_frames: bpy.props.StringProperty(
        name="Diverged", description="Frames where the last run stopped, and why")
    frames_to_check: bpy.props.StringProperty(
        name="Frames to Check", description="Tracked frames where a view disagrees with a limb "
        "(its pixels, or its bone off the silhouette), no view sees it, or the body tracked "
        "side-on turned toward or away from the camera")
    doubts_begin: bpy.props.StringProperty(
        name="Doubts Begin", description="Tracked frames where a limb's flag begins, with "
        "those limbs (marked on the timeline): a limb in doubt stays flagged until it clearly "
        "agrees again, so look, and correct, there first")
    notes: bpy.props.StringProperty(
        name="Notes", description="What the tracker noted about the last run, one note a "
        "line (a view whose backdrop moves, joints one line of sight cannot see turn)")


class TWIST_PG_scene(bpy.types.PropertyGroup):
    """Per scene: the armature to track and how."""

    armature: bpy.props.PointerProperty(
        type=bpy.types.Object, poll=_is_armature, name="Armature",
        description="The armature posed over the first frame; tracking keys its bones")
    mode: bpy.props.EnumProperty(
        name="Views",
        description="How the views' cameras are used",
        items=[
            (CALIBRATED.upper(), "Calibrated", "The cameras are where the scene's cameras "
             "are: one root motion, seen by every view"),
            (INDEPENDENT.upper(), "Independent", "Each view tracks its own pose of the body "
             "(cameras not calibrated to each other)"),
        ],
        default=CALIBRATED.upper())
    tracker: bpy.props.PointerProperty(type=TWIST_PG_tracker_settings)
    views: bpy.props.CollectionProperty(type=TWIST_PG_view)
    active_view: bpy.props.IntProperty(name="Active View", description="The selected view")
    result: bpy.props.PointerProperty(type=TWIST_PG_result)
    marker_bone: bpy.props.StringProperty(
        name="Marker Bone",
        description="The bone whose head (or tip) the next click of Place Markers marks; "
                    "each click moves on: to the tip of a bone that ends a limb, else to the "
                    "next bone")
    marker_tip: bpy.props.BoolProperty(
        name="Tip",
        description="The next click marks the Marker Bone's tail instead of its head: the end "
                    "of a limb (a hoof, a hand's tip), for a bone no other bone hangs from")
    show_overlay: bpy.props.BoolProperty(
        name="Show Blobs", default=True,
        description="Draw the outline of every blob over the viewport, to line the armature up "
                    "with the footage through each view's camera")
    bone_map: bpy.props.CollectionProperty(
        type=TWIST_PG_bone_pair, name="Bone Map",
        description="Which target bone copies which tracked bone when retargeting; empty, "
                    "the presets' names are used")
    active_bone_pair: bpy.props.IntProperty(name="Active Pair",
                                            description="The selected line of the bone map")
    direction: bpy.props.EnumProperty(
        name="Direction", default="FORWARD",
        description="Which way to track from the current frame",
        items=[("FORWARD", "Forward", "From the current frame to the scene's end frame"),
               ("BACKWARD", "Backward", "From the current frame back to the scene's start")])


CLASSES = (TWIST_PG_tracker_settings, TWIST_PG_marker, TWIST_PG_view, TWIST_PG_bone_pair,
           TWIST_PG_result, TWIST_PG_scene)


def register():
    bpy.types.Scene.twist = bpy.props.PointerProperty(type=TWIST_PG_scene)


def unregister():
    del bpy.types.Scene.twist

"""Make Hinges: the selected bones of the armature to track turned into hinges about the
plane each is bent in on the current frame (a knee, an elbow), as the tracker wants them.

An imported rig (a BVH, an FBX) leaves every bone free to turn, and its bones' axes are not
the joints' hinge axes, so locking two of them does not make a knee. Here each bone is
rolled so that its local z is the axis its bend on this frame shows (``core.skeleton.
bend_hinge``: normal to its rest direction and its posed one), locked to turn about it
alone within ``BEND_RANGE`` of its rest direction, bending the way it is bent, and posed as
it was (its twist about itself, which a hinge cannot hold, goes, and the bones below turn
with it). Bones whose rotation is keyed are refused: a hinge is keyed on one Euler channel,
and their keys would stop driving them.

Operator id (a public contract): ``twist.make_hinges``."""

from __future__ import annotations

import bpy
import numpy as np

from ..core import se3
from ..core.skeleton import bend_hinge
from . import keyframes
from .armature_action import ArmatureAction
from .bridge import (
    BridgeError,
    bone_frames,
    pose_from_armature,
    rig_hinges,
    skeleton_from_armature,
)

BEND_RANGE = (-10.0, 165.0)  # degrees from the rest direction: a little past straight to folded


def make_hinges(arm, names: list[str], bend_range=BEND_RANGE) -> dict[str, float]:
    """Make the bones ``names`` of ``arm`` hinges (the module's rule) within ``bend_range``
    (degrees), at the current frame's pose; returns each one's bend there (degrees).
    BridgeError, with nothing changed, naming every bone that cannot be one. The armature
    is left in the mode it was in (an edit in progress is taken in first)."""
    view_layer = bpy.context.view_layer
    active, view_layer.objects.active = view_layer.objects.active, arm
    mode = arm.mode
    bpy.ops.object.mode_set(mode="OBJECT")
    try:
        return _make_hinges(arm, names, bend_range)
    finally:
        bpy.ops.object.mode_set(mode=mode)
        view_layer.objects.active = active


def _make_hinges(arm, names: list[str], bend_range) -> dict[str, float]:
    """``make_hinges`` on ``arm``, active and in object mode."""
    sk = skeleton_from_armature(arm)
    R, root = pose_from_armature(arm, sk)
    C = bone_frames(arm)
    keyed = _keyed_rotations(arm)
    hinges, problems = {}, []
    for name in names:
        j = sk.index(name)
        if sk.parents[j] < 0:
            problems.append(f"{name} is the root, which the tracker turns freely")
        elif name in keyed:
            problems.append(f"{name}'s rotation is keyed (Clear Track, or delete its keys)")
        else:
            try:
                hinges[name] = bend_hinge(C[j][:, 1], R[j])
            except ValueError as e:
                problems.append(f"{name} is {e}; bend it the way it bends on this frame")
    if problems:
        raise BridgeError("cannot make hinges: " + "; ".join(problems))
    for name, (axis, angle) in hinges.items():
        R[sk.index(name)] = se3.exp_so3(axis * angle)
    rig_hinges(arm, {name: (axis, np.radians(bend_range)) for name, (axis, _) in hinges.items()},
               R, root)
    return {name: float(np.degrees(angle)) for name, (_, angle) in hinges.items()}


def _keyed_rotations(arm) -> set[str]:
    """The bones of ``arm`` with keys on any rotation channel."""
    bag = keyframes.channelbag(arm)
    if bag is None:
        return set()
    return {fc.data_path.split('"')[1] for fc in bag.fcurves
            if fc.data_path.startswith("pose.bones[") and ".rotation_" in fc.data_path}


class TWIST_OT_make_hinges(ArmatureAction, bpy.types.Operator):
    """Make the selected bones hinges about the plane each is bent in on this frame (knees,
    elbows): each rolled so its local z is that axis and locked to it, bending one way"""

    bl_idname = "twist.make_hinges"
    bl_label = "Make Hinges"

    bend_range: bpy.props.FloatVectorProperty(
        name="Range", size=2, default=BEND_RANGE, min=-180.0, max=180.0,
        description="How far each hinge turns from its rest direction (degrees), the way it "
                    "is bent now being positive: a little past straight to folded")

    def run(self, context) -> str:
        arm = context.scene.twist.armature
        names = [pb.name for pb in arm.pose.bones if pb.select]
        if not names:
            raise BridgeError("select the bones to make hinges (knees, elbows) in Pose Mode, "
                              "bent the way they bend")
        bent = make_hinges(arm, names, tuple(self.bend_range))
        return "hinges: " + ", ".join(f"{n} (bent {a:.0f} degrees)" for n, a in bent.items())


CLASSES = (TWIST_OT_make_hinges,)

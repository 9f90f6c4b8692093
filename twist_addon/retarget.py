"""Copying tracked motion onto another armature through a bone map.

Each mapped target bone is turned in the world the way its source bone turned from its own
rest pose (R_target = D R_target_rest with D = R_source R_source_rest^T, world rotations), so
different rest poses and bone rolls carry over; unmapped bones follow their parents. The root
travels as the source's root did, scaled by the ratio of the two legs' lengths (each rest
pose's root height above its lowest bone end).

The bone map is the scene's editable list (``scene.twist.bone_map``), which the presets fill;
while it is empty, the two presets chosen on the operator map the bones directly.
"""

from __future__ import annotations

import bpy
import numpy as np
from mathutils import Matrix

from .armature_action import ArmatureAction
from .bridge import BridgeError, rest_heads_and_tails

_PRESET_ITEMS = [("CMU", "CMU / BVH", "Bone names of the CMU motion capture BVH files"),
                 ("RIGIFY", "Rigify", "Blender's Rigify human metarig"),
                 ("MIXAMO", "Mixamo", "Mixamo's mixamorig: names")]
_LABEL = {"CMU": "CMU", "RIGIFY": "Rigify", "MIXAMO": "Mixamo"}

# body part -> bone name in each naming scheme
ROLES = {
    "hips": ("Hips", "spine", "mixamorig:Hips"),
    "spine": ("lowerback", "spine.001", "mixamorig:Spine"),
    "chest": ("Chest", "spine.002", "mixamorig:Spine1"),
    "upper_chest": ("Chest2", "spine.003", "mixamorig:Spine2"),
    "neck": ("Neck", "spine.004", "mixamorig:Neck"),
    "head": ("Head", "spine.006", "mixamorig:Head"),
}
for _s, _r, _m in (("Left", "L", "Left"), ("Right", "R", "Right")):
    ROLES.update({
        f"thigh_{_r}": (f"{_s}Hip", f"thigh.{_r}", f"mixamorig:{_m}UpLeg"),
        f"shin_{_r}": (f"{_s}Knee", f"shin.{_r}", f"mixamorig:{_m}Leg"),
        f"foot_{_r}": (f"{_s}Ankle", f"foot.{_r}", f"mixamorig:{_m}Foot"),
        f"toe_{_r}": (f"{_s}Toe", f"toe.{_r}", f"mixamorig:{_m}ToeBase"),
        f"clavicle_{_r}": (f"{_s}Collar", f"shoulder.{_r}", f"mixamorig:{_m}Shoulder"),
        f"upper_arm_{_r}": (f"{_s}Shoulder", f"upper_arm.{_r}", f"mixamorig:{_m}Arm"),
        f"forearm_{_r}": (f"{_s}Elbow", f"forearm.{_r}", f"mixamorig:{_m}ForeArm"),
        f"hand_{_r}": (f"{_s}Wrist", f"hand.{_r}", f"mixamorig:{_m}Hand"),
    })
PRESETS = {"CMU": 0, "RIGIFY": 1, "MIXAMO": 2}


def bone_map(source_preset: str, target_preset: str) -> dict[str, str]:
    """Source bone name -> target bone name for every role both presets name."""
    s, t = PRESETS[source_preset], PRESETS[target_preset]
    return {names[s]: names[t] for names in ROLES.values()}


def _rot(m) -> np.ndarray:
    a = np.array([list(r) for r in m], dtype=float)[:3, :3]
    return a / np.linalg.norm(a, axis=0)


def _leg_length(arm) -> float:
    """The rest pose's root height above its lowest bone end (world units, world z up)."""
    heads, tails = rest_heads_and_tails(arm)
    root = next(j for j, b in enumerate(arm.data.bones) if b.parent is None)
    height = heads[root, 2] - min(heads[:, 2].min(), tails[:, 2].min())
    if height < 1e-6:
        raise BridgeError(f"the root of '{arm.name}' is its lowest point at rest: its legs "
                          "cannot be measured to scale the travel")
    return float(height)


def retarget(source, target, mapping: dict[str, str], frames: list[int], scene,
             map_name: str = "bone map") -> int:
    """Key ``target`` on ``frames`` with the motion of ``source`` through ``mapping`` (source
    bone -> target bone); returns the bones mapped."""
    pairs = {t: s for s, t in mapping.items()
             if s in source.data.bones and t in target.data.bones}
    if not pairs:
        raise BridgeError(f"no bone of the {map_name} is in both '{source.name}' and "
                          f"'{target.name}'")
    ratio = _leg_length(target) / _leg_length(source)
    src_root = next(b.name for b in source.data.bones if b.parent is None)
    tgt_root = next(b.name for b in target.data.bones if b.parent is None)
    S_obj, T_obj = _rot(source.matrix_world), _rot(target.matrix_world)
    rest_s = {b.name: S_obj @ _rot(b.matrix_local) for b in source.data.bones}
    rest_t = {b.name: _rot(b.matrix_local) for b in target.data.bones}
    for b in target.pose.bones:
        b.rotation_mode = "QUATERNION"
    for f in frames:
        scene.frame_set(f)
        pose = {}
        for b in target.data.bones:  # parents come first in this order
            if b.name in pairs:
                s = pairs[b.name]
                D = S_obj @ _rot(source.pose.bones[s].matrix) @ rest_s[s].T
                pose[b.name] = T_obj.T @ D @ T_obj @ rest_t[b.name]
            elif b.parent is not None:
                pose[b.name] = pose[b.parent.name] @ rest_t[b.parent.name].T @ rest_t[b.name]
            else:
                pose[b.name] = rest_t[b.name]
            parent = (pose[b.parent.name] @ rest_t[b.parent.name].T if b.parent is not None
                      else np.eye(3))
            basis = rest_t[b.name].T @ parent.T @ pose[b.name]
            pb = target.pose.bones[b.name]
            pb.rotation_quaternion = Matrix(basis.tolist()).to_quaternion()
            pb.keyframe_insert("rotation_quaternion", frame=f, group=b.name)
        # the root travels like the source's, scaled by the legs
        sp = source.pose.bones[src_root]
        disp = np.array(source.matrix_world)[:3, :3] @ (np.array(sp.head)
                                                         - np.array(sp.bone.head_local))
        tb = target.pose.bones[tgt_root]
        t_scale = np.linalg.norm(np.array(target.matrix_world)[:3, 0])
        local = rest_t[tgt_root].T @ T_obj.T @ (disp * ratio) / t_scale
        tb.location = local
        tb.keyframe_insert("location", frame=f, group=tgt_root)
    return len(pairs)


def _preset_property(side: str, default: str, which: str):
    return bpy.props.EnumProperty(name=f"{side} Names", items=_PRESET_ITEMS, default=default,
                                  description=f"How the {which} armature's bones are named")


class TWIST_OT_retarget(ArmatureAction, bpy.types.Operator):
    """Copy the tracked motion onto another armature through a bone map, over the scene's
    frame range"""

    bl_idname = "twist.retarget"
    bl_label = "Retarget"

    target: bpy.props.StringProperty(
        name="Target", description="The armature object to key (by name)")
    source_preset: _preset_property("Source", "CMU", "tracked")
    target_preset: _preset_property("Target", "RIGIFY", "target")

    def invoke(self, context, event):
        return context.window_manager.invoke_props_dialog(self)

    def draw(self, context):
        self.layout.prop_search(self, "target", bpy.data, "objects")
        self.layout.prop(self, "source_preset")
        self.layout.prop(self, "target_preset")

    def run(self, context) -> str:
        scene = context.scene
        target = bpy.data.objects.get(self.target)
        if target is None or target.type != "ARMATURE":
            raise BridgeError(f"no armature named '{self.target}' to retarget onto")
        frames = list(range(scene.frame_start, scene.frame_end + 1))
        mapping = {p.source: p.target for p in scene.twist.bone_map if p.source and p.target}
        if mapping:
            name = "scene's bone map"
        else:
            mapping = bone_map(self.source_preset, self.target_preset)
            name = f"{_LABEL[self.source_preset]} to {_LABEL[self.target_preset]} map"
        n = retarget(scene.twist.armature, target, mapping, frames, scene, name)
        return f"retargeted {n} bones onto '{target.name}' over {len(frames)} frames"


class TWIST_OT_load_bone_map(bpy.types.Operator):
    """Fill the scene's bone map from two naming presets, to edit it before retargeting"""

    bl_idname = "twist.load_bone_map"
    bl_label = "Load Bone Map"
    bl_options = {"REGISTER", "UNDO"}

    source_preset: _preset_property("Source", "CMU", "tracked")
    target_preset: _preset_property("Target", "RIGIFY", "target")

    def invoke(self, context, event):
        return context.window_manager.invoke_props_dialog(self)

    def execute(self, context):
        pairs = context.scene.twist.bone_map
        pairs.clear()
        for s, t in bone_map(self.source_preset, self.target_preset).items():
            pair = pairs.add()
            pair.source, pair.target = s, t
        self.report({"INFO"}, f"{len(pairs)} bone pairs from the "
                              f"{_LABEL[self.source_preset]} and "
                              f"{_LABEL[self.target_preset]} names")
        return {"FINISHED"}


class TWIST_OT_edit_bone_map(bpy.types.Operator):
    """Add a line to the scene's bone map, or remove the selected one"""

    bl_idname = "twist.edit_bone_map"
    bl_label = "Edit Bone Map"
    bl_options = {"REGISTER", "UNDO"}

    action: bpy.props.EnumProperty(
        name="Action", items=[("ADD", "Add", "Add an empty pair after the selected one"),
                              ("REMOVE", "Remove", "Remove the selected pair")])

    def execute(self, context):
        tw = context.scene.twist
        if self.action == "ADD":
            tw.bone_map.add()
            tw.bone_map.move(len(tw.bone_map) - 1, tw.active_bone_pair + 1)
            tw.active_bone_pair = min(tw.active_bone_pair + 1, len(tw.bone_map) - 1)
        elif len(tw.bone_map):
            tw.bone_map.remove(tw.active_bone_pair)
            tw.active_bone_pair = max(0, min(tw.active_bone_pair, len(tw.bone_map) - 1))
        return {"FINISHED"}


CLASSES = (TWIST_OT_retarget, TWIST_OT_load_bone_map, TWIST_OT_edit_bone_map)

"""The volumetric body: one ellipsoid mesh per blob, parented to its bone, so the tracked
motion shows as a body in the viewport and in renders (the paper's animated Muybridge)."""

from __future__ import annotations

import bpy
import numpy as np
from mathutils import Matrix

from .bridge import BridgeError, pose_from_armature, skeleton_from_armature
from .reporting import ArmatureAction

SIDE_COLOURS = {"Left": (0.75, 0.25, 0.2, 1.0), "Right": (0.2, 0.35, 0.75, 1.0),
                None: (0.8, 0.75, 0.65, 1.0)}


def _side(name: str):
    return next((s for s in ("Left", "Right") if s.lower() in name.lower()), None)


def _material(side) -> bpy.types.Material:
    name = f"Twist body ({side or 'centre'})"
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    mat.diffuse_color = SIDE_COLOURS[side]
    return mat


def blob_matrix(b) -> np.ndarray:
    """4x4 taking the unit sphere to the blob at rest (reference frame)."""
    M = np.eye(4)
    M[:3, :3] = b.Q * b.radii
    M[:3, 3] = b.centre
    return M


def add_body(context, arm) -> list[bpy.types.Object]:
    """Ellipsoids for every blob of ``arm``'s skeleton, parented to their bones where the
    armature stands now, so that they ride on it from then on."""
    import bmesh

    sk = skeleton_from_armature(arm)
    if not sk.blobs:
        raise BridgeError(f"no bone of '{arm.name}' has a blob: give bones envelope radii")
    collection = bpy.data.collections.get("Twist body") or bpy.data.collections.new(
        "Twist body")
    if collection.name not in context.scene.collection.children:
        context.scene.collection.children.link(collection)
    R, root = pose_from_armature(arm, sk)
    g = sk.segment_motions(sk.joint_frames(R, root))
    made = []
    for b in sk.blobs:
        bone = sk.names[b.joint]
        mesh = bpy.data.meshes.new(f"body {bone}")
        bm = bmesh.new()
        bmesh.ops.create_uvsphere(bm, u_segments=24, v_segments=12, radius=1.0)
        bm.to_mesh(mesh)
        bm.free()
        mesh.shade_smooth()
        mesh.materials.append(_material(_side(bone)))
        obj = bpy.data.objects.new(f"body {bone}", mesh)
        collection.objects.link(obj)
        obj.parent, obj.parent_type, obj.parent_bone = arm, "BONE", bone
        context.view_layer.update()
        obj.matrix_world = Matrix((g[b.joint] @ blob_matrix(b)).tolist())
        made.append(obj)
    context.view_layer.update()
    return made


class TWIST_OT_add_volumetric_body(ArmatureAction, bpy.types.Operator):
    """Add an ellipsoid for every blob of the armature, riding on its bone, coloured by side"""

    bl_idname = "twist.add_volumetric_body"
    bl_label = "Add Volumetric Body"

    def run(self, context) -> str:
        arm = context.scene.twist.armature
        made = add_body(context, arm)
        return f"added {len(made)} ellipsoids riding on '{arm.name}'"


CLASSES = (TWIST_OT_add_volumetric_body,)

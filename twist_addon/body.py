"""The body's blobs: sized from the bones' lengths (the envelope radii they are read from),
and the volumetric body, one ellipsoid mesh per blob parented to its bone, so the tracked
motion shows as a body in the viewport and in renders (the paper's animated Muybridge); and,
on request, a stick figure: a thin rod along every bone of a blob."""

from __future__ import annotations

import bpy
import numpy as np
from mathutils import Matrix

from ..core.se3 import frame_along
from .armature_action import ArmatureAction
from .bridge import BridgeError, pose_from_armature, size_blobs, skeleton_from_armature

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


STICK_RADIUS = 0.2  # of the blob's thinner cross radius


def _part(context, collection, arm, bone: str, name: str, mesh, matrix) -> bpy.types.Object:
    """An object of ``mesh`` coloured by side, parented to ``bone``, placed at ``matrix``
    (world, where the armature stands now)."""
    mesh.shade_smooth()
    mesh.materials.append(_material(_side(bone)))
    obj = bpy.data.objects.new(name, mesh)
    collection.objects.link(obj)
    obj.parent, obj.parent_type, obj.parent_bone = arm, "BONE", bone
    context.view_layer.update()
    obj.matrix_world = Matrix(matrix.tolist())
    return obj


def add_body(context, arm, sticks: bool = False) -> list[bpy.types.Object]:
    """Ellipsoids for every blob of ``arm``'s skeleton (and, with ``sticks``, a rod along each
    of their bones from head to tail), parented to their bones where the armature stands now,
    so that they ride on it from then on."""
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
    W = np.array(arm.matrix_world)
    for b in sk.blobs:
        bone = sk.names[b.joint]
        mesh = bpy.data.meshes.new(f"body {bone}")
        bm = bmesh.new()
        bmesh.ops.create_uvsphere(bm, u_segments=24, v_segments=12, radius=1.0)
        bm.to_mesh(mesh)
        bm.free()
        made.append(_part(context, collection, arm, bone, f"body {bone}", mesh,
                          g[b.joint] @ blob_matrix(b)))
        if sticks:
            pb = arm.pose.bones[bone]
            head, tail = ((W @ np.append(np.array(p), 1))[:3] for p in (pb.head, pb.tail))
            mesh = bpy.data.meshes.new(f"stick {bone}")
            bm = bmesh.new()  # a unit rod along z from 0 to 1, scaled to the bone below
            bmesh.ops.create_cone(bm, cap_ends=True, segments=8, radius1=1.0, radius2=1.0,
                                  depth=1.0, matrix=Matrix.Translation((0, 0, 0.5)))
            bm.to_mesh(mesh)
            bm.free()
            along, across, up = frame_along(tail - head)
            r = STICK_RADIUS * min(b.radii[1:])
            M = np.eye(4)
            M[:3, :3] = np.stack([across * r, up * r, tail - head], axis=1)
            M[:3, 3] = head
            made.append(_part(context, collection, arm, bone, f"stick {bone}", mesh, M))
    context.view_layer.update()
    return made


class TWIST_OT_add_volumetric_body(ArmatureAction, bpy.types.Operator):
    """Add an ellipsoid for every blob of the armature, riding on its bone, coloured by side"""

    bl_idname = "twist.add_volumetric_body"
    bl_label = "Add Volumetric Body"

    sticks: bpy.props.BoolProperty(
        name="Stick Figure", default=False,
        description="Also add a thin rod along every bone, from its head to its tail")

    def run(self, context) -> str:
        arm = context.scene.twist.armature
        made = add_body(context, arm, self.sticks)
        return f"added {len(made)} parts riding on '{arm.name}'"


class TWIST_OT_size_blobs(ArmatureAction, bpy.types.Operator):
    """Size every bone's blob (its envelope radii) from its length, as a body's proportions
    have it: a limb's radius a sixth of its length, the trunk's bones an adult trunk's"""

    bl_idname = "twist.size_blobs"
    bl_label = "Size Blobs"

    def run(self, context) -> str:
        arm = context.scene.twist.armature
        n = size_blobs(arm)
        return f"sized the blobs of '{arm.name}': {n} of {len(arm.data.bones)} bones have one"


CLASSES = (TWIST_OT_add_volumetric_body, TWIST_OT_size_blobs)

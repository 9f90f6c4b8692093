"""Blender objects to core types and back: armatures, poses and cameras.

Frames. Core's reference frame is Blender's world with the armature at rest; a joint is a
bone's head, and its local rotation R_j turns the bone's subtree about the head in world-
aligned axes. Blender keeps a pose bone's rotation Q_j in the bone's own rest axes; with
C_j = (armature object rotation) @ (bone rest rotation), the two are conjugates:

    R_j = C_j Q_j C_j^T,   Q_j = C_j^T R_j C_j.

A bone whose rotation is locked on exactly two axes is a hinge about the third; one locked on
all three stays fixed; any other is a ball. A hinge's inverse-kinematics limit on its free axis
(Bone Properties > Inverse Kinematics) bounds its angle while tracking: the core hinge angle
is the bone's own rotation about that axis. A bone's blob runs from its head to its tail with
the mean of its envelope's head and tail radii; a bone whose envelope radii are zero has none.
A bone no other bone hangs from ends in its tail: the joint's end site (a hoof, a hand's tip).
"""

from __future__ import annotations

import numpy as np

from ..core import se3
from ..core.camera import Camera, Pinhole, View
from ..core.errors import InputError
from ..core.pose import CALIBRATED
from ..core.skeleton import BALL, FIXED, HINGE, MIN_LENGTH, Skeleton, bone_blob


class BridgeError(InputError):
    """A Blender object that cannot become a core one; the message says which and why."""


def _matrix(m) -> np.ndarray:
    return np.array([list(row) for row in m], dtype=float)


def _object_rotation_and_scale(obj) -> tuple[np.ndarray, float]:
    M = _matrix(obj.matrix_world)[:3, :3]
    scales = np.linalg.norm(M, axis=0)
    if np.ptp(scales) > 1e-6 * scales.max():
        raise BridgeError(f"'{obj.name}' has a non-uniform scale {tuple(scales.round(4))}; "
                          "apply the scale (Ctrl A) first")
    return M / scales[0], float(scales[0])


def bone_frames(arm) -> np.ndarray:
    """C_j (J, 3, 3): each bone's rest axes in the world, in ``arm.data.bones`` order."""
    R_obj, _ = _object_rotation_and_scale(arm)
    return np.array([R_obj @ _matrix(b.matrix_local)[:3, :3] for b in arm.data.bones])


def rest_heads_and_tails(arm) -> tuple[np.ndarray, np.ndarray]:
    """World positions (J, 3) of every bone's head and tail at rest, in bone order."""
    W = _matrix(arm.matrix_world)
    bones = arm.data.bones
    return tuple(np.array([(W @ np.append(np.array(getattr(b, end)), 1))[:3] for b in bones])
                 for end in ("head_local", "tail_local"))


def skeleton_from_armature(arm) -> Skeleton:
    """The armature's rest pose as a core skeleton: one joint per bone, in bone order."""
    bones = list(arm.data.bones)
    if not bones:
        raise BridgeError(f"the armature '{arm.name}' has no bones; add bones or a template")
    names = [b.name for b in bones]
    roots = [b.name for b in bones if b.parent is None]
    if len(roots) != 1:
        raise BridgeError(f"the armature '{arm.name}' has {len(roots)} root bones "
                          f"({', '.join(roots)}); parent them under one root bone")
    heads, tails = rest_heads_and_tails(arm)
    parents = [names.index(b.parent.name) if b.parent else -1 for b in bones]
    offsets = np.array([heads[j] - (heads[p] if p >= 0 else 0) for j, p in enumerate(parents)])
    C = bone_frames(arm)
    kinds, axes = [], np.tile([1.0, 0.0, 0.0], (len(bones), 1))
    limits = np.tile([-np.inf, np.inf], (len(bones), 1))
    for j, pb in enumerate(arm.pose.bones[b.name] for b in bones):
        free = [k for k in range(3) if not pb.lock_rotation[k]]
        if parents[j] < 0 or not free:
            kinds.append(FIXED)
        elif len(free) == 1:
            kinds.append(HINGE)
            axes[j] = C[j][:, free[0]]
            xyz = "xyz"[free[0]]
            if getattr(pb, f"use_ik_limit_{xyz}"):
                limits[j] = getattr(pb, f"ik_min_{xyz}"), getattr(pb, f"ik_max_{xyz}")
        else:
            kinds.append(BALL)
    # a bone no other bone hangs from ends in its tail: its end site (a hoof, a hand's tip)
    ends = [[tails[j] - heads[j]] if j not in parents else [] for j in range(len(bones))]
    sk = Skeleton(names=names, parents=parents, offsets=offsets, kinds=kinds, axes=axes,
                  end_sites=ends, limits=limits)
    _, s = _object_rotation_and_scale(arm)
    sk.blobs = [bone_blob(j, b.name, heads[j], tails[j] - heads[j],
                          s * (b.head_radius + b.tail_radius) / 2)
                for j, b in enumerate(bones)
                if np.linalg.norm(tails[j] - heads[j]) > 1e-6
                and b.head_radius + b.tail_radius > 0]
    return sk


def size_blobs(arm) -> int:
    """Set every bone's envelope radii to the default blob's short radius for its length
    (``Skeleton.blob_radii``: a body's proportions, the trunk's bones an adult trunk's
    width), zero (no blob) for a bone too short to see; returns how many bones have a blob.
    An imported armature's envelopes are Blender's defaults, the same for a forearm as for
    the chest."""
    sk = skeleton_from_armature(arm)
    heads, tails = rest_heads_and_tails(arm)
    tips = tails - heads
    _, s = _object_rotation_and_scale(arm)
    seen = np.linalg.norm(tips, axis=1) >= MIN_LENGTH * sk.height()
    radii = sk.blob_radii(list(enumerate(tips)))
    for b, r, ok in zip(arm.data.bones, radii, seen):
        b.head_radius = b.tail_radius = r / s if ok else 0.0
    return int(sum(seen))


def tracked_skeleton(arm) -> Skeleton:
    """``skeleton_from_armature``, refused when no bone is free to turn (nothing to track)."""
    sk = skeleton_from_armature(arm)
    if not sk.dof_names():
        raise BridgeError(f"no bone of '{arm.name}' is free to turn: unlock the rotations "
                          "of the bones to track")
    return sk


def _basis_rotation(pb) -> np.ndarray:
    """A pose bone's rotation in its own axes, whatever its rotation mode."""
    if pb.rotation_mode == "QUATERNION":
        return _matrix(pb.rotation_quaternion.to_matrix())
    if pb.rotation_mode == "AXIS_ANGLE":
        a = pb.rotation_axis_angle
        axis = np.array(a[1:])
        return se3.exp_so3(axis / max(np.linalg.norm(axis), 1e-12) * a[0])
    return _matrix(pb.rotation_euler.to_matrix())


def pose_from_armature(arm, sk: Skeleton) -> tuple[np.ndarray, np.ndarray]:
    """Core local rotations (J, 3, 3) and root position (3,) of the armature's current pose
    (rotations and the root bone's location; other bones' locations are not tracked)."""
    C = bone_frames(arm)
    R = np.empty((sk.n_joints, 3, 3))
    for j, name in enumerate(sk.names):
        R[j] = C[j] @ _basis_rotation(arm.pose.bones[name]) @ C[j].T
    root = arm.pose.bones[sk.names[0]]
    _, s = _object_rotation_and_scale(arm)
    loc = C[0] @ np.array(root.location) * s
    return R, sk.rest_positions[0] + loc


def armature_rotations(arm, sk: Skeleton, R: np.ndarray, root_position: np.ndarray):
    """Blender's basis rotations (J, 3, 3) and the root bone's location (3,) for a core pose."""
    C = bone_frames(arm)
    Q = np.einsum("jba,jbc,jcd->jad", C, R, C)
    _, s = _object_rotation_and_scale(arm)
    loc = C[0].T @ (root_position - sk.rest_positions[0]) / s
    return Q, loc


def set_pose(arm, sk: Skeleton, R: np.ndarray, root_position: np.ndarray) -> None:
    """Pose the armature (unkeyed) at a core pose: each bone's rotation in its own rotation
    mode (an axis-angle bone is left as it is) and the root bone's location."""
    from mathutils import Matrix

    Q, loc = armature_rotations(arm, sk, R, root_position)
    for j, name in enumerate(sk.names):
        pb = arm.pose.bones[name]
        m = Matrix(Q[j].tolist())
        if pb.rotation_mode == "QUATERNION":
            pb.rotation_quaternion = m.to_quaternion()
        elif pb.rotation_mode != "AXIS_ANGLE":
            pb.rotation_euler = m.to_euler(pb.rotation_mode)
    arm.pose.bones[sk.names[0]].location = loc


def view_from_camera(cam, scene) -> Camera:
    """The camera as the tracker sees it, at the scene's resolution and current frame: an
    orthographic camera as a scaled orthographic view, a perspective one as a pinhole (its
    focal length, sensor fit and lens shift as Blender renders them)."""
    if cam.type != "CAMERA":
        raise BridgeError(f"'{cam.name}' is not a camera")
    data = cam.data
    if data.type not in ("ORTHO", "PERSP"):
        kind = {"PANO": "panoramic"}.get(data.type, data.type.lower())
        raise BridgeError(f"the camera '{cam.name}' is {kind}; the tracker needs an "
                          "orthographic or perspective camera (Camera properties > Lens > Type)")
    r = scene.render
    W = r.resolution_x * r.resolution_percentage / 100
    H = r.resolution_y * r.resolution_percentage / 100
    if r.pixel_aspect_x != r.pixel_aspect_y:
        raise BridgeError("the scene's pixels are not square (Output > Format > Aspect)")
    fit = data.sensor_fit
    horizontal = fit == "HORIZONTAL" or fit == "AUTO" and W >= H
    span = W if horizontal else H  # the image side the sensor (or ortho scale) spans
    M = _matrix(cam.matrix_world)
    axes = M[:3, :3] / np.linalg.norm(M[:3, :3], axis=0)
    R = np.stack([axes[:, 0], -axes[:, 1], -axes[:, 2]])  # x right, y down, z forward
    t = -R @ M[:3, 3]
    # shifting the lens right moves the picture left (and up moves it down)
    center = np.array([(W - 1) / 2 - data.shift_x * span, (H - 1) / 2 + data.shift_y * span])
    if data.type == "ORTHO":
        return View(se3.Similarity(span / data.ortho_scale, R, t), center)
    sensor = data.sensor_height if fit == "VERTICAL" else data.sensor_width
    f = data.lens / sensor * span
    return Pinhole(np.array([[f, 0.0, center[0]], [0.0, f, center[1]], [0.0, 0.0, 1.0]]), R, t)


def place_pinhole(cam, pinhole: Pinhole, size: tuple[int, int]) -> None:
    """Make the camera object ``cam`` the perspective camera ``pinhole`` is for images of
    ``size`` = (width, height) (the inverse of ``view_from_camera``, which the scene's
    resolution must then match): its sensor fitted horizontally, the focal length and lens
    shift in its terms, placed and turned in the world."""
    from mathutils import Matrix

    W, _ = size
    K = pinhole.K
    data = cam.data
    data.type, data.sensor_fit = "PERSP", "HORIZONTAL"
    data.lens = K[0, 0] * data.sensor_width / W  # Blender's pixels are square: fx
    data.shift_x = ((W - 1) / 2 - K[0, 2]) / W
    data.shift_y = (K[1, 2] - (size[1] - 1) / 2) / W
    M = np.eye(4)
    M[:3, :3] = pinhole.R.T @ np.diag([1.0, -1.0, -1.0])  # Blender's camera: x, y up, -z
    M[:3, 3] = pinhole.centre
    cam.matrix_world = Matrix(M.tolist())


def _animated(obj) -> bool:
    """Whether anything can move ``obj`` or change its lens over the frames: its own or a
    parent's animation, drivers or constraints, or its camera data's animation."""
    data = getattr(obj, "data", None)
    if data is not None and data.animation_data is not None:
        return True
    while obj is not None:
        if obj.animation_data is not None or len(obj.constraints):
            return True
        obj = obj.parent
    return False


def camera_path(cam, scene, frames) -> list[Camera] | None:
    """The camera on each of ``frames`` (scene frames, in that order) when it moves or zooms
    over them, else None; the scene is left on the frame it was on."""
    if not _animated(cam):
        return None
    cur = scene.frame_current
    path = []
    try:
        for f in frames:
            scene.frame_set(f)
            path.append(view_from_camera(cam, scene))
    finally:
        scene.frame_set(cur)
    numbers = [np.concatenate([c.K.ravel(), c.R.ravel(), c.t]) if c.central else
               np.concatenate([c.pose.matrix().ravel(), c.center]) for c in path]
    return path if any(not np.allclose(n, numbers[0]) for n in numbers) else None


def tracking_mode(scene, views: list[Camera], moving=()) -> str:
    """The core mode of the scene's *Views* setting; perspective cameras and cameras that
    move (``moving``: per view, its ``camera_path``) are calibrated only (a BridgeError says
    so under *Independent*)."""
    mode = scene.twist.mode.lower()
    if mode != CALIBRATED and any(v.central for v in views):
        raise BridgeError("perspective cameras are placed where they filmed from: set Views "
                          "to Calibrated (or make the cameras orthographic)")
    if mode != CALIBRATED and any(m is not None for m in moving):
        raise BridgeError("a view's camera moves over the frames: set Views to Calibrated "
                          "(the body's root is then tracked in the world)")
    return mode


# core templates are y up and face +z; Blender is z up and a character faces -y
_CORE_TO_BLENDER = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])


def armature_from_skeleton(sk: Skeleton, name: str, collection):
    """A new armature object whose bones are the skeleton's joints (head at the joint, tail at
    its first child or end site), locked to the joint's kind: a hinge's free axis is the
    bone's local z, aligned with the hinge axis, and a limited hinge's range is that axis's
    inverse-kinematics limit; envelope radii are the blobs' radii."""
    import bpy
    from mathutils import Vector

    data = bpy.data.armatures.new(name)
    obj = bpy.data.objects.new(name, data)
    collection.objects.link(obj)
    view_layer = bpy.context.view_layer
    view_layer.objects.active = obj
    bpy.ops.object.mode_set(mode="EDIT")
    T = _CORE_TO_BLENDER
    heads = sk.rest_positions @ T.T
    radius = {b.joint: float(np.mean(b.radii[1:])) for b in sk.blobs}
    limits = {}  # hinge -> its range about the bone's z, which may point against its axis
    for j, joint in enumerate(sk.names):
        tips = [sk.offsets[c] for c in sk.children(j)] + list(sk.end_sites[j])
        tips = [t for t in tips if np.linalg.norm(t) > 1e-6]
        d = T @ tips[0] if tips else np.array([0, 0, 0.05])
        eb = data.edit_bones.new(joint)
        eb.head, eb.tail = Vector(heads[j]), Vector(heads[j] + d)
        if sk.parents[j] >= 0:
            eb.parent = data.edit_bones[sk.names[sk.parents[j]]]
        if sk.kinds[j] == HINGE:
            limits[joint] = roll_to_hinge(eb, T @ sk.axes[j], sk.limits[j])
        eb.head_radius = eb.tail_radius = radius.get(j, 0.0)
    bpy.ops.object.mode_set(mode="OBJECT")
    for j, joint in enumerate(sk.names):
        pb = obj.pose.bones[joint]
        kind = sk.kinds[j] if j else BALL
        if kind == HINGE:
            lock_to_hinge(pb, limits[joint])
        else:
            pb.lock_rotation = (kind == FIXED,) * 3
            pb.rotation_mode = "QUATERNION"
    return obj


def roll_to_hinge(eb, axis: np.ndarray, limits: tuple[float, float]
                  ) -> tuple[float, float] | None:
    """Roll an edit bone so that its local z is a hinge's ``axis`` (armature space, across
    the bone); returns the hinge's ``limits`` (radians about ``axis``) as a range about that
    z, which may point against it, or None for a hinge without limits (``lock_to_hinge``)."""
    from mathutils import Vector

    eb.align_roll(Vector(axis))
    lo, hi = limits
    if not (np.isfinite(lo) or np.isfinite(hi)):
        return None
    along = np.sign(np.dot(eb.z_axis, axis))
    return tuple(np.clip(sorted([along * lo, along * hi]), -np.pi, np.pi))


def rig_hinges(arm, hinges: dict[str, tuple[np.ndarray, tuple[float, float]]],
               R: np.ndarray, root_position: np.ndarray) -> None:
    """Make bones of ``arm`` (active, in object mode) hinges: each of ``hinges`` (name: its
    axis, world, across the bone, and its limits, radians about it) rolled to its axis and
    locked there (``roll_to_hinge``, ``lock_to_hinge``); then the armature posed at the core
    pose (``R``, ``root_position``, ``set_pose``), each hinge about its local z alone (what
    its locked channels would hold, a turn off the axis or rounding, goes)."""
    import bpy

    to_armature = np.linalg.inv(np.array(arm.matrix_world.to_3x3()))
    bpy.ops.object.mode_set(mode="EDIT")
    ranges = {name: roll_to_hinge(arm.data.edit_bones[name], to_armature @ axis, limits)
              for name, (axis, limits) in hinges.items()}
    bpy.ops.object.mode_set(mode="OBJECT")
    for name, z_range in ranges.items():
        lock_to_hinge(arm.pose.bones[name], z_range)
    set_pose(arm, skeleton_from_armature(arm), R, root_position)
    for name in hinges:
        pb = arm.pose.bones[name]
        pb.rotation_euler = (0.0, 0.0, pb.rotation_euler[2])


def lock_to_hinge(pb, z_limits: tuple[float, float] | None) -> None:
    """Make a pose bone whose bone ``roll_to_hinge`` rolled a hinge about its local z, turning
    within ``z_limits`` (radians, its inverse-kinematics limit) where given."""
    pb.lock_rotation = (True, True, False)
    pb.rotation_mode = "XYZ"
    if z_limits is not None:
        pb.use_ik_limit_z = True
        pb.ik_min_z, pb.ik_max_z = z_limits

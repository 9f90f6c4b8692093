"""Tracked poses as keyframes on the armature, and their removal.

Tracking writes keyframes of type GENERATED, so that clearing a track removes exactly what
tracking wrote and never a key the user set; where the user keyed a bone on a tracked frame,
tracking leaves that bone's keys there alone (the frame is the user's correction, see
``user_keys``). A ball joint is keyed as a quaternion, a hinge as the one Euler channel of its
free axis, the root bone as location and quaternion.

Track keys its first frame too, as tracking's (the pose the user set there, so that the
frame shows it after the run and a second Track starts from it again), and remembers the
pose bones' own values from before the first Track on the armature (``POSE_BEFORE_TRACK``);
clearing the track puts them back, so that the scene is as it was before Track.
"""

from __future__ import annotations

import json

import numpy as np
from mathutils import Matrix

from ..core.skeleton import BALL, FIXED, HINGE, Skeleton
from .bridge import armature_rotations, pose_from_armature

TRACKED = "GENERATED"  # keyframe type of tracked keys
USER = "KEYFRAME"  # keyframe type of a correction (Blender keeps a key's type when re-keyed)
POSE_BEFORE_TRACK = "twist_pose_before_track"  # custom property of the armature object


def channels(arm, sk: Skeleton) -> list[tuple[str, str, int]]:
    """(bone, data path, index) of every channel tracking keys."""
    out = []
    for j, (name, kind) in enumerate(zip(sk.names, sk.kinds)):
        pb = f'pose.bones["{name}"]'
        if j == 0:
            out += [(name, f"{pb}.location", i) for i in range(3)]
            out += [(name, f"{pb}.rotation_quaternion", i) for i in range(4)]
        elif kind == BALL:
            out += [(name, f"{pb}.rotation_quaternion", i) for i in range(4)]
        elif kind == HINGE:
            free = [k for k in range(3) if not arm.pose.bones[name].lock_rotation[k]]
            out.append((name, f"{pb}.rotation_euler", free[0]))
    return out


def write_pose(arm, sk: Skeleton, frame: int, R: np.ndarray, root: np.ndarray,
               keep: frozenset[str] = frozenset()) -> None:
    """Key the core pose (local rotations R (J, 3, 3), root position (3,)) on ``frame``,
    except on the bones named in ``keep``."""
    Q, loc = armature_rotations(arm, sk, R, root)
    for j, (name, kind) in enumerate(zip(sk.names, sk.kinds)):
        if (kind == FIXED and j) or name in keep:
            continue
        pb = arm.pose.bones[name]
        if j == 0 or kind == BALL:
            if pb.rotation_mode != "QUATERNION":
                pb.rotation_mode = "QUATERNION"
            q = Matrix(Q[j].tolist()).to_quaternion()
            if q.dot(pb.rotation_quaternion) < 0:
                q.negate()  # the same rotation, on the side that keeps the curves continuous
            pb.rotation_quaternion = q
            pb.keyframe_insert("rotation_quaternion", frame=frame, group=name, keytype=TRACKED)
        else:
            if pb.rotation_mode in ("QUATERNION", "AXIS_ANGLE"):
                pb.rotation_mode = "XYZ"
            free = [k for k in range(3) if not pb.lock_rotation[k]][0]
            e = Matrix(Q[j].tolist()).to_euler(pb.rotation_mode)
            pb.rotation_euler[free] = e[free]
            pb.keyframe_insert("rotation_euler", index=free, frame=frame, group=name,
                               keytype=TRACKED)
        if j == 0:
            pb.location = loc
            pb.keyframe_insert("location", frame=frame, group=name, keytype=TRACKED)


def channelbag(arm):
    """Where the armature's F-curves live (its action's slot), or None without animation."""
    from bpy_extras import anim_utils

    ad = arm.animation_data
    if ad is None or ad.action is None:
        return None
    return anim_utils.action_get_channelbag_for_slot(ad.action, ad.action_slot)


def tracked_fcurves(arm, sk: Skeleton, bag) -> list:
    """The F-curves of ``bag`` on the channels tracking keys (see ``channels``)."""
    wanted = {(path, i) for _, path, i in channels(arm, sk)}
    return [fc for fc in bag.fcurves if (fc.data_path, fc.array_index) in wanted]


def key_correction(arm, sk: Skeleton, frame: int) -> None:
    """Key the armature's current pose on ``frame`` as the user's own keys (type KEYFRAME) on
    every tracked channel, also where tracking had keyed that frame: re-keying a key keeps
    its type, so a tracked frame re-posed and keyed would still read as tracking's."""
    R, root = pose_from_armature(arm, sk)
    write_pose(arm, sk, frame, R, root)
    for fc in tracked_fcurves(arm, sk, channelbag(arm)):
        for kp in fc.keyframe_points:
            if int(round(kp.co[0])) == frame:
                kp.type = USER


def user_keys(arm, sk: Skeleton, any_type: bool = False) -> dict[int, frozenset[str]]:
    """Per frame, the bones whose tracked channels hold a key the user set (any type but
    GENERATED) there; with ``any_type``, any key."""
    bag = channelbag(arm)
    if bag is None:
        return {}
    bone_of = {(path, i): bone for bone, path, i in channels(arm, sk)}
    out: dict[int, set[str]] = {}
    for fc in tracked_fcurves(arm, sk, bag):
        for kp in fc.keyframe_points:
            if any_type or kp.type != TRACKED:
                out.setdefault(int(round(kp.co[0])), set()).add(
                    bone_of[fc.data_path, fc.array_index])
    return {f: frozenset(bones) for f, bones in out.items()}


def clear(arm, sk: Skeleton, frames: set[int] | None = None) -> int:
    """Remove tracked keys (of the given frames, or all) from the tracked channels; returns how
    many were removed. Keys the user set are kept."""
    bag = channelbag(arm)
    if bag is None:
        return 0
    removed = 0
    for fc in tracked_fcurves(arm, sk, bag):
        for kp in reversed(list(fc.keyframe_points)):
            f = int(round(kp.co[0]))
            if kp.type == TRACKED and (frames is None or f in frames):
                fc.keyframe_points.remove(kp)
                removed += 1
        if not len(fc.keyframe_points):
            bag.fcurves.remove(fc)
    return removed


def remember_pose(arm) -> None:
    """Keep the pose bones' own values (rotation mode, location, rotations, scale) on the
    armature, unless an earlier Track already kept them (then they are the user's, and the
    current ones may be tracking's)."""
    if POSE_BEFORE_TRACK in arm:
        return
    arm[POSE_BEFORE_TRACK] = json.dumps({pb.name: {
        "rotation_mode": pb.rotation_mode, "location": list(pb.location),
        "rotation_quaternion": list(pb.rotation_quaternion),
        "rotation_euler": list(pb.rotation_euler), "scale": list(pb.scale)}
        for pb in arm.pose.bones})


def restore_pose(arm) -> None:
    """Put back the pose bones' values ``remember_pose`` kept, and forget them."""
    if POSE_BEFORE_TRACK not in arm:
        return
    for name, values in json.loads(arm[POSE_BEFORE_TRACK]).items():
        pb = arm.pose.bones.get(name)
        if pb is None:
            continue
        pb.rotation_mode = values.pop("rotation_mode")
        for prop, v in values.items():
            setattr(pb, prop, v)
    del arm[POSE_BEFORE_TRACK]

"""Make a walk cycle of the tracked motion: find the gait period from the legs' curves, keep
one period (or complete a partial one by mirroring left and right), bridge its end into its
start, and let F-curve Cycles modifiers repeat it.

Mirroring assumes Blender's convention for symmetric rigs: at rest the armature is symmetric
across its x = 0 plane and paired bones are named as ``bpy.utils.flip_name`` pairs them
(LeftKnee/RightKnee, thigh.L/thigh.R). Bone rolls need not be mirrored."""

from __future__ import annotations

import bpy
import numpy as np
from mathutils import Euler, Matrix, Quaternion

from ..core.cycles import (
    CycleError,
    complete_by_mirroring,
    continuous_quaternions,
    gait_period,
    make_loop,
    mirror_poses,
    sample,
)
from .armature_action import ArmatureAction
from .bridge import BridgeError, skeleton_from_armature
from .keyframes import TRACKED, channelbag, tracked_fcurves


class BodyMirror:
    """Maps rows of tracked channel values (k, C) onto the rows of the mirrored body, a
    half period later: sides swapped, reflected across the sagittal plane of the recorded
    frames (through the root's mean position, across its mean heading), and carried on by
    half a period's travel."""

    def __init__(self, arm, curves: list, recorded: np.ndarray, half: float):
        self.arm, self.curves = arm, curves
        self.bones = list(dict.fromkeys(_bone(fc) for fc in curves))
        # per bone, its channels: (column, attribute, index)
        self.channels = {b: [(c, fc.data_path.rsplit(".", 1)[1], fc.array_index)
                             for c, fc in enumerate(curves) if _bone(fc) == b]
                         for b in self.bones}
        tracked = set(self.bones)
        partners = []
        for b in self.bones:
            other = bpy.utils.flip_name(b)
            if other not in tracked:
                raise BridgeError(f"bone '{b}' has no tracked partner '{other}' to mirror "
                                  f"onto: mirroring needs left/right names such as .L/.R")
            partners.append(self.bones.index(other))
        self.partners = np.array(partners)
        bones = arm.data.bones
        self.rest = np.array([np.array(bones[b].matrix_local.to_3x3()) for b in self.bones])
        self.head = np.array(bones[self.bones[0]].head_local)
        turns, heads = self._pose(recorded)
        lateral = (turns[:, 0] @ [1.0, 0, 0]).mean(0)
        lateral[2] = 0.0  # the plane is upright (armature z is up)
        self.normal = n = lateral / np.linalg.norm(lateral)
        Sp = np.eye(3) - 2 * np.outer(n, n)
        # where the recording overlaps itself half a period on, each root position is its
        # mirror image from then plus the travel: a - Sp b = 2 n (n . centre) + travel
        overlap = np.arange(np.ceil(half), len(recorded))
        if len(overlap):
            _, before = self._pose(sample(recorded, overlap - half))
            d = (heads[overlap.astype(int)] - before @ Sp.T).mean(0)
        else:  # no overlap: the mean position, and the mean velocity
            d = 2 * n * (n @ heads.mean(0)) + (heads[-1] - heads[0]) / max(len(heads) - 1,
                                                                             1) * half
        self.centre = n * (d @ n) / 2
        self.travel = d - n * (d @ n)

    def __call__(self, rows: np.ndarray) -> np.ndarray:
        turns, heads = self._pose(rows)
        turns, heads = mirror_poses(turns, heads, self.partners, self.normal, self.centre)
        return self._rows(turns, heads + self.travel, rows)

    def _pose(self, rows: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Turns (k, B, 3, 3) in armature axes (A Q A^T, A the bone's rest) and root heads."""
        k = len(rows)
        Q = np.tile(np.eye(3), (k, len(self.bones), 1, 1))
        heads = np.tile(self.head, (k, 1))
        for i, b in enumerate(self.bones):
            pb = self.arm.pose.bones[b]
            for f, row in enumerate(rows):
                value = {"rotation_quaternion": Quaternion(pb.rotation_quaternion),
                         "rotation_euler": Euler(pb.rotation_euler),
                         "location": np.array(pb.location)}
                for c, attr, index in self.channels[b]:
                    value[attr][index] = row[c]
                quat, euler, loc = (value[k] for k in ("rotation_quaternion",
                                                       "rotation_euler", "location"))
                if pb.rotation_mode == "QUATERNION":
                    Q[f, i] = np.array(quat.normalized().to_matrix())
                else:
                    euler.order = pb.rotation_mode
                    Q[f, i] = np.array(euler.to_matrix())
                if i == 0:
                    heads[f] = self.head + self.rest[0] @ loc
        return self.rest @ Q @ self.rest.transpose(0, 2, 1), heads

    def _rows(self, turns: np.ndarray, heads: np.ndarray, like: np.ndarray) -> np.ndarray:
        """Channel rows of a pose (the inverse of ``_pose``)."""
        Q = self.rest.transpose(0, 2, 1) @ turns @ self.rest
        out = like.copy()
        for f in range(len(out)):
            for i, b in enumerate(self.bones):
                pb = self.arm.pose.bones[b]
                m = Matrix(Q[f, i].tolist())
                if pb.rotation_mode == "QUATERNION":
                    value = {"rotation_quaternion": m.to_quaternion()}
                else:
                    value = {"rotation_euler": m.to_euler(pb.rotation_mode, pb.rotation_euler)}
                if i == 0:
                    value["location"] = self.rest[0].T @ (heads[f] - self.head)
                for c, attr, index in self.channels[b]:
                    out[f, c] = value[attr][index]
        return out


def _bone(fc) -> str:
    return fc.data_path.split('"')[1]


def _continuous_quaternions(values: np.ndarray, curves: list) -> None:
    """Put each bone's quaternion rows, in place, on the side of the row before."""
    for b in dict.fromkeys(_bone(fc) for fc in curves):
        cols = [c for c, fc in enumerate(curves)
                if _bone(fc) == b and fc.data_path.endswith("rotation_quaternion")]
        if len(cols) == 4:
            values[:, cols] = continuous_quaternions(values[:, cols])


MIN_GAIT_SECONDS = 0.5  # no gait repeats faster: a period found shorter is not a gait's


def make_cycle(arm, first: int, last: int, period: float | None = None,
               blend: int = 4, in_place: bool = True, mirror: bool = False,
               fps: float = 24.0) -> tuple[int, int]:
    """Turn the tracked channels of ``arm`` over frames first..last into one looping cycle.

    The period (frames) is found from the tracked channels unless given (a period under
    ``MIN_GAIT_SECONDS`` at ``fps`` is taken as not found); the cycle is the last
    full period of the range, or with ``mirror`` the period from ``first`` on, its frames past
    the range filled by the mirrored body half a period earlier. Returns (cycle start, cycle
    length). The root's location repeats in place, or advances by one cycle's travel each
    repetition when ``in_place`` is False.
    """
    sk = skeleton_from_armature(arm)
    bag = channelbag(arm)
    if bag is None:
        raise BridgeError(f"'{arm.name}' has no animation: track it first")
    curves = tracked_fcurves(arm, sk, bag)
    if not curves:
        raise BridgeError(f"'{arm.name}' has no tracked keyframes to make a cycle of")
    curves.sort(key=lambda fc: sk.index(_bone(fc)))  # the root's channels first
    frames = np.arange(first, last + 1)
    values = np.array([[fc.evaluate(f) for fc in curves] for f in frames])
    rotations = np.array([not fc.data_path.endswith("location") for fc in curves])
    if period is None:
        try:
            period = gait_period(values[:, rotations])
        except CycleError:
            period = 0.0
        if period < MIN_GAIT_SECONDS * fps:
            raise BridgeError(f"frames {first}-{last} hold too little of a walk to find its "
                              f"period: set the Period (frames per cycle)") from None
    n = int(round(period))
    if n < blend + 3:
        raise BridgeError(f"a cycle of {n} frames is too short to loop with a Blend of "
                          f"{blend} frames: set a longer Period, or a Blend of at most "
                          f"{max(n - 3, 1)}")
    if mirror:
        if 2 * len(frames) < period:
            raise BridgeError(f"frames {first}-{last} are less than half of a {n}-frame cycle: "
                              f"mirroring needs at least half a cycle")
        start = first
        cycle = complete_by_mirroring(values, period,
                                      BodyMirror(arm, curves, values, period / 2))
        _continuous_quaternions(cycle, curves)
    else:
        if n > len(frames):
            raise BridgeError(f"a cycle of {n} frames does not fit in frames {first}-{last}: "
                              f"complete it by mirroring")
        start = last - n + 1
        cycle = values[-n:]
    # the root's locations drift over a cycle (it walks): loop what is left once one
    # period's travel is taken out, then put the travel back unless walking on the spot
    drift = ~rotations
    travel = cycle[-1] - cycle[0] + (cycle[-1] - cycle[-2])
    ramp = np.outer(np.arange(n) / n, travel[drift])
    looped = cycle.copy()
    looped[:, drift] -= ramp
    looped = make_loop(looped, blend)
    # Blender repeats the span from the first key to the last: close it with the first key's
    # value one period on (plus one period's travel when walking on)
    closing = looped[0].copy()
    if not in_place:
        looped[:, drift] += ramp
        closing[drift] += travel[drift]
    looped = np.vstack([looped, closing])
    for k, fc in enumerate(curves):
        fc.keyframe_points.clear()
        fc.keyframe_points.add(n + 1)
        for i, kp in enumerate(fc.keyframe_points):
            kp.co = (start + i, looped[i, k])
            kp.interpolation = "BEZIER"
            kp.type = TRACKED
        fc.update()
        for m in list(fc.modifiers):
            fc.modifiers.remove(m)
        mod = fc.modifiers.new("CYCLES")
        if drift[k] and not in_place:
            mod.mode_before = mod.mode_after = "REPEAT_OFFSET"
    return start, n


class TWIST_OT_make_cycle(ArmatureAction, bpy.types.Operator):
    """Make the tracked motion one seamless, repeating walk cycle (its gait period found from
    the legs), in place or travelling forward"""

    bl_idname = "twist.make_cycle"
    bl_label = "Make Walk Cycle"

    period: bpy.props.FloatProperty(
        name="Period", default=0.0, min=0.0,
        description="Frames per cycle; 0 finds it from the tracked legs")
    range_is_cycle: bpy.props.BoolProperty(
        name="Frame Range Is One Cycle", default=False,
        description="The scene's frame range spans exactly one cycle: its length is the "
                    "period")
    blend: bpy.props.IntProperty(
        name="Blend", default=4, min=1,
        description="Frames at the end of the cycle bent into its start")
    in_place: bpy.props.BoolProperty(
        name="In Place", default=True,
        description="Walk on the spot; off, the root travels on by one cycle's distance each "
                    "repetition")
    mirror: bpy.props.BoolProperty(
        name="Complete by Mirroring", default=False,
        description="The frame range holds only part of a cycle (at least half): fill in the "
                    "rest with the left and right sides swapped and mirrored, half a period "
                    "later. Set the Period")

    def invoke(self, context, event):
        return context.window_manager.invoke_props_dialog(self)

    def run(self, context) -> str:
        scene = context.scene
        period = (scene.frame_end - scene.frame_start + 1 if self.range_is_cycle
                  else self.period or None)
        start, n = make_cycle(scene.twist.armature, scene.frame_start, scene.frame_end,
                              period, self.blend, self.in_place, self.mirror,
                              scene.render.fps / scene.render.fps_base)
        return f"a cycle of {n} frames from frame {start}, repeating"


CLASSES = (TWIST_OT_make_cycle,)

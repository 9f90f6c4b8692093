"""Smoothing tracked motion: a zero-phase low-pass on the tracked channels, quaternions kept
on one side (q and -q are one rotation) so that the filter never averages across a flip."""

from __future__ import annotations

import bpy
import numpy as np

from ..core.cycles import lowpass, lowpass_quaternions
from .armature_action import ArmatureAction
from .bridge import BridgeError, skeleton_from_armature
from .keyframes import TRACKED, channelbag, tracked_fcurves


def smooth_track(arm, first: int, last: int, cutoff_hz: float, fps: float) -> int:
    """Low-pass every tracked channel of ``arm`` over frames first..last: the keys tracking
    wrote on those frames get the filtered values; the user's own (the first pose, the
    corrections) and keys elsewhere stay. Returns the channels smoothed."""
    sk = skeleton_from_armature(arm)
    bag = channelbag(arm)
    curves = tracked_fcurves(arm, sk, bag) if bag is not None else []
    if not curves:
        raise BridgeError(f"'{arm.name}' has no tracked keyframes to smooth: track it first")
    frames = np.arange(first, last + 1)
    if len(frames) < 8:
        raise BridgeError(f"frames {first}-{last} are too few to filter (at least 8)")
    groups: dict[str, list] = {}
    for fc in curves:
        if fc.data_path.endswith("rotation_quaternion"):
            groups.setdefault(fc.data_path, []).append(fc)
        else:
            groups[f"{fc.data_path}[{fc.array_index}]"] = [fc]
    for group in groups.values():
        group.sort(key=lambda fc: fc.array_index)
        values = np.array([[fc.evaluate(f) for fc in group] for f in frames])
        if len(group) == 4:
            smooth = lowpass_quaternions(values, cutoff_hz, fps)
        else:
            smooth = lowpass(values, cutoff_hz, fps)
        for k, fc in enumerate(group):
            for kp in fc.keyframe_points:
                i = int(round(kp.co[0])) - first
                if 0 <= i < len(frames) and kp.co[0] == frames[i] and kp.type == TRACKED:
                    kp.co[1] = smooth[i, k]
            fc.update()
    return len(curves)


class TWIST_OT_smooth_track(ArmatureAction, bpy.types.Operator):
    """Take the jitter out of the tracked motion over the scene's frame range: a zero-phase
    low-pass filter (no lag) on every tracked channel"""

    bl_idname = "twist.smooth_track"
    bl_label = "Smooth Track"

    cutoff: bpy.props.FloatProperty(
        name="Cutoff", default=6.0, min=0.1,
        description="Motion faster than this many cycles per second (Hz) is removed; gait "
                    "is usually filtered at 4 to 8 Hz. Below half the scene's frame rate")

    def invoke(self, context, event):
        return context.window_manager.invoke_props_dialog(self)

    def run(self, context) -> str:
        scene = context.scene
        fps = scene.render.fps / scene.render.fps_base
        n = smooth_track(scene.twist.armature, scene.frame_start, scene.frame_end,
                         self.cutoff, fps)
        return f"smoothed {n} channels below {self.cutoff:g} Hz"


CLASSES = (TWIST_OT_smooth_track,)

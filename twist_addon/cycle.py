"""Make a walk cycle of the tracked motion: find the gait period from the legs' curves, keep
one period, bridge its end into its start, and let F-curve Cycles modifiers repeat it."""

from __future__ import annotations

import bpy
import numpy as np

from ..core.cycles import gait_period, make_loop
from .bridge import BridgeError, skeleton_from_armature
from .keyframes import TRACKED, channelbag, tracked_fcurves
from .reporting import ArmatureAction


def make_cycle(arm, first: int, last: int, period: float | None = None,
               blend: int = 4, in_place: bool = True) -> tuple[int, int]:
    """Turn the tracked channels of ``arm`` over frames first..last into one looping cycle.

    The period (frames) is found from the tracked channels unless given; the cycle is the last
    full period of the range. Returns (cycle start, cycle length). The root's location repeats
    in place, or advances by one cycle's travel each repetition when ``in_place`` is False.
    """
    sk = skeleton_from_armature(arm)
    bag = channelbag(arm)
    if bag is None:
        raise BridgeError(f"'{arm.name}' has no animation: track it first")
    curves = tracked_fcurves(arm, sk, bag)
    if not curves:
        raise BridgeError(f"'{arm.name}' has no tracked keyframes to make a cycle of")
    frames = np.arange(first, last + 1)
    values = np.array([[fc.evaluate(f) for fc in curves] for f in frames])
    rotations = np.array([not fc.data_path.endswith("location") for fc in curves])
    if period is None:
        period = gait_period(values[:, rotations])
    n = int(round(period))
    if n + 3 > len(frames):
        raise BridgeError(f"a cycle of {n} frames does not fit in frames {first}-{last}")
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
    blend: bpy.props.IntProperty(
        name="Blend", default=4, min=1,
        description="Frames at the end of the cycle bent into its start")
    in_place: bpy.props.BoolProperty(
        name="In Place", default=True,
        description="Walk on the spot; off, the root travels on by one cycle's distance each "
                    "repetition")

    def run(self, context) -> str:
        scene = context.scene
        start, n = make_cycle(scene.twist.armature, scene.frame_start, scene.frame_end,
                              self.period or None, self.blend, self.in_place)
        return f"a cycle of {n} frames from frame {start}, repeating"


CLASSES = (TWIST_OT_make_cycle,)

"""twist.make_cycle on a tracked-looking walk: keys written the way Track writes them."""

import numpy as np
import pytest

from support.walking import PERIOD, walking_template


def test_make_cycle_finds_the_period_and_loops_seamlessly(bpy_module, registered):
    bpy = bpy_module
    scene, arm = walking_template(bpy, registered)
    assert bpy.ops.twist.make_cycle() == {"FINISHED"}
    bag = registered.twist_addon.keyframes.channelbag(arm)
    curves = [fc for fc in bag.fcurves]
    assert curves and all(fc.modifiers and fc.modifiers[0].type == "CYCLES" for fc in curves)
    n = len(curves[0].keyframe_points) - 1  # the last key closes the cycle
    assert abs(n - PERIOD) <= 1
    start = int(curves[0].keyframe_points[0].co[0])
    for fc in curves:
        v = np.array([fc.evaluate(f) for f in range(start, start + 2 * n + 1)])
        kink = np.abs(np.diff(v, 2))  # kink[i] is at frame start + i + 1
        seam = kink[n - 2:n + 1]  # around frame start + n, where the cycle repeats
        inside = kink[2:n - 6]  # well inside the first cycle
        assert seam.max() <= 1.5 * inside.max() + 1e-5, fc.data_path
        if fc.data_path.endswith("location"):  # in place: each repetition starts where it did
            assert fc.evaluate(start + n) == pytest.approx(fc.evaluate(start), abs=1e-4)


def test_make_cycle_can_keep_walking_forward(bpy_module, registered):
    bpy = bpy_module
    scene, arm = walking_template(bpy, registered)
    bag = registered.twist_addon.keyframes.channelbag(arm)
    root_y = max((fc for fc in bag.fcurves if fc.data_path.endswith("location")),
                 key=lambda fc: abs(fc.evaluate(70) - fc.evaluate(1)))  # the walking direction
    direction = np.sign(root_y.evaluate(70) - root_y.evaluate(1))
    assert bpy.ops.twist.make_cycle(in_place=False) == {"FINISHED"}
    start = int(root_y.keyframe_points[0].co[0])
    n = len(root_y.keyframe_points) - 1
    travel = root_y.evaluate(start + n) - root_y.evaluate(start)
    assert travel == pytest.approx(direction * 0.05 * n, rel=0.05)  # one cycle's distance on
    assert root_y.evaluate(start + 2 * n) - root_y.evaluate(start + n) == pytest.approx(travel,
                                                                                      rel=1e-3)


def test_make_cycle_needs_tracked_motion(bpy_module, registered):
    bpy = bpy_module
    bpy.ops.twist.add_template_armature(template="HUMAN")
    with pytest.raises(RuntimeError, match="has no animation: track it first"):
        bpy.ops.twist.make_cycle()

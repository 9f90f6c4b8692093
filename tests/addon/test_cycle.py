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


def test_a_range_too_short_for_a_walk_or_its_blend_is_refused_with_what_to_set(bpy_module,
                                                                              registered):
    """Five frames of the walk hold no gait (a period found there would be under half a
    second); a given period shorter than the blend allows is refused too, saying what fits."""
    bpy = bpy_module
    scene, arm = walking_template(bpy, registered)
    scene.frame_start, scene.frame_end = 1, 5
    with pytest.raises(RuntimeError, match="frames 1-5 hold too little of a walk to find its "
                                           "period: set the Period"):
        bpy.ops.twist.make_cycle()
    with pytest.raises(RuntimeError, match="a cycle of 5 frames is too short to loop with a "
                                           "Blend of 4 frames: set a longer Period, or a Blend"
                                           " of at most 2"):
        bpy.ops.twist.make_cycle(period=5)


def _bone_rotations(arm, bag, frames):
    """Each tracked bone's rotation per frame as a quaternion (w, x, y, z), from its curves."""
    from mathutils import Euler, Quaternion

    out = {}
    for pb in arm.pose.bones:
        path = f'pose.bones["{pb.name}"].rotation_'
        quat = sorted((fc for fc in bag.fcurves if fc.data_path == path + "quaternion"),
                      key=lambda c: c.array_index)
        euler = [fc for fc in bag.fcurves if fc.data_path == path + "euler"]
        rows = []
        for f in frames:
            if quat:
                q = Quaternion([fc.evaluate(f) for fc in quat])
            elif euler:
                e = Euler(pb.rotation_euler, pb.rotation_mode)
                for fc in euler:
                    e[fc.array_index] = fc.evaluate(f)
                q = e.to_quaternion()
            else:
                break
            rows.append(np.array(q.normalized()))
        if rows:
            out[pb.name] = np.array(rows)
    return out


def test_mirroring_completes_sixty_percent_of_a_walk_within_half_a_degree(bpy_module,
                                                                          registered):
    """The walk keyed over 60 % of a cycle only; the rest of the cycle filled in by mirroring
    against the walk as it was keyed (its legs swing and sway sideways, its root bobs, sways
    and travels; the knees' rolls are not mirror images)."""
    bpy = bpy_module
    scene, arm = walking_template(bpy, registered)
    tw = registered.twist_addon
    bag = tw.keyframes.channelbag(arm)
    n = int(round(PERIOD))
    frames = range(1, n - 1)  # before the last frames, which bridge into the cycle's start
    truth = _bone_rotations(arm, bag, frames)
    root_loc = [fc for fc in bag.fcurves if fc.data_path.endswith("location")]
    truth_loc = np.array([[fc.evaluate(f) for fc in root_loc] for f in frames])
    scene.frame_end = int(0.6 * PERIOD)
    assert bpy.ops.twist.make_cycle(mirror=True, period=PERIOD, blend=1,
                                    in_place=False) == {"FINISHED"}
    got = _bone_rotations(arm, bag, frames)
    assert set(got) == set(truth) and len(truth) >= 10
    for bone, q in truth.items():
        err = np.degrees(2 * np.arccos(np.clip(np.abs(np.sum(q * got[bone], 1)), 0, 1)))
        assert err.max() < 0.5, (bone, err.round(2))
    loc = np.array([[fc.evaluate(f) for fc in root_loc] for f in frames])
    np.testing.assert_allclose(loc, truth_loc, atol=2e-3)
    assert int(root_loc[0].keyframe_points[0].co[0]) == 1  # the cycle starts with the range


def test_mirroring_needs_paired_bones_and_half_a_cycle(bpy_module, registered):
    bpy = bpy_module
    scene, arm = walking_template(bpy, registered)
    scene.frame_end = int(0.4 * PERIOD)
    with pytest.raises(RuntimeError, match="less than half of a 24-frame cycle"):
        bpy.ops.twist.make_cycle(mirror=True, period=PERIOD)
    with pytest.raises(RuntimeError, match="set the Period"):
        bpy.ops.twist.make_cycle(mirror=True)
    scene.frame_end = int(0.6 * PERIOD)
    arm.data.bones["RightKnee"].name = "Knee2"
    with pytest.raises(RuntimeError, match="'LeftKnee' has no tracked partner 'RightKnee'"):
        bpy.ops.twist.make_cycle(mirror=True, period=PERIOD)


def test_the_frame_range_can_be_the_cycle(bpy_module, registered):
    bpy = bpy_module
    scene, arm = walking_template(bpy, registered)
    scene.frame_start, scene.frame_end = 5, 28
    assert bpy.ops.twist.make_cycle(range_is_cycle=True) == {"FINISHED"}
    bag = registered.twist_addon.keyframes.channelbag(arm)
    keys = [kp.co[0] for kp in bag.fcurves[0].keyframe_points]
    assert keys == list(range(5, 30))  # 24 frames and the key that closes the cycle

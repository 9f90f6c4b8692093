"""Make Hinges on an imported capture whose every joint turns freely: the knees and elbows
become hinges about the capture's own axes, the pose kept; what cannot be made one is
refused, naming it, with nothing changed."""

import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

from walk_footage import JOINTS  # noqa: E402

WALK = ROOT / "example_blends" / "walk_3view"
HINGES = [name for name, spec in JOINTS.items() if spec != "ball"]


def _imported(bpy):
    """The walk's capture imported, posed on its first frame, every bone free to turn."""
    bpy.ops.import_anim.bvh(filepath=str(WALK / "truth.bvh"), axis_forward="Y", axis_up="Z",
                            frame_start=1)
    arm = bpy.context.view_layer.objects.active
    bpy.context.scene.frame_set(1)
    arm.animation_data_clear()
    bpy.context.scene.twist.armature = arm
    return arm


def _select(arm, names):
    for pb in arm.pose.bones:
        pb.select = pb.name in names


def test_bent_knees_and_elbows_become_hinges_about_the_captures_axes_the_pose_kept(
        bpy_module, registered):
    """The capture bends its knees and elbows about fixed axes (``JOINTS``'s); made hinges
    in Pose Mode from their bend on the first frame, each bone turns about that axis alone,
    bending positive within its range, every joint stays where the capture has it, and the
    armature stays in Pose Mode."""
    from core.skeleton import HINGE

    bpy = bpy_module
    arm = _imported(bpy)
    bridge = registered.twist_addon.bridge
    sk = bridge.skeleton_from_armature(arm)
    before = sk.world_positions(*bridge.pose_from_armature(arm, sk))
    bpy.ops.object.mode_set(mode="POSE")  # where the bones are selected
    _select(arm, HINGES)
    assert bpy.ops.twist.make_hinges() == {"FINISHED"}
    assert arm.mode == "POSE"
    sk = bridge.skeleton_from_armature(arm)
    R, root = bridge.pose_from_armature(arm, sk)
    np.testing.assert_allclose(sk.world_positions(R, root), before, atol=1e-5)  # metres
    for name in HINGES:
        j = sk.index(name)
        assert sk.kinds[j] == HINGE, name
        axis = np.array(JOINTS[name]["axis"]) / np.linalg.norm(JOINTS[name]["axis"])
        assert abs(sk.axes[j] @ axis) > np.cos(np.radians(1.0)), (name, sk.axes[j])
        bend = np.degrees(sk.hinge_angle(j, R[j]))
        lo, hi = np.degrees(sk.limits[j])
        assert 10 < bend and (lo, hi) == pytest.approx((-10, 165)), (name, bend, lo, hi)
        pb = arm.pose.bones[name]
        assert tuple(pb.lock_rotation) == (True, True, False) and pb.rotation_mode == "XYZ"
        assert tuple(pb.rotation_euler)[:2] == (0.0, 0.0)
    assert sk.kinds[sk.index("LeftHip")] != HINGE  # not selected: as it was


def test_a_straight_or_keyed_bone_is_refused_by_name_and_nothing_changes(bpy_module,
                                                                        registered):
    from mathutils import Matrix

    bpy = bpy_module
    arm = _imported(bpy)
    arm.pose.bones["RightElbow"].matrix_basis = Matrix.Identity(4)  # straight, as at rest
    knee = arm.pose.bones["LeftKnee"]
    knee.keyframe_insert("rotation_quaternion" if knee.rotation_mode == "QUATERNION"
                         else "rotation_euler", frame=1)
    _select(arm, ["RightElbow", "LeftKnee", "LeftElbow"])
    rolls = {b.name: tuple(b.matrix_local.col[2]) for b in arm.data.bones}
    with pytest.raises(RuntimeError) as refused:
        bpy.ops.twist.make_hinges()
    assert "RightElbow is bent 0 degrees" in str(refused.value)
    assert "LeftKnee's rotation is keyed" in str(refused.value)
    assert "LeftElbow" not in str(refused.value)
    assert {b.name: tuple(b.matrix_local.col[2]) for b in arm.data.bones} == rolls
    assert not any(any(pb.lock_rotation) for pb in arm.pose.bones)
    _select(arm, [])
    with pytest.raises(RuntimeError, match="select the bones to make hinges"):
        bpy.ops.twist.make_hinges()

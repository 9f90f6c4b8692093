"""Retargeting from the CMU skeleton onto Blender's Rigify metarig and back."""

import numpy as np
import pytest

from core import se3
from core.bvh import read_bvh, write_bvh

FRAMES = 6


def _import(bpy, path):
    bpy.ops.import_anim.bvh(filepath=str(path), axis_forward="Y", axis_up="Z", frame_start=1)
    return bpy.context.view_layer.objects.active


def _directions(arm, names):
    W = np.array(arm.matrix_world)
    out = {}
    for n in names:
        pb = arm.pose.bones[n]
        head = (W @ np.append(np.array(pb.head), 1))[:3]
        out[n] = (W @ np.append(np.array(pb.tail), 1))[:3] - head
    return out


def test_cmu_to_rigify_and_back_keeps_every_mapped_bone_within_a_degree(
        bpy_module, registered, cmu_walk, tmp_path):
    bpy = bpy_module
    import addon_utils

    addon_utils.enable("rigify", default_set=False)
    b = read_bvh(cmu_walk)
    b.motion = b.motion[600:600 + FRAMES]
    write_bvh(b, tmp_path / "walk.bvh")
    scene = bpy.context.scene
    cmu = _import(bpy, tmp_path / "walk.bvh")
    scene.frame_start, scene.frame_end = 1, FRAMES
    bpy.ops.object.armature_human_metarig_add()
    rig = bpy.context.active_object
    rig.location = (2.0, 0.0, 0.0)
    back = _import(bpy, tmp_path / "walk.bvh")  # the CMU skeleton again, to receive the motion
    back.animation_data_clear()
    back.location = (-2.0, 0.0, 0.0)
    for pb in back.pose.bones:
        pb.rotation_mode = "QUATERNION"
        pb.rotation_quaternion, pb.location = (1, 0, 0, 0), (0, 0, 0)

    scene.twist.armature = cmu
    assert bpy.ops.twist.retarget(target=rig.name, source_preset="CMU",
                                  target_preset="RIGIFY") == {"FINISHED"}
    scene.twist.armature = rig
    assert bpy.ops.twist.retarget(target=back.name, source_preset="RIGIFY",
                                  target_preset="CMU") == {"FINISHED"}

    mapped = list(registered.twist_addon.retarget.bone_map("CMU", "RIGIFY"))
    for f in range(1, FRAMES + 1):
        scene.frame_set(f)
        a, c = _directions(cmu, mapped), _directions(back, mapped)
        err = np.degrees(se3.angle_between_vectors(np.array([a[n] for n in mapped]),
                                                   np.array([c[n] for n in mapped])))
        assert err.max() < 1.0, dict(zip(mapped, err.round(2)))
        travel_src = np.array(cmu.pose.bones["Hips"].head)
        travel_back = np.array(back.pose.bones["Hips"].head)
        np.testing.assert_allclose(travel_back, travel_src, atol=1e-3)  # legs' ratio undone


def test_retarget_names_what_is_missing(bpy_module, registered):
    bpy = bpy_module
    bpy.ops.twist.add_template_armature(template="WALKER")
    other = bpy.context.scene.twist.armature
    bpy.ops.twist.add_template_armature(template="HUMAN")
    with pytest.raises(RuntimeError, match="no bone of the CMU to Rigify map is in both"):
        bpy.ops.twist.retarget(target=other.name)
    with pytest.raises(RuntimeError, match="no armature named 'nothing'"):
        bpy.ops.twist.retarget(target="nothing")


def test_the_scene_bone_map_loads_from_presets_and_its_edits_are_used(bpy_module, registered,
                                                                      cmu_walk, tmp_path):
    """Loaded from the CMU and Rigify presets, then edited: the thighs swapped. The Rigify
    thigh.R then turns from its rest as the CMU LeftHip turns from its own (world rotations),
    and no longer as the RightHip does."""
    bpy = bpy_module
    import addon_utils

    addon_utils.enable("rigify", default_set=False)
    b = read_bvh(cmu_walk)
    b.motion = b.motion[600:602]
    write_bvh(b, tmp_path / "walk.bvh")
    scene = bpy.context.scene
    cmu = _import(bpy, tmp_path / "walk.bvh")
    scene.frame_start, scene.frame_end = 1, 2
    bpy.ops.object.armature_human_metarig_add()
    rig = bpy.context.active_object
    scene.twist.armature = cmu
    assert bpy.ops.twist.load_bone_map(source_preset="CMU", target_preset="RIGIFY") == {
        "FINISHED"}
    pairs = scene.twist.bone_map
    assert len(pairs) == len(registered.twist_addon.retarget.ROLES)
    by_source = {p.source: p for p in pairs}
    by_source["LeftHip"].target, by_source["RightHip"].target = "thigh.R", "thigh.L"
    scene.twist.active_bone_pair = 0
    assert bpy.ops.twist.edit_bone_map(action="ADD") == {"FINISHED"}
    assert len(pairs) == len(registered.twist_addon.retarget.ROLES) + 1
    assert (pairs[1].source, pairs[1].target) == ("", "")  # after the selected pair
    assert bpy.ops.twist.edit_bone_map(action="REMOVE") == {"FINISHED"}
    assert "" not in {p.source for p in pairs}
    assert bpy.ops.twist.retarget(target=rig.name) == {"FINISHED"}
    scene.frame_set(2)

    def world(arm, m):
        r = np.array(arm.matrix_world @ m)[:3, :3]
        return r / np.linalg.norm(r, axis=0)

    def turn(name):  # the CMU bone's world rotation from its rest
        pb = cmu.pose.bones[name]
        return world(cmu, pb.matrix) @ world(cmu, pb.bone.matrix_local).T

    thigh = rig.pose.bones["thigh.R"]
    got = world(rig, thigh.matrix)
    rest = world(rig, thigh.bone.matrix_local)
    angle = [np.degrees(se3.angle_between_vectors(got[:, 1], turn(n) @ rest[:, 1]))
             for n in ("LeftHip", "RightHip")]
    assert angle[0] < 1.0 and angle[1] > 5.0, angle
    pairs.clear()
    for p in ("Nothing", "Hips"), ("Hips", "nothing"):
        pair = pairs.add()
        pair.source, pair.target = p
    with pytest.raises(RuntimeError, match="no bone of the scene's bone map is in both"):
        bpy.ops.twist.retarget(target=rig.name)

"""The volumetric body rides on the armature: every ellipsoid stays its blob, frame by frame."""

import numpy as np
import pytest


def test_volumetric_body_follows_the_tracked_armature(bpy_module, registered):
    bpy = bpy_module
    from support.walking import walking_template

    scene, arm = walking_template(bpy, registered, frames=12)
    scene.frame_set(1)
    assert bpy.ops.twist.add_volumetric_body() == {"FINISHED"}
    tw = registered.twist_addon
    sk = tw.bridge.skeleton_from_armature(arm)
    bodies = {o.name: o for o in bpy.data.collections["Twist body"].objects}
    assert len(bodies) == len(sk.blobs)
    left = bodies["body LeftKnee"].data.materials[0].diffuse_color[:]
    right = bodies["body RightKnee"].data.materials[0].diffuse_color[:]
    assert left != right  # a material per side
    for f in (1, 5, 12):
        scene.frame_set(f)
        R, root = tw.bridge.pose_from_armature(arm, sk)
        g = sk.segment_motions(sk.joint_frames(R, root))
        for b in sk.blobs:
            want = g[b.joint] @ tw.body.blob_matrix(b)
            got = np.array(bodies[f"body {sk.names[b.joint]}"].matrix_world)
            np.testing.assert_allclose(got, want, atol=1e-5)


def test_no_blobs_no_body(bpy_module, registered):
    bpy = bpy_module
    bpy.ops.twist.add_template_armature(template="WALKER")
    arm = bpy.context.scene.twist.armature
    bpy.context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="EDIT")
    for eb in arm.data.edit_bones:
        eb.head_radius = eb.tail_radius = 0.0
    bpy.ops.object.mode_set(mode="OBJECT")
    with pytest.raises(RuntimeError, match="no bone of 'Walker' has a blob"):
        bpy.ops.twist.add_volumetric_body()


def test_stick_figure_rods_run_from_head_to_tail_of_their_bones(bpy_module, registered):
    bpy = bpy_module
    from support.walking import walking_template

    scene, arm = walking_template(bpy, registered, frames=8)
    scene.frame_set(1)
    assert bpy.ops.twist.add_volumetric_body(sticks=True) == {"FINISHED"}
    sticks = [o for o in bpy.data.collections["Twist body"].objects
              if o.name.startswith("stick ")]
    sk = registered.twist_addon.bridge.skeleton_from_armature(arm)
    assert len(sticks) == len(sk.blobs)
    W = np.array(arm.matrix_world)
    for f in (1, 6):
        scene.frame_set(f)
        for o in sticks:
            pb = arm.pose.bones[o.parent_bone]
            M = np.array(o.matrix_world)
            z = np.array([v.co.z for v in o.data.vertices])
            for end, point in ((z.min(), pb.head), (z.max(), pb.tail)):  # the rod's caps
                want = (W @ np.append(np.array(point), 1))[:3]
                np.testing.assert_allclose((M @ [0, 0, end, 1])[:3], want, atol=1e-5)
            assert np.linalg.norm(M[:3, 0]) < 0.5 * np.linalg.norm(M[:3, 2])  # thin


def test_size_blobs_gives_an_imported_armature_a_body_s_proportions(bpy_module, registered,
                                                                    cmu_walk):
    bpy = bpy_module
    bpy.ops.import_anim.bvh(filepath=str(cmu_walk), axis_forward="Y", axis_up="Z")
    arm = bpy.context.view_layer.objects.active
    arm.scale = (0.5,) * 3  # envelope radii are the bone's own, before the object's scale
    bpy.context.view_layer.update()
    bpy.context.scene.twist.armature = arm
    bridge = registered.twist_addon.bridge

    def radii():
        sk = bridge.skeleton_from_armature(arm)
        return sk, {sk.names[b.joint]: b.radii for b in sk.blobs}

    sk, before = radii()
    # Blender's importer gives every bone the same envelope: the forearm as thick as the chest
    assert before["LeftElbow"][1] == pytest.approx(before["Chest"][1])
    assert bpy.ops.twist.size_blobs() == {"FINISHED"}
    sk, after = radii()
    H = sk.height()
    for name in ("lowerback", "Chest", "LHipJoint", "RHipJoint"):
        assert np.all(after[name][1:] >= 0.065 * H - 1e-6), name
    for name in ("LeftElbow", "RightKnee", "LeftShoulder"):
        L = 2 * after[name][0]  # the blob spans the bone
        np.testing.assert_allclose(after[name][1:], max(0.16 * L, 0.022 * H), rtol=1e-5)
    lengths = {b.name: 0.5 * b.length for b in arm.data.bones}
    assert set(after) == {n for n, L in lengths.items() if L >= 0.03 * H}
    assert after["Chest"][1] > 2 * after["LeftElbow"][1]

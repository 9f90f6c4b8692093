"""Armatures, poses and cameras through the bridge, against what Blender itself computes."""

import numpy as np
import pytest


def _armature(bpy, rotated=True):
    """A three-bone arm with rolls and bent rest axes on a rotated, scaled object."""
    from mathutils import Euler, Vector

    arm_data = bpy.data.armatures.new("rig")
    arm = bpy.data.objects.new("rig", arm_data)
    bpy.context.collection.objects.link(arm)
    bpy.context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="EDIT")
    spec = [("root", None, (0, 0, 0), (0, 0.1, 0.3), 0.3),
            ("upper", "root", (0, 0.1, 0.3), (0.3, 0.2, 0.5), 1.1),
            ("lower", "upper", (0.3, 0.2, 0.5), (0.5, -0.1, 0.6), -0.7)]
    for name, parent, head, tail, roll in spec:
        b = arm_data.edit_bones.new(name)
        b.head, b.tail, b.roll = Vector(head), Vector(tail), roll
        b.head_radius = b.tail_radius = 0.05
        if parent:
            b.parent = arm_data.edit_bones[parent]
            b.use_connect = True
    bpy.ops.object.mode_set(mode="OBJECT")
    if rotated:
        arm.rotation_euler = Euler((0.3, -0.5, 1.2))
        arm.location = (1.0, -2.0, 0.5)
        arm.scale = (1.5, 1.5, 1.5)
    bpy.context.view_layer.update()
    return arm


def _world_heads_tails(arm):
    W = np.array(arm.matrix_world)
    heads = [(W @ np.append(np.array(pb.head), 1))[:3] for pb in arm.pose.bones]
    tails = [(W @ np.append(np.array(pb.tail), 1))[:3] for pb in arm.pose.bones]
    return np.array(heads), np.array(tails)


def test_forward_kinematics_match_blenders_pose(bpy_module, addon):
    bpy = bpy_module
    bridge = addon.twist_addon.bridge
    arm = _armature(bpy)
    sk = bridge.skeleton_from_armature(arm)
    rng = np.random.default_rng(0)
    for pb in arm.pose.bones:
        q = rng.normal(size=4)
        pb.rotation_mode = "QUATERNION"
        pb.rotation_quaternion = q / np.linalg.norm(q)
    arm.pose.bones["root"].location = (0.1, -0.2, 0.05)
    arm.pose.bones["lower"].rotation_mode = "XZY"
    arm.pose.bones["lower"].rotation_euler = (0.4, -0.3, 1.1)
    bpy.context.view_layer.update()
    R, root = bridge.pose_from_armature(arm, sk)
    M = sk.joint_frames(R, root)
    heads, tails = _world_heads_tails(arm)
    np.testing.assert_allclose(M[:, :3, 3], heads, atol=1e-6)
    g_all = sk.segment_motions(M)
    for b in sk.blobs:  # each blob's far end is its bone's tail
        g = g_all[b.joint]
        far = b.centre + b.Q[:, 0] * b.radii[0]
        np.testing.assert_allclose(g[:3, :3] @ far + g[:3, 3], tails[b.joint], atol=1e-6)


def test_core_poses_written_back_reproduce_themselves(bpy_module, addon):
    bpy = bpy_module
    bridge = addon.twist_addon.bridge
    from core import se3

    arm = _armature(bpy)
    sk = bridge.skeleton_from_armature(arm)
    rng = np.random.default_rng(1)
    R = np.array([se3.exp_so3(rng.normal(0, 0.6, 3)) for _ in range(sk.n_joints)])
    root = sk.rest_positions[0] + rng.normal(0, 0.1, 3)
    Q, loc = bridge.armature_rotations(arm, sk, R, root)
    from mathutils import Matrix

    for j, name in enumerate(sk.names):
        pb = arm.pose.bones[name]
        pb.rotation_mode = "QUATERNION"
        pb.rotation_quaternion = Matrix(Q[j].tolist()).to_quaternion()
    arm.pose.bones[sk.names[0]].location = loc
    bpy.context.view_layer.update()
    R2, root2 = bridge.pose_from_armature(arm, sk)
    np.testing.assert_allclose(R2, R, atol=1e-6)
    np.testing.assert_allclose(root2, root, atol=1e-6)


def test_locks_choose_hinges_balls_and_fixed_joints(bpy_module, addon):
    bpy = bpy_module
    bridge = addon.twist_addon.bridge
    arm = _armature(bpy)
    arm.pose.bones["lower"].lock_rotation = (True, False, True)  # a hinge about local y
    arm.pose.bones["upper"].lock_rotation = (False, False, False)
    sk = bridge.skeleton_from_armature(arm)
    assert sk.kinds == ["fixed", "ball", "hinge"]
    C = bridge.bone_frames(arm)
    np.testing.assert_allclose(sk.axes[2], C[2][:, 1])
    assert np.all(np.isinf(sk.limits[2]))  # no IK limit: free
    lower = arm.pose.bones["lower"]
    lower.use_ik_limit_y, lower.ik_min_y, lower.ik_max_y = True, -0.2, 2.5
    lower.use_ik_limit_x, lower.ik_min_x = True, -1.0  # a locked axis's limit is not the hinge's
    np.testing.assert_allclose(bridge.skeleton_from_armature(arm).limits[2], [-0.2, 2.5])
    lower.rotation_mode = "XYZ"
    lower.rotation_euler = (0, 0.7, 0)
    R, _ = bridge.pose_from_armature(arm, sk)
    assert abs(sk.hinge_angle(2, R[2]) - 0.7) < 1e-6  # the angle the limits bound
    lower.lock_rotation = (True, True, True)
    assert bridge.skeleton_from_armature(arm).kinds[2] == "fixed"


@pytest.mark.parametrize("kind, fit, size", [
    ("ORTHO", "AUTO", (480, 360)), ("PERSP", "AUTO", (480, 360)), ("PERSP", "AUTO", (360, 480)),
    ("PERSP", "VERTICAL", (480, 360)), ("PERSP", "HORIZONTAL", (360, 480))])
def test_cameras_project_like_blender(bpy_module, addon, kind, fit, size):
    """World points land where Blender's own camera mapping puts them, for orthographic and
    perspective cameras, each sensor fit, portrait and landscape, with the lens shifted."""
    bpy = bpy_module
    bridge = addon.twist_addon.bridge
    from bpy_extras.object_utils import world_to_camera_view
    from mathutils import Euler, Vector

    scene = bpy.context.scene
    W, H = size
    scene.render.resolution_x, scene.render.resolution_y = W, H
    cam_data = bpy.data.cameras.new("cam")
    cam_data.type = kind
    cam_data.ortho_scale = 3.2
    cam_data.lens, cam_data.sensor_width, cam_data.sensor_height = 42.0, 36.0, 20.0
    cam_data.sensor_fit = fit
    cam_data.shift_x, cam_data.shift_y = 0.05, -0.1
    cam = bpy.data.objects.new("cam", cam_data)
    scene.collection.objects.link(cam)
    cam.location = (4.0, -3.0, 1.5)
    cam.rotation_euler = Euler((1.3, 0.1, 0.9))
    bpy.context.view_layer.update()
    view = bridge.view_from_camera(cam, scene)
    assert view.central == (kind == "PERSP")
    pts = np.random.default_rng(2).normal(0, 0.8, (20, 3))
    for X in pts:
        u, v, _ = world_to_camera_view(scene, cam, Vector(X))
        expect = np.array([u * W - 0.5, (1 - v) * H - 0.5])
        np.testing.assert_allclose(view.project(X), expect, atol=2e-3)  # mathutils: float32
    bpy.data.objects.remove(cam)


def test_bad_objects_are_refused_with_a_reason(bpy_module, addon):
    bpy = bpy_module
    bridge = addon.twist_addon.bridge
    empty = bpy.data.objects.new("empty_rig", bpy.data.armatures.new("empty_rig"))
    with pytest.raises(bridge.BridgeError, match="'empty_rig' has no bones"):
        bridge.skeleton_from_armature(empty)
    pano = bpy.data.objects.new("pano", bpy.data.cameras.new("pano"))
    pano.data.type = "PANO"
    with pytest.raises(bridge.BridgeError, match="'pano' is panoramic; the tracker needs an "
                       "orthographic or perspective camera"):
        bridge.view_from_camera(pano, bpy.context.scene)
    arm = _armature(bpy, rotated=False)
    arm.scale = (1, 2, 1)
    bpy.context.view_layer.update()
    with pytest.raises(bridge.BridgeError, match="non-uniform scale"):
        bridge.skeleton_from_armature(arm)


@pytest.mark.parametrize("template", ["HUMAN", "HUMAN_LOWER_BACK", "WALKER", "QUADRUPED"])
def test_template_armatures_come_back_as_their_skeletons(bpy_module, registered, template):
    bpy = bpy_module
    from core import skeleton

    bridge = registered.twist_addon.bridge
    assert bpy.ops.twist.add_template_armature(template=template) == {"FINISHED"}
    arm = bpy.context.scene.twist.armature
    back = bridge.skeleton_from_armature(arm)
    _, _, name, kwargs = registered.twist_addon.templates.TEMPLATES[template]
    core_sk = getattr(skeleton, name)(**kwargs)
    assert back.names == core_sk.names
    assert back.kinds[1:] == core_sk.kinds[1:]  # the root moves by its keys, not by a joint
    assert back.dof_names() == core_sk.dof_names()
    T = bridge._CORE_TO_BLENDER
    np.testing.assert_allclose(back.offsets[1:], core_sk.offsets[1:] @ T.T, atol=1e-6)
    dj, da = back.dof_joints_and_axes()
    cj, ca = core_sk.dof_joints_and_axes()
    hinge = [k for k, j in enumerate(cj) if core_sk.kinds[j] == "hinge"]
    np.testing.assert_allclose(np.abs(da[hinge]), np.abs(ca[hinge] @ T.T), atol=1e-6)
    for j in range(core_sk.n_joints):
        if np.all(np.isinf(core_sk.limits[j])):
            assert np.all(np.isinf(back.limits[j])), core_sk.names[j]
            continue
        # the same turns allowed: each end of the range as a rotation vector (the bone's
        # axis may point against the template's)
        ends = [sorted(map(tuple, np.round(np.outer(limits, axis), 6))) for limits, axis in
                [(back.limits[j], back.axes[j]), (core_sk.limits[j], core_sk.axes[j] @ T.T)]]
        assert ends[0] == ends[1], core_sk.names[j]


def test_overlay_outlines_lie_on_the_projected_blobs(bpy_module, registered):
    from core import raycast
    from core.camera import View
    from core.se3 import Similarity, exp_so3
    from core.skeleton import human_template

    overlay = registered.twist_addon.overlay
    sk = human_template()
    rng = np.random.default_rng(3)
    R = np.array([exp_so3(rng.normal(0, 0.3, 3)) for _ in range(sk.n_joints)])
    cam_R = exp_so3(np.array([0.2, 1.0, -0.1]))
    view = View(Similarity(200.0, cam_R, np.array([0, 0, 5.0])), np.array([200.0, 200.0]))
    loops = overlay.silhouette_loops(sk, R, sk.rest_positions[0], cam_R[2])
    g = sk.segment_motions(sk.joint_frames(R, sk.rest_positions[0]))
    A, C = raycast.blob_frames(sk.blobs, g)
    for i, loop in enumerate(loops):
        y = (loop - C[i]) @ A[i].T  # on the blob's surface ...
        np.testing.assert_allclose(np.linalg.norm(y, axis=1), 1.0, atol=1e-9)
        pix = view.project(loop)  # ... and on its outline: half a pixel in hits, out misses
        centre = view.project(C[i])
        inward = (centre - pix) / np.linalg.norm(centre - pix, axis=1, keepdims=True)
        assert np.all(raycast.cast(view, pix + 0.5 * inward, [sk.blobs[i]], g).label == 0)
        assert np.all(raycast.cast(view, pix - 0.5 * inward, [sk.blobs[i]], g).label == -1)

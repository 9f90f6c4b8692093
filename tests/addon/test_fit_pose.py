"""twist.import_markers and twist.fit_pose: markers in three views bring the armature back to
the pose they were projected from."""

import numpy as np
import pytest


def _scene_with_views(bpy, registered):
    from mathutils import Euler

    bpy.ops.twist.add_template_armature(template="HUMAN")
    scene = bpy.context.scene
    scene.render.resolution_x, scene.render.resolution_y = 640, 480
    for i, yaw in enumerate((0, 90, 50)):
        data = bpy.data.cameras.new(f"cam{i}")
        data.type, data.ortho_scale = "ORTHO", 2.6
        cam = bpy.data.objects.new(f"cam{i}", data)
        scene.collection.objects.link(cam)
        a = np.radians(yaw)
        cam.location = (10 * np.sin(a), -10 * np.cos(a), 1.0)
        cam.rotation_euler = Euler((np.pi / 2, 0, a))
        view = scene.twist.views.add()
        view.camera = cam
    bpy.context.view_layer.update()
    return scene, scene.twist.armature


def test_fitting_markers_recovers_the_pose(bpy_module, registered, tmp_path):
    bpy = bpy_module
    from mathutils import Quaternion

    scene, arm = _scene_with_views(bpy, registered)
    tw = registered.twist_addon
    sk = tw.bridge.skeleton_from_armature(arm)
    rng = np.random.default_rng(0)
    for name, kind in zip(sk.names, sk.kinds):
        pb = arm.pose.bones[name]
        if kind == "ball":
            pb.rotation_quaternion = Quaternion(rng.normal(0, 0.3, 3), 0.5)
        elif kind == "hinge":
            pb.rotation_euler[2] = rng.uniform(0.2, 1.0)
    bpy.context.view_layer.update()
    R, root = tw.bridge.pose_from_armature(arm, sk)
    truth = sk.world_positions(R, root)
    rows = ["view,bone,x,y"]
    for i, v in enumerate(scene.twist.views):
        view = tw.bridge.view_from_camera(v.camera, scene)
        for j, name in enumerate(sk.names):
            if (i + j) % 5:  # each view misses a few joints
                x, y = view.project(truth[j]) + rng.normal(0, 0.5, 2)
                rows.append(f"{i + 1 if i else v.camera.name},{name},{x:.3f},{y:.3f}")
    (tmp_path / "markers.csv").write_text("\n".join(rows) + "\n")
    for pb in arm.pose.bones:  # back to the rest pose: the fit starts from there
        pb.rotation_quaternion = (1, 0, 0, 0)
        pb.rotation_euler = (0, 0, 0)
    assert bpy.ops.twist.import_markers(filepath=str(tmp_path / "markers.csv")) == {"FINISHED"}
    assert sum(len(v.markers) for v in scene.twist.views) == len(rows) - 1
    assert bpy.ops.twist.fit_pose() == {"FINISHED"}
    bpy.context.view_layer.update()
    R2, root2 = tw.bridge.pose_from_armature(arm, sk)
    got = sk.world_positions(R2, root2)
    assert np.abs(got - truth).max() < 0.01  # metres


def test_bad_markers_are_refused(bpy_module, registered, tmp_path):
    bpy = bpy_module
    scene, arm = _scene_with_views(bpy, registered)
    (tmp_path / "bad.csv").write_text("1,LeftKnee,12,nope\n")
    with pytest.raises(RuntimeError, match="bad.csv, row 1: x and y must be numbers"):
        bpy.ops.twist.import_markers(filepath=str(tmp_path / "bad.csv"))
    (tmp_path / "few.csv").write_text("1,LeftKnee,100,200\n2,Neck,300,100\n")
    bpy.ops.twist.import_markers(filepath=str(tmp_path / "few.csv"))
    with pytest.raises(RuntimeError, match="click at least"):
        bpy.ops.twist.fit_pose()

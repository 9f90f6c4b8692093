"""A scene for the marker and fit tests: the human template seen by three cameras."""

import numpy as np


def three_view_scene(bpy, registered):
    """The human template, 640x480, three orthographic cameras around it (yaw 0, 90, 50),
    each a view; returns the scene and the armature."""
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


def one_view_example(bpy, registered, name: str):
    """An example scene of one view opened: (scene, armature, the view's item, its core
    ``View``, the armature's core skeleton)."""
    from pathlib import Path

    examples = Path(__file__).resolve().parents[2] / "example_blends"
    bpy.ops.wm.open_mainfile(filepath=str(examples / name))
    scene = bpy.context.scene
    tw = registered.twist_addon
    arm, view_pg = scene.twist.armature, scene.twist.views[0]
    view = tw.bridge.view_from_camera(view_pg.camera, scene)
    return scene, arm, view_pg, view, tw.bridge.skeleton_from_armature(arm)


def projected_points(bridge, arm, sk, view, names) -> dict:
    """Where ``view`` shows each named point of the armature's current pose: a joint, or
    ``"<joint>/end"``, the tip of its end site."""
    M = sk.joint_frames(*bridge.pose_from_armature(arm, sk))
    out = {}
    for name in names:
        joint, _, end = name.partition("/")
        j = sk.index(joint)
        X = M[j, :3, :3] @ sk.end_sites[j][0] + M[j, :3, 3] if end else M[j, :3, 3]
        out[name] = view.project(X[None])[0]
    return out

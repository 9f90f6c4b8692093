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

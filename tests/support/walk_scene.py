"""A Blender scene ready to track the rendered CMU walk: the capture imported as an armature
and posed on frame 1, its tracked bones unlocked (as balls), envelope radii from the
benchmark's blobs, one orthographic camera and view per rendered view. Needs the add-on
registered (``scene.twist``)."""

from pathlib import Path

import numpy as np
from walk_footage import BLOBS, JOINTS, add_camera, camera_rotations

TRACKED = list(JOINTS)


def walk_scene(bpy, folder: Path, views: list[str], last_frame: int):
    """Build it in the current scene (resetting is the caller's: a factory reset disables an
    installed extension)."""
    bpy.ops.import_anim.bvh(filepath=str(folder / "truth.bvh"), axis_forward="Y", axis_up="Z",
                            frame_start=1)
    arm = bpy.context.view_layer.objects.active
    scene = bpy.context.scene
    scene.frame_set(1)
    arm.animation_data_clear()  # the pose of frame 1 stays: the user's initial pose
    for pb in arm.pose.bones:
        pb.lock_rotation = (pb.name not in TRACKED,) * 3
    bpy.context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="EDIT")
    for eb in arm.data.edit_bones:
        spec = BLOBS.get(eb.name, {"radius": 0.0})
        r = 0.0 if spec is False else float(np.mean(spec.get("radii", [spec.get("radius")])))
        eb.head_radius = eb.tail_radius = r
    bpy.ops.object.mode_set(mode="OBJECT")
    scene.render.resolution_x, scene.render.resolution_y = 480, 360
    scene.frame_start, scene.frame_end = 1, last_frame
    scene.twist.armature = arm
    rotations = camera_rotations()
    for v in views:
        cam = add_camera(bpy, v, rotations[v])
        view = scene.twist.views.add()
        view.camera, view.images, view.first_frame = cam, str(folder / v / "*.png"), 1
    scene.frame_set(1)
    return scene, arm

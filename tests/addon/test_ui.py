"""The sidebar panels drawn into a recording stand-in layout, and adding and removing views."""

import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

from support.layout import draw_panel

ROOT = Path(__file__).resolve().parents[2]


def test_panels_draw_existing_properties_and_operators(bpy_module, registered, tmp_path):
    bpy = bpy_module
    panels = registered.twist_addon.panels
    png = tmp_path / "f_0001.png"
    cv2.imwrite(str(png), np.zeros((36, 48, 3), np.uint8))
    bpy.ops.twist.add_view(filepath=str(png))
    bpy.context.scene.twist.result.diverged_frames = "12 (the body left the image of view 1)"
    drawn_props, drawn_ops = set(), set()
    for cls in panels.CLASSES:
        if not issubclass(cls, bpy.types.Panel):
            continue
        assert cls.poll(bpy.context) if hasattr(cls, "poll") else True
        for name, args, _ in draw_panel(bpy, cls):
            if name == "prop":
                data, prop = args[0], args[1]
                assert prop in data.bl_rna.properties, (cls.__name__, prop)
                assert data.bl_rna.properties[prop].description, (cls.__name__, prop)
                drawn_props.add(prop)
            elif name in ("operator", "operator_menu_enum"):
                op = args[0]
                mod, fn = op.split(".")
                rna = getattr(getattr(bpy.ops, mod), fn).get_rna_type()
                assert rna.description, op
                drawn_ops.add(op)
            elif name == "template_list":
                assert args[0] in ("TWIST_UL_views", "TWIST_UL_bone_map")
                assert args[3] in args[2].bl_rna.properties
    assert {"armature", "mode", "direction", "levels", "stop_on_divergence",
            "frames_tracked", "first_frame"} <= drawn_props
    assert {"twist.track", "twist.clear_track", "twist.add_view", "twist.remove_view",
            "twist.add_template_armature", "twist.smooth_track", "twist.make_cycle",
            "twist.retarget", "twist.load_bone_map", "twist.edit_bone_map",
            "twist.add_plate_view", "twist.add_calibrated_views"} <= drawn_ops


def test_add_and_remove_views(bpy_module, registered, tmp_path):
    bpy = bpy_module
    for i in range(4):
        cv2.imwrite(str(tmp_path / f"side_{i:04d}.png"), np.full((30, 40, 3), 50 * i, np.uint8))
    scene = bpy.context.scene
    assert bpy.ops.twist.add_view(filepath=str(tmp_path / "side_0002.png"),
                                  first_frame=5) == {"FINISHED"}
    view = scene.twist.views[0]
    assert view.camera.data.type == "ORTHO" and view.first_frame == 5
    bg = view.camera.data.background_images[0]
    assert bg.image.source == "SEQUENCE" and bg.image_user.frame_duration == 4
    assert (scene.render.resolution_x, scene.render.resolution_y) == (40, 30)
    assert view.images.endswith("*.png")
    assert (scene.frame_start, scene.frame_end) == (5, 8)  # the footage's frames
    for i in range(3):  # a second view whose footage ends sooner shortens the scene
        cv2.imwrite(str(tmp_path / f"end_{i:04d}.jpg"), np.zeros((30, 40, 3), np.uint8))
    assert bpy.ops.twist.add_view(filepath=str(tmp_path / "end_0000.jpg"),
                                  first_frame=5) == {"FINISHED"}
    assert (scene.frame_start, scene.frame_end) == (5, 7)
    assert bpy.ops.twist.remove_view() == {"FINISHED"}
    with pytest.raises(RuntimeError, match="missing.png: no such image or movie file"):
        bpy.ops.twist.add_view(filepath=str(tmp_path / "missing.png"))
    assert bpy.ops.twist.remove_view() == {"FINISHED"}
    assert len(scene.twist.views) == 0 and "View 1" in bpy.data.objects


def test_a_movie_becomes_a_view_with_the_clip_behind_its_camera(bpy_module, registered,
                                                                 tmp_path):
    bpy = bpy_module
    movie = tmp_path / "walk.avi"
    writer = cv2.VideoWriter(str(movie), cv2.VideoWriter_fourcc(*"MJPG"), 15, (64, 48))
    for i in range(6):
        writer.write(np.full((48, 64, 3), 30 * i, np.uint8))
    writer.release()
    assert bpy.ops.twist.add_view(filepath=str(movie), first_frame=3) == {"FINISHED"}
    scene = bpy.context.scene
    view = scene.twist.views[0]
    bg = view.camera.data.background_images[0]
    assert bg.source == "MOVIE_CLIP" and bg.clip.frame_duration == 6
    assert (scene.render.resolution_x, scene.render.resolution_y) == (64, 48)
    views = registered.twist_addon.views
    frames = views.footage_frames(view, [4, 8, 3])
    assert len(frames) == 3
    assert [int(round(frames[k].mean() / 30)) for k in range(3)] == [1, 5, 0]
    with pytest.raises(registered.twist_addon.bridge.BridgeError, match="no image for frame 9"):
        views.footage_frames(view, [9])


def test_a_file_that_is_no_movie_is_refused_before_anything_is_made(bpy_module, registered,
                                                                    tmp_path):
    bpy = bpy_module
    fake = tmp_path / "holiday.mp4"
    fake.write_bytes(b"not a movie at all" * 100)
    cameras = len(bpy.data.objects)
    with pytest.raises(RuntimeError, match="holiday.mp4: Blender cannot read it as a movie"):
        bpy.ops.twist.add_view(filepath=str(fake))
    assert len(bpy.context.scene.twist.views) == 0 and len(bpy.data.objects) == cameras
    assert not bpy.data.movieclips


def test_track_without_an_armature_says_why_it_cannot_run(bpy_module, registered):
    bpy = bpy_module
    assert not bpy.ops.twist.track.poll()
    with pytest.raises(RuntimeError, match="Set the armature to track first"):
        bpy.ops.twist.track()


def test_a_plate_becomes_a_view_of_its_cells(bpy_module, registered, tmp_path):
    """Add View from Plate cuts the plate beside itself and adds the cells as the view's
    frames; the scene's range is the cells'; a file that is no plate is refused."""
    bpy = bpy_module
    plate = tmp_path / "plate_camel.png"
    shutil.copy(ROOT / "example_blends" / "muybridge_plates" / plate.name, plate)
    assert bpy.ops.twist.add_plate_view(filepath=str(plate), first_frame=1) == {"FINISHED"}
    scene = bpy.context.scene
    (view,) = scene.twist.views
    frames = registered.twist_addon.views.footage_frames(view, list(range(1, 11)))
    assert [Path(f).name for f in frames] == [f"plate_camel_{i:02d}.png" for i in range(1, 11)]
    assert (scene.frame_start, scene.frame_end) == (1, 10)
    blank = tmp_path / "blank.png"
    cv2.imwrite(str(blank), np.full((60, 90), 200, np.uint8))
    with pytest.raises(RuntimeError, match="blank.png: found fewer than two cells"):
        bpy.ops.twist.add_plate_view(filepath=str(blank))
    assert len(scene.twist.views) == 1

"""Joint markers: a click's 3-D point turned into a footage pixel and back, markers kept per
view and frame, the overlay's crosses on their pixels, CSV frames, the fit on the current
frame's markers only."""

import numpy as np
import pytest

from support.views import three_view_scene as _scene_with_views


def test_a_click_lands_on_its_pixel_and_a_marker_is_drawn_on_it(bpy_module, registered):
    bpy = bpy_module
    scene, arm = _scene_with_views(bpy, registered)
    tw = registered.twist_addon
    rng = np.random.default_rng(0)
    for v in scene.twist.views:
        cam = v.camera
        view = tw.bridge.view_from_camera(cam, scene)
        for X in rng.normal(0, 0.5, (5, 3)):
            pixel = tw.markers.pixel_of_point(cam, scene, X)
            np.testing.assert_allclose(pixel, view.project(X))
            # any point along the click's ray gives the same pixel (orthographic)
            along = X + 3.0 * np.array(cam.matrix_world.to_3x3().col[2])
            np.testing.assert_allclose(tw.markers.pixel_of_point(cam, scene, along), pixel,
                                       atol=1e-9)
            np.testing.assert_allclose(tw.markers.point_of_pixel(cam, scene, pixel, X), X,
                                       atol=1e-9)
        crosses = tw.overlay.marker_crosses(cam, scene, {"Hips": np.array([200.0, 150.0])},
                                            np.zeros(3)).reshape(2, 2, 3)
        px = view.project(crosses)
        np.testing.assert_allclose(px.mean(1), [[200, 150], [200, 150]], atol=1e-9)
        np.testing.assert_allclose(np.abs(px[:, 1] - px[:, 0]).sum(1),
                                   2 * tw.overlay.MARKER_PIXELS, atol=1e-9)


def test_markers_are_kept_per_view_and_frame(bpy_module, registered, tmp_path):
    bpy = bpy_module
    scene, arm = _scene_with_views(bpy, registered)
    tw = registered.twist_addon
    v = scene.twist.views[0]
    tw.markers.set_marker(v, "LeftKnee", 1, 10.0, 20.0)
    tw.markers.set_marker(v, "LeftKnee", 7, 11.0, 21.0)
    tw.markers.set_marker(v, "LeftKnee", 1, 12.0, 22.0)  # moved, not doubled
    assert len(v.markers) == 2
    np.testing.assert_allclose(tw.markers.markers_at(v, 1)["LeftKnee"], [12, 22])
    np.testing.assert_allclose(tw.markers.markers_at(v, 7)["LeftKnee"], [11, 21])
    names = [b.name for b in arm.data.bones]
    assert tw.markers.next_bone(arm, names[0]) == names[1]
    assert tw.markers.next_bone(arm, names[-1]) == names[0]
    (tmp_path / "m.csv").write_text("view,bone,x,y,frame\n2,Neck,5,6,3\ncam2,Hips,7,8\n")
    scene.frame_set(4)
    assert bpy.ops.twist.import_markers(filepath=str(tmp_path / "m.csv")) == {"FINISHED"}
    assert set(tw.markers.markers_at(scene.twist.views[1], 3)) == {"Neck"}
    assert set(tw.markers.markers_at(scene.twist.views[2], 4)) == {"Hips"}
    assert bpy.ops.twist.clear_markers() == {"FINISHED"}  # frame 4's only
    assert not tw.markers.markers_at(scene.twist.views[2], 4)
    assert set(tw.markers.markers_at(scene.twist.views[1], 3)) == {"Neck"}
    (tmp_path / "bad.csv").write_text("1,Neck,5,6,three\n")
    with pytest.raises(RuntimeError, match="bad.csv, row 1: x and y must be numbers, frame"):
        bpy.ops.twist.import_markers(filepath=str(tmp_path / "bad.csv"))


def test_placing_markers_needs_a_view_seen_through_its_camera(bpy_module, registered):
    """Headless there is no viewport to click in: the tool refuses to start, saying why."""
    bpy = bpy_module
    _scene_with_views(bpy, registered)
    assert not bpy.ops.twist.place_markers.poll()

"""Add Views from Calibration on the Pose2Sim demo's Qualisys file: perspective cameras as
calibrated, each camera's footage found beside the file and undistorted."""

import shutil
from pathlib import Path

import cv2
import numpy as np
import pytest

from core.calibration import read_calibration
from core.image import to_grey
from core.lens import Undistorted
from core.video import VideoFrames

DATA = Path(__file__).resolve().parents[2] / "bench" / "data" / "pose2sim"
FRAMES = 3


@pytest.fixture(scope="module")
def calibrated_folder(tmp_path_factory):
    """The calibration with three frames of each camera beside it: cam01 as a movie, the
    others as folders of frames."""
    folder = tmp_path_factory.mktemp("calibrated")
    shutil.copy(DATA / "Calib.qca.txt", folder)
    for name in ("cam01", "cam02", "cam03", "cam04"):
        video = VideoFrames(DATA / f"{name}.mp4")
        frames = [video[i] for i in range(FRAMES)]
        if name == "cam01":
            h, w = frames[0].shape[:2]
            out = cv2.VideoWriter(str(folder / "cam01.mp4"), cv2.VideoWriter_fourcc(*"mp4v"),
                                  60, (w, h))
            for img in frames:
                out.write(img)
            out.release()
        else:
            (folder / name).mkdir()
            for i, img in enumerate(frames):
                cv2.imwrite(str(folder / name / f"{i:04d}.png"), img)
    return folder


def test_calibrated_views_are_the_calibrations_cameras_with_undistorted_footage(
        bpy_module, registered, calibrated_folder):
    bpy = bpy_module
    bridge = registered.twist_addon.bridge
    scene = bpy.context.scene
    calib = calibrated_folder / "Calib.qca.txt"
    assert bpy.ops.twist.add_calibrated_views(filepath=str(calib), first_frame=1) == {"FINISHED"}
    cams = read_calibration(calib)
    tw = scene.twist
    assert [v.camera.name for v in tw.views] == [c.name for c in cams]
    assert (scene.render.resolution_x, scene.render.resolution_y) == (1088, 1920)
    assert tw.mode == "CALIBRATED" and (scene.frame_start, scene.frame_end) == (1, FRAMES)
    # around where the person stands, a few metres from every camera
    X = np.random.default_rng(0).uniform([-0.5, -0.5, 0.0], [0.5, 0.5, 1.8], (30, 3))
    for view, cam in zip(tw.views, cams):
        assert view.camera.data.type == "PERSP"
        got = bridge.view_from_camera(view.camera, scene)
        # Blender's pixels are square: fx for both axes, fy differs by 1e-4 here
        np.testing.assert_allclose(got.project(X), cam.camera.project(X), atol=0.25)
        # the footage: undistorted into a folder beside the calibration, frame by frame
        folder = calibrated_folder / f"{cam.name}_undistorted"
        assert Path(bpy.path.abspath(view.images)).parent == folder
        written = sorted(folder.glob("*.png"))
        assert len(written) == FRAMES
        source = (VideoFrames(calibrated_folder / "cam01.mp4") if cam.name == "cam01" else
                  sorted(str(p) for p in (calibrated_folder / cam.name).glob("*.png")))
        want = to_grey(Undistorted(source, cam.camera.K, cam.dist, cam.size)[FRAMES - 1])
        img = cv2.imread(str(written[-1]), cv2.IMREAD_GRAYSCALE) / 255.0
        assert img.shape == (1920, 1088)
        assert np.abs(img - want).mean() < 2 / 255


def test_a_camera_without_footage_is_named_and_nothing_is_added(bpy_module, registered,
                                                                  calibrated_folder, tmp_path):
    bpy = bpy_module
    shutil.copy(calibrated_folder / "Calib.qca.txt", tmp_path)
    shutil.copy(calibrated_folder / "cam01.mp4", tmp_path)
    shutil.copytree(calibrated_folder / "cam02", tmp_path / "cam02")
    with pytest.raises(RuntimeError, match="no footage for the camera 'cam03': put its movie"):
        bpy.ops.twist.add_calibrated_views(filepath=str(tmp_path / "Calib.qca.txt"))
    assert len(bpy.context.scene.twist.views) == 0 and not bpy.data.cameras
    assert not list(tmp_path.glob("*_undistorted"))

"""A printed plate in Blender through the real operators: Add View from Plate, an armature
posed on the clicked joints, Track, and the tracked frames measured against the animal."""

import json
import shutil
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path[:0] = [str(ROOT / "bench"), str(ROOT / "example_blends")]

import plates  # noqa: E402
from build_examples import pose_on_plate  # noqa: E402


def test_the_baboons_plate_is_cut_posed_and_tracked_in_blender(bpy_module, registered,
                                                               tmp_path):
    """The armature is the planar quadruped of ``bench/plates.py``; its blobs are the
    bones' envelopes (one radius each, the trunk's from rump to neck), coarser than the
    benchmark's. Measured: the first frame's overlap with the silhouette 0.52; frames 2-8
    tracked 0.45-0.55 against the first pose carried along 0.41-0.48; the pose is lost from
    frame 9 (0.18-0.26) and the run stops at frame 12 (the body read as leaving the image),
    keeping frames 1-11. Asserted: the run goes through the real operators and keys at
    least eight frames, and on frames 2-8 the tracked outline beats the carried pose's."""
    bpy = bpy_module
    spec = json.loads((plates.DATA / "baboon.json").read_text())
    plate = tmp_path / "plate_baboon.png"
    shutil.copy(ROOT / spec["plate"], plate)
    assert bpy.ops.twist.add_plate_view(filepath=str(plate), first_frame=1) == {"FINISHED"}
    scene = bpy.context.scene
    assert (scene.frame_start, scene.frame_end) == (1, 12)
    assert (scene.render.resolution_x, scene.render.resolution_y) == (129, 82)
    tw = registered.twist_addon
    arm = pose_on_plate(scene, tw, spec, "baboon")
    view = tw.bridge.view_from_camera(scene.twist.views[0].camera, scene)
    bridged = tw.bridge.skeleton_from_armature(arm)
    R, root = tw.bridge.pose_from_armature(arm, bridged)
    np.testing.assert_allclose(view.project(bridged.world_positions(R, root)),
                               [spec["clicks"][n] for n in bridged.names], atol=1e-3)
    scene.frame_set(1)
    assert bpy.ops.twist.track() == {"FINISHED"}
    tracked_frames = scene.twist.result.frames_tracked
    assert tracked_frames >= 8
    frames = sorted((tmp_path / "plate_baboon_frames").glob("*.png"))[:tracked_frames + 1]
    R_first, _ = tw.bridge.pose_from_armature(arm, bridged)  # frame 1: the clicked pose
    scores = []
    for f, path in enumerate(frames, 1):
        scene.frame_set(f)
        R, root = tw.bridge.pose_from_armature(arm, bridged)
        sil = plates.silhouette(registered.core.image.load_grey(path))
        pose = registered.core.pose.BodyPose(R, root, [view])
        carried = R_first.copy()
        carried[0] = R[0]  # the first pose carried along with the body
        still = registered.core.pose.BodyPose(carried, root, [view])
        scores.append((plates.overlap(bridged, pose, sil), plates.overlap(bridged, still, sil)))
    tracked, carried = np.array(scores[1:8]).T
    assert scores[0][0] > 0.5  # the clicked pose lines up
    assert tracked.mean() > carried.mean() + 0.02

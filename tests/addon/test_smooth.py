"""twist.smooth_track on a keyed walk with jitter added: the jitter goes, the walk stays, a
quaternion track that flips sign midway is smoothed as the rotation it is, the user's keys
(other channels', and a corrected frame's) stay."""

import numpy as np
import pytest

from support.walking import walking_template


def _rotations(bag, bone, frames):
    curves = sorted((fc for fc in bag.fcurves
                     if fc.data_path == f'pose.bones["{bone}"].rotation_quaternion'),
                    key=lambda fc: fc.array_index)
    q = np.array([[fc.evaluate(f) for fc in curves] for f in frames])
    return q / np.linalg.norm(q, axis=1, keepdims=True)


def _angle(a, b):
    return np.degrees(2 * np.arccos(np.clip(np.abs(np.sum(a * b, 1)), 0, 1)))


def _roughness(q):
    """Mean size of the second difference of a rotation track, each key on its
    predecessor's side."""
    q = q.copy()
    for i in range(1, len(q)):
        q[i] *= np.sign(q[i] @ q[i - 1])
    return np.linalg.norm(np.diff(q, 2, axis=0), axis=1).mean()


def test_smoothing_removes_jitter_across_a_quaternion_flip(bpy_module, registered):
    bpy = bpy_module
    scene, arm = walking_template(bpy, registered)
    scene.render.fps = 24
    tw = registered.twist_addon
    bag = tw.keyframes.channelbag(arm)
    frames = range(scene.frame_start, scene.frame_end + 1)
    clean = _rotations(bag, "LeftHip", frames)
    assert bpy.ops.twist.smooth_track(cutoff=3.0) == {"FINISHED"}  # the walk's 1 Hz swing
    assert _angle(_rotations(bag, "LeftHip", frames), clean).max() < 1.0  # stays
    rng = np.random.default_rng(5)
    hip = sorted((fc for fc in bag.fcurves
                  if fc.data_path == 'pose.bones["LeftHip"].rotation_quaternion'),
                 key=lambda fc: fc.array_index)
    for i in range(len(frames)):  # jitter, and the second half keyed as -q
        q = clean[i] + rng.normal(0, 0.05, 4)
        q *= (-1 if i >= len(frames) // 2 else 1) / np.linalg.norm(q)
        for fc in hip:
            fc.keyframe_points[i].co[1] = q[fc.array_index]
    user = arm.pose.bones["Neck"]
    user.scale = (1.2, 1.2, 1.2)
    user.keyframe_insert("scale", frame=10)  # the user's own key, not tracking's
    corrected = 20  # a frame the user corrected: its hip keys are the user's
    for fc in hip:
        fc.keyframe_points[corrected - scene.frame_start].type = "KEYFRAME"
    noisy = _rotations(bag, "LeftHip", frames)
    assert bpy.ops.twist.smooth_track(cutoff=3.0) == {"FINISHED"}
    smooth = _rotations(bag, "LeftHip", frames)
    assert _roughness(smooth) < 0.1 * _roughness(noisy)  # the jitter is gone
    assert _angle(smooth, clean).mean() < 0.6 * _angle(noisy, clean).mean()
    assert _angle(smooth, clean).max() < _angle(noisy, clean).max()  # no spike at the flip
    assert all(len(fc.keyframe_points) == len(frames) for fc in hip)
    i = corrected - scene.frame_start
    assert _angle(smooth[i:i + 1], noisy[i:i + 1])[0] < 1e-4  # the correction stays
    assert _angle(smooth[i + 1:i + 2], noisy[i + 1:i + 2])[0] > 0.1  # its neighbours move
    neck_scale = [fc for fc in bag.fcurves if fc.data_path.endswith('"Neck"].scale')]
    assert neck_scale and all(fc.evaluate(10) == pytest.approx(1.2) for fc in neck_scale)


def test_smoothing_refuses_a_cutoff_above_half_the_frame_rate(bpy_module, registered):
    bpy = bpy_module
    scene, arm = walking_template(bpy, registered)
    scene.render.fps = 24
    with pytest.raises(RuntimeError, match="cutoff must be between 0 and 12.0 Hz"):
        bpy.ops.twist.smooth_track(cutoff=13.0)

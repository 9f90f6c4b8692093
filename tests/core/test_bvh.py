"""BVH reading and writing against the file's own numbers and hand-built rotations."""

import warnings

import numpy as np
import pytest

from core import se3
from core.bvh import BvhError, read_bvh, write_bvh


def _axis_rotation(axis: str, deg: float) -> np.ndarray:
    w = {"X": [1, 0, 0], "Y": [0, 1, 0], "Z": [0, 0, 1]}[axis]
    return se3.exp_so3(np.radians(deg) * np.array(w, float))


def test_reads_the_cmu_walk(cmu_walk):
    b = read_bvh(cmu_walk)
    assert len(b.joints) == 31 and b.names[0] == "Hips"
    assert b.motion.shape == (800, 6 + 30 * 3)  # the capture trimmed to its first 800 frames
    assert b.frame_time == pytest.approx(1 / 120, rel=1e-3)
    knee = b.joints[b.names.index("LeftKnee")]
    np.testing.assert_allclose(knee.offset, [0.140731, -0.386656, 0.0])
    assert b.joints[knee.parent].name == "LeftHip"
    assert len(b.joints[b.names.index("Head")].end_sites) == 1


def test_rotation_channels_compose_in_listed_order(cmu_walk):
    b = read_bvh(cmu_walk)
    f = 400
    R, root = b.frame_pose(f)
    sl = b.channel_slices()
    for name in ["LeftShoulder", "LeftKnee", "Hips"]:  # orders ZXY and ZYX
        j = b.names.index(name)
        chans, vals = b.joints[j].channels, b.motion[f, sl[j]]
        expect = np.eye(3)
        for c, v in zip(chans, vals):
            if c.endswith("rotation"):
                expect = expect @ _axis_rotation(c[0], v)
        np.testing.assert_allclose(R[j], expect, atol=1e-12)
    np.testing.assert_allclose(root, b.motion[f, :3])


def test_write_then_read_round_trips(tmp_path, cmu_walk):
    b = read_bvh(cmu_walk)
    R, p = b.poses(np.arange(100, 110))
    out = b.with_motion(R, p)
    out.frame_time = 1 / 30
    write_bvh(out, tmp_path / "x.bvh")
    back = read_bvh(tmp_path / "x.bvh")
    assert back.names == b.names and back.frame_time == pytest.approx(1 / 30, abs=1e-6)
    R2, p2 = back.poses()
    assert np.max(np.degrees(se3.rotation_angle_between(R, R2))) < 1e-4
    np.testing.assert_allclose(p2, p, atol=1e-6)


def test_a_joint_turned_into_gimbal_lock_is_written_exactly_and_quietly(tmp_path, cmu_walk):
    b = read_bvh(cmu_walk)
    R, p = b.poses(np.arange(100, 102))
    knee = b.names.index("LeftKnee")  # channels Z, Y, X: Y at 90 degrees locks Z with X
    R[0, knee] = _axis_rotation("Z", 30) @ _axis_rotation("Y", 90) @ _axis_rotation("X", 40)
    R[1, knee] = _axis_rotation("Z", -20) @ _axis_rotation("Y", -90) @ _axis_rotation("X", 10)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # scipy's warning on the lock would fail the test
        write_bvh(b.with_motion(R, p), tmp_path / "locked.bvh")
    R2, _ = read_bvh(tmp_path / "locked.bvh").poses()
    assert np.max(np.degrees(se3.rotation_angle_between(R, R2))) < 1e-4


@pytest.mark.parametrize(
    "text, message",
    [
        ("HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n}\n", "no MOTION"),
        ("HIERARCHY\nROOT a\n{\nOFFSET 0 x 0\nCHANNELS 1 Xrotation\n}\nMOTION\nFrames: 1\n"
         "Frame Time: 0.1\n0\n", "line 4: expected a number"),
        ("HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 1 Wrotation\n}\nMOTION\nFrames: 1\n"
         "Frame Time: 0.1\n0\n", "unknown channel 'Wrotation'"),
        ("HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n}\nMOTION\nFrames: 2\n"
         "Frame Time: 0.1\n0\n", "promises 2 frames"),
        ("HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 1 Xrotation\n}\nMOTION\nFrames: 1\n"
         "Frame Time: 0.1\n0 1\n", "2 values, the hierarchy has 1"),
    ],
)
def test_malformed_files_name_file_and_problem(tmp_path, text, message):
    path = tmp_path / "bad.bvh"
    path.write_text(text)
    with pytest.raises(BvhError, match=message) as e:
        read_bvh(path)
    assert "bad.bvh" in str(e.value)

"""Walk-cycle tools against known periods, a symmetric synthetic gait and the CMU walk."""

import numpy as np
import pytest

from core import se3
from core.bvh import read_bvh
from core.cycles import (
    CycleError,
    complete_by_mirroring,
    gait_period,
    lowpass,
    lowpass_quaternions,
    make_loop,
    mirror_poses,
)
from core.skeleton import human_template, skeleton_from_bvh


def _gait(t, period):
    """A smooth two-harmonic gait curve in degrees."""
    w = 2 * np.pi * t / period
    return 30 * np.sin(w) + 8 * np.sin(2 * w + 0.7)


def test_period_of_a_noisy_gait_is_found_to_a_fifth_of_a_frame():
    t = np.arange(400.0)
    rng = np.random.default_rng(0)
    curves = np.stack([_gait(t, 37.3), _gait(t + 10, 37.3)], 1) + rng.normal(0, 1, (400, 2))
    assert gait_period(curves) == pytest.approx(37.3, abs=0.2)


@pytest.mark.parametrize("frames", [3, 9])
def test_curves_too_short_to_repeat_get_a_cycle_error(frames):
    """A few frames of a swing hold no repetition past the shortest period looked for: a
    CycleError the add-on reports, not numpy's error about an empty sequence."""
    t = np.arange(frames, dtype=float)
    with pytest.raises(CycleError, match="do not repeat within half their length"):
        gait_period(np.stack([np.sin(t / 3), np.cos(t / 3)], 1))


def test_period_of_the_cmu_walk_matches_its_footfalls(cmu_walk):
    """The period from the legs' swing angles against the one between the feet's lift-offs
    (each foot's forward speed rising past 0.5 m/s), measured independently."""
    b = read_bvh(cmu_walk)
    sk = skeleton_from_bvh(b)
    R, p = b.poses()
    X = np.array([sk.world_positions(R[f], p[f]) for f in range(len(R))])

    def swing(a, c):
        v = X[:, sk.index(c)] - X[:, sk.index(a)]
        return np.degrees(np.arctan2(v[:, 2], -v[:, 1]))

    walk = slice(500, 790)  # steady walking in the capture, 120 frames per second
    curves = np.stack([swing("LeftHip", "LeftKnee"), swing("RightHip", "RightKnee"),
                       swing("LeftKnee", "LeftAnkle"), swing("RightKnee", "RightAnkle")], 1)
    period = gait_period(curves[walk])
    lifts = []
    for foot in ("LeftAnkle", "RightAnkle"):
        moving = np.gradient(X[:, sk.index(foot), 2]) * 120 > 0.5
        starts = [f for f in range(walk.start, walk.stop) if moving[f] and not moving[f - 1]]
        lifts.append(starts[1] - starts[0])
    assert period == pytest.approx(np.mean(lifts), abs=1.0)


def test_mirroring_completes_a_symmetric_gait_within_half_a_degree():
    period = 40.4
    t = np.arange(0, 41, dtype=float)

    def side(t, shift):  # channel 0 swings forward, channel 1 sideways (mirrors by sign)
        return np.stack([_gait(t - shift, period), 5 * np.sin(2 * np.pi * (t - shift) / period)],
                        1)

    def mirror(rows):  # swap the sides, flip the sideways channels
        return rows[:, [2, 3, 0, 1]] * [1, -1, 1, -1]

    left = side(t, 0)
    body = np.hstack([left, side(t, period / 2) * [1, -1]])  # the right: the left half a
    rec = int(0.6 * period)  # period later, mirrored; 60 % recorded, as in the paper's walk
    got = complete_by_mirroring(body[:rec], period, mirror)
    n = int(round(period))
    np.testing.assert_allclose(got, body[:n], atol=0.5)
    np.testing.assert_array_equal(got[:rec], body[:rec])  # recorded frames kept as they were
    with pytest.raises(CycleError, match="less than half a period"):
        complete_by_mirroring(body[:10], period, mirror)


def test_mirrored_poses_put_each_joint_where_its_partner_is_seen_in_a_mirror():
    """Forward kinematics of the mirrored pose against the reflected joint positions of the
    original, for a body turned away from the axes (so the plane is not the rest x = 0)."""
    sk = human_template()
    rng = np.random.default_rng(3)
    k = 4
    turns = np.stack([[se3.exp_so3(rng.normal(0, 0.5, 3)) for _ in sk.names]
                      for _ in range(k)])
    heading = se3.exp_so3(np.array([0.0, 0.7, 0.0]))  # templates are y up
    turns[:, 0] = heading @ turns[:, 0]
    root = rng.normal(0, 1, (k, 3))
    partners = np.array([sk.index(n.replace("Left", "#").replace("Right", "Left")
                                  .replace("#", "Right")) for n in sk.names])
    normal, centre = heading @ [1.0, 0, 0], np.array([0.3, 0.0, -0.2])
    got, got_root = mirror_poses(turns, root, partners, normal, centre)
    S = np.eye(3) - 2 * np.outer(normal, normal)
    for f in range(k):
        X = sk.world_positions(turns[f], root[f])
        Y = sk.world_positions(got[f], got_root[f])
        np.testing.assert_allclose(Y[partners], centre + (X - centre) @ S.T, atol=1e-9)
        assert all(abs(np.linalg.det(r) - 1) < 1e-9 for r in got[f])


def test_a_looped_cycle_repeats_smoothly_in_value_and_slope():
    t = np.arange(48.0)
    # a tracked cycle never closes by itself: this one drifts and ends early
    cycle = np.stack([_gait(t, 50.0) + 0.05 * t, np.cos(2 * np.pi * t / 50) + 0.004 * t], 1)
    loop = make_loop(cycle, blend=8)
    np.testing.assert_array_equal(loop[:39], cycle[:39])  # before the blend, untouched
    twice = np.concatenate([loop, loop[:3]])
    d = np.diff(twice, axis=0)
    seam = len(loop) - 1  # the step from the last frame into the next cycle's first
    typical = np.abs(np.diff(cycle, axis=0)).max(0)
    assert np.all(np.abs(d[seam] - d[seam - 1]) < 0.35 * typical)  # slope carries over
    assert np.all(np.abs(d[seam + 1] - d[seam]) < 0.35 * typical)
    before = np.abs(np.diff(np.concatenate([cycle, cycle[:1]]), axis=0))[-1]
    assert np.all(np.abs(d[seam]) < before)  # the jump the raw cycle had is gone


def test_lowpass_keeps_slow_motion_drops_jitter_without_delay():
    fps = 120.0
    t = np.arange(480) / fps
    slow = np.sin(2 * np.pi * 1.0 * t)
    fast = 0.5 * np.sin(2 * np.pi * 15.0 * t)
    out = lowpass(np.stack([slow + fast], 1), cutoff_hz=3.0, fps=fps)[:, 0]
    mid = slice(60, -60)
    np.testing.assert_allclose(out[mid], slow[mid], atol=0.03)  # no lag, no residue
    with pytest.raises(CycleError, match="half the frame rate"):
        lowpass(np.zeros((20, 1)), cutoff_hz=70, fps=fps)


def test_quaternion_lowpass_ignores_sign_flips():
    t = np.arange(200) / 60.0
    rng = np.random.default_rng(1)
    R = [se3.exp_so3(np.array([0.8 * np.sin(2 * np.pi * 0.5 * s), 0.3, 0.1])) for s in t]
    from scipy.spatial.transform import Rotation

    q = Rotation.from_matrix(np.array(R)).as_quat()
    noisy = q + rng.normal(0, 0.01, q.shape)
    noisy *= np.where(np.arange(200) % 2, -1, 1)[:, None]  # every other one flipped
    out = lowpass_quaternions(noisy, cutoff_hz=2.0, fps=60.0)
    angle = se3.rotation_angle_between(Rotation.from_quat(out).as_matrix(), np.array(R))
    assert np.degrees(angle[10:-10]).max() < 1.0

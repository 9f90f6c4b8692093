"""Refining the skeleton from footage: the factorisation against constructed twists, the
estimated twists against the true skeleton's motion, and a planar chain whose middle joint
starts 6 cm off."""

import numpy as np
import pytest

from core import se3
from core.pose import CALIBRATED, BodyPose
from core.refine import (
    RefineError,
    Refinement,
    carried_pose,
    centre_from_twists,
    hinge_from_twists,
    moved_joint,
    refine,
    segment_twists,
    without_spin,
)
from core.settings import TrackerSettings
from core.skeleton import human_template, planar_chain_template
from core.tracker import Tracker
from support.synthetic import EXACT, render, side_pinhole, side_view


def test_the_rank_one_factorisation_recovers_a_hinge_and_a_ball_centre():
    rng = np.random.default_rng(0)
    axis = rng.normal(size=3)
    axis /= np.linalg.norm(axis)
    point = rng.normal(0, 0.1, 3)
    point -= axis * (point @ axis)  # the point on the axis nearest the origin
    rates = rng.normal(0, 0.2, 30)
    W = np.outer(np.concatenate([np.cross(point, axis), axis]), rates)
    W += rng.normal(0, 1e-5, W.shape)
    got_axis, got_point = hinge_from_twists(W, -axis)  # the old axis says which way round
    np.testing.assert_allclose(got_axis, -axis, atol=1e-4)
    np.testing.assert_allclose(got_point, point, atol=1e-3)
    spins = rng.normal(0, 0.2, (3, 30))  # a ball: a new axis every step, one centre
    W = np.vstack([np.cross(point, spins.T).T, spins])
    np.testing.assert_allclose(centre_from_twists(W), point, atol=1e-9)


def test_a_few_stray_steps_do_not_tilt_a_hinge_axis():
    rng = np.random.default_rng(0)
    axis = np.array([0.8, 0.6, 0.0])
    point = np.array([0.0, 0.0, 0.05])
    rates = rng.normal(0, 0.2, 30)
    W = np.outer(np.concatenate([np.cross(point, axis), axis]), rates)
    W += rng.normal(0, 1e-3, W.shape)
    W[:, [3, 11, 20]] += rng.normal(0, 0.1, (6, 3))  # steps where the segment was hidden
    plain = hinge_from_twists(W, axis, rounds=1)[0]  # one unweighted factorisation
    assert np.degrees(se3.angle_between_vectors(plain, axis)) > 3
    got_axis, got_point = hinge_from_twists(W, axis)
    assert np.degrees(se3.angle_between_vectors(got_axis, axis)) < 0.3
    np.testing.assert_allclose(got_point, point, atol=2e-3)


def test_a_spin_about_the_bone_no_longer_tilts_a_hinge_axis():
    # a knee (axis x) under a shank that swings through the steps; each step also reads a
    # spin about the shank in step with the knee's turn, as pixels of a round blob may
    sk = human_template()
    j = sk.index("LeftKnee")
    axis = sk.axes[j] / np.linalg.norm(sk.axes[j])
    bone = sk.bone_frame(j)[0]
    rates = np.linspace(0.05, 0.3, 20) * np.sign(np.sin(np.arange(20)))
    angles = np.concatenate([[0.0], np.cumsum(rates)])
    poses = [BodyPose(np.stack([np.eye(3)] * sk.n_joints), np.zeros(3), [])
             for _ in angles]
    for p, a in zip(poses, angles):
        p.rotations[j] = se3.exp_so3(axis * a)
    spin = np.array([p.rotations[j] @ bone for p in poses[1:]]).T * 0.3 * rates
    W = np.vstack([np.zeros((3, 20)), np.outer(axis, rates) + spin])
    tilted = hinge_from_twists(W, axis)[0]
    assert np.degrees(se3.angle_between_vectors(tilted, axis)) > 3  # the spin draws it off
    got = hinge_from_twists(without_spin(W, poses, sk, j), axis)[0]
    np.testing.assert_allclose(got, axis, atol=1e-9)


def test_moving_a_joint_keeps_the_body_at_rest_and_carries_a_pose():
    sk = human_template()
    j = sk.index("LeftKnee")
    new = moved_joint(sk, j, np.array([0.0, 0.03, 0.02]), np.array([1.0, 0.2, 0.0]))
    np.testing.assert_allclose(new.rest_positions[j], sk.rest_positions[j] + [0, 0.03, 0.02])
    others = [k for k in range(sk.n_joints) if k != j]
    np.testing.assert_allclose(new.rest_positions[others], sk.rest_positions[others])
    assert np.linalg.norm(new.axes[j]) == pytest.approx(1.0)
    R = np.tile(np.eye(3), (sk.n_joints, 1, 1))
    R[j] = se3.exp_so3(sk.axes[j] * 0.6)
    pose = BodyPose(R, np.zeros(3), [side_view()])
    carried = carried_pose(sk, new, pose)
    g_old = sk.segment_motions(sk.joint_frames(pose.rotations, pose.root_position))[j]
    g_new = new.segment_motions(new.joint_frames(carried.rotations, carried.root_position))[j]
    c = next(b.centre for b in sk.blobs if b.joint == j)
    moved_as_is = new.segment_motions(new.joint_frames(R, np.zeros(3)))[j]
    err = np.linalg.norm(g_new[:3, :3] @ c + g_new[:3, 3] - g_old[:3, :3] @ c - g_old[:3, 3])
    naive = np.linalg.norm(moved_as_is[:3, :3] @ c + moved_as_is[:3, 3]
                           - g_old[:3, :3] @ c - g_old[:3, 3])
    assert err < 0.5 * naive  # the shank is put back near where it was


def _human_walk(T=8, camera=side_view):
    sk = human_template()
    views = [camera(yaw_deg=90), camera(yaw_deg=0), camera(yaw_deg=60)]
    poses = []
    for t in range(T):
        R = np.tile(np.eye(3), (sk.n_joints, 1, 1))
        for name, shift in (("LeftKnee", 0.0), ("RightElbow", 0.0)):
            j = sk.index(name)
            R[j] = se3.exp_so3(sk.axes[j] * (0.5 + 0.4 * np.sin(0.5 * t + shift)))
        R[sk.index("LeftHip")] = se3.exp_so3(np.array([0.4 * np.sin(0.5 * t), 0, 0]))
        poses.append(BodyPose(R, sk.rest_positions[0].copy(), [v.copy() for v in views]))
    images = [[render(sk, p, c, background=0.05, noise=0.01, seed=t)
               for t, p in enumerate(poses)] for c in range(3)]
    return sk, poses, images


def test_a_round_settles_only_when_no_joint_moves_and_no_axis_turns():
    sk = human_template()
    pose = BodyPose(np.tile(np.eye(3), (sk.n_joints, 1, 1)), np.zeros(3), [side_view()])
    res = Refinement(sk, pose)
    assert not res.settled()  # no round yet
    res.shifts.append({"LeftKnee": 5e-4, "LeftHip": 2e-4})
    res.turns.append({"LeftKnee": 2.0})  # the centres are still, the axis is not
    assert not res.settled()
    assert res.settled(turn_tolerance=3.0)
    res.turns[-1]["LeftKnee"] = 0.2
    assert res.settled()
    res.shifts.append({"LeftHip": 2e-3})  # a round of ball joints only: no axis to turn
    res.turns.append({})
    assert not res.settled()
    assert res.settled(tolerance=3e-3)


@pytest.mark.parametrize("camera", [side_view, side_pinhole], ids=["orthographic", "pinhole"])
def test_twists_estimated_from_footage_match_the_true_skeleton(camera):
    """At the true skeleton and poses, the factorised twists of a knee and an elbow give their
    axes within 3 degrees and their centres within a centimetre (measured through
    orthographic views: 0.3 and 2.6 degrees, under 1 mm)."""
    sk, poses, images = _human_walk(camera=camera)
    tracker = Tracker(sk, images, CALIBRATED, TrackerSettings(**EXACT))
    for name in ("LeftKnee", "RightElbow"):
        j = sk.index(name)
        W = segment_twists(tracker, poses, list(range(len(poses))), j)
        axis, point = hinge_from_twists(W, poses[0].rotations[j] @ sk.axes[j])
        assert np.degrees(se3.angle_between_vectors(axis, poses[0].rotations[j] @ sk.axes[j])
                          ) < 3.0, name
        assert np.linalg.norm(point) < 0.01, name


def test_a_planar_chain_joint_six_centimetres_off_comes_back_within_one():
    truth = planar_chain_template(lengths=(0.5, 0.4, 0.3), axis=(0, 0, 1))
    for b in truth.blobs:
        b.radii[1:] = 0.06
    view = side_view(yaw_deg=0, height=0.0, center=(110, 180))
    j = 2
    guess = moved_joint(truth, j, np.array([0.05, -0.03, 0.0]))
    poses = []
    for t in range(10):
        R = np.tile(np.eye(3), (truth.n_joints, 1, 1))
        for k, (amp, rate, bias, phase) in enumerate(((0.2, 0.5, 0, 0), (0.5, 0.6, 0.3, 1),
                                                      (0.4, 0.7, -0.3, 0)), 1):
            R[k] = se3.exp_so3(np.array([0, 0, bias + amp * np.sin(rate * t + phase)]))
        poses.append(BodyPose(R, np.zeros(3), [view]))
    images = [[render(truth, p, 0, background=0.05, noise=0.01, seed=t)
               for t, p in enumerate(poses)]]
    initial = carried_pose(truth, guess, poses[0])  # lined up by the user, centre wrong
    res = refine(guess, images, initial, [guess.names[j]], planar=True, rounds=8)
    before = np.linalg.norm(guess.rest_positions[j] - truth.rest_positions[j])
    after = np.linalg.norm(res.skeleton.rest_positions[j] - truth.rest_positions[j])
    assert before > 0.05 and after < 0.01, (before, after)
    assert len(res.shifts) == 8 and res.shifts[-1][guess.names[j]] < res.shifts[0][
        guess.names[j]]
    with pytest.raises(RefineError, match="no joint named 'Elbow'"):
        refine(guess, images, initial, ["Elbow"])
    with pytest.raises(RefineError, match="planar refinement is for one view"):
        refine(guess, images * 2, BodyPose(initial.rotations, initial.root_position,
                                           [view, view]), [guess.names[j]], planar=True)
    with pytest.raises(RefineError, match="2 frames are too few"):
        refine(guess, [images[0][:2]], initial, [guess.names[j]])

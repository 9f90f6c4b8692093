"""Forward kinematics against the product of exponentials built from twists (paper eq. 23)."""

import numpy as np
import pytest

from core import se3
from core.bvh import read_bvh
from core.skeleton import (
    BALL,
    HINGE,
    MIN_BEND,
    TRUNK_RADIUS,
    Skeleton,
    bend_hinge,
    human_template,
    planar_chain_template,
    planar_quadruped_template,
    skeleton_from_bvh,
    twist_about,
    walker_template,
)


def test_segment_motions_are_the_product_of_exponentials(cmu_walk):
    b = read_bvh(cmu_walk)
    sk = skeleton_from_bvh(b)
    R, root = b.frame_pose(500)
    g = sk.segment_motions(sk.joint_frames(R, root))
    p = sk.rest_positions
    G0 = se3.rigid(R[0], root) @ se3.rigid(np.eye(3), -p[0])
    for k in range(1, sk.n_joints):  # every joint, each generation of the tree
        chain = sk.ancestors(k)[::-1][1:]  # root excluded, root first
        expect = G0.copy()
        for j in chain:
            w = se3.log_so3(R[j])
            theta = np.linalg.norm(w)
            xi = se3.twist_of_axis(w / theta, p[j]) if theta > 0 else np.zeros(6)
            expect = expect @ se3.exp_se3(xi * theta)
        np.testing.assert_allclose(g[k], expect, atol=1e-10)


def test_world_positions_follow_offsets_at_rest(cmu_walk):
    sk = skeleton_from_bvh(read_bvh(cmu_walk))
    J = sk.n_joints
    X = sk.world_positions(np.tile(np.eye(3), (J, 1, 1)), np.array([1.0, 2.0, 3.0]))
    np.testing.assert_allclose(X - X[0], sk.rest_positions - sk.rest_positions[0], atol=1e-12)
    np.testing.assert_allclose(X[0], [1, 2, 3])


def test_templates_have_the_named_degrees_of_freedom():
    human = human_template()
    assert len(human.dof_names()) == 19
    assert {human.names[j] for j, k in enumerate(human.kinds) if k == BALL} == {
        "Neck", "LeftShoulder", "RightShoulder", "LeftHip", "RightHip"}
    assert {human.names[j] for j, k in enumerate(human.kinds) if k == HINGE} == {
        "LeftElbow", "RightElbow", "LeftKnee", "RightKnee"}
    walker = walker_template()
    assert len(walker.dof_names()) == 6
    chain = planar_chain_template(axis=(0, 0, 1))
    _, axes = chain.dof_joints_and_axes()
    np.testing.assert_allclose(axes, np.tile([0, 0, 1.0], (len(axes), 1)))
    horse = planar_quadruped_template()
    _, axes = horse.dof_joints_and_axes()
    assert len(axes) == 10  # neck, head, two joints on each of four legs
    np.testing.assert_allclose(axes, np.tile([0, 0, 1.0], (10, 1)))
    assert [b.name for b in horse.blobs if b.joint == 0] == ["Trunk"]
    # every hinge kept within its reach of the standing pose: a leg's bone 75 degrees
    # either way, the head and neck 45
    reach = np.degrees(horse.limits[:, 1])
    assert reach[horse.index("LeftHindLower")] == reach[horse.index("RightForeUpper")] == 75
    assert reach[horse.index("Head")] == reach[horse.index("Neck")] == 45
    np.testing.assert_allclose(horse.limits[1:, 0], -horse.limits[1:, 1])
    assert all(horse.limited_hinge(j) for j in range(1, horse.n_joints))
    for sk in (human, walker, chain, horse):
        assert sk.blobs and all(np.all(b.radii > 0) for b in sk.blobs)


def test_the_human_template_may_free_its_lower_back():
    human = human_template(lower_back=True)
    assert len(human.dof_names()) == 22
    assert human.kinds[human.index("Spine")] == BALL
    paper = human_template()
    assert paper.kinds[paper.index("Spine")] != BALL


@pytest.mark.parametrize("template, forward, bends", [
    (human_template, (0, 0, 1), {"LeftKnee": -1, "RightKnee": -1, "LeftElbow": 1,
                                 "RightElbow": 1}),
    (walker_template, (1, 0, 0), {"LeftKnee": -1, "RightKnee": -1}),
])
def test_template_hinges_bend_the_way_anatomy_does(template, forward, bends):
    # anywhere inside its limits a knee swings its shank behind it and an elbow its forearm
    # in front (the hinge's end site seen from its joint, along the way the body faces)
    sk = template()
    limited = {sk.names[j] for j in range(sk.n_joints) if np.all(np.isfinite(sk.limits[j]))}
    assert limited == set(bends)
    for name, side in bends.items():
        j = sk.index(name)
        lo, hi = sk.limits[j]
        assert hi - lo == pytest.approx(np.radians(160))
        end = (list(sk.end_sites[j]) + [sk.offsets[c] for c in sk.children(j)])[0]
        for angle in np.linspace(lo, hi, 9)[1:-1]:  # not straight
            tip = se3.exp_so3(sk.axes[j] * angle) @ end
            assert side * tip @ forward > 0, (name, np.degrees(angle))


def test_a_planar_chain_stays_in_its_plane():
    chain = planar_chain_template(lengths=(0.5, 0.4, 0.3), axis=(0, 0, 1))
    R = np.tile(np.eye(3), (chain.n_joints, 1, 1))
    for j, a in zip(*chain.dof_joints_and_axes()):
        R[j] = se3.exp_so3(a * 0.7)
    X = chain.world_positions(R, np.zeros(3))
    np.testing.assert_allclose(X[:, 2], 0, atol=1e-12)
    lengths = np.linalg.norm(np.diff(X[1:], axis=0), axis=1)
    np.testing.assert_allclose(lengths, [0.5, 0.4])


def test_default_blobs_span_their_bones():
    sk = human_template()
    b = next(b for b in sk.blobs if b.name == "LeftKnee")
    knee = sk.rest_positions[sk.index("LeftKnee")]
    tip = knee + sk.end_sites[sk.index("LeftKnee")][0]
    np.testing.assert_allclose(b.centre, (knee + tip) / 2)
    assert b.radii[0] == pytest.approx(np.linalg.norm(tip - knee) / 2)
    np.testing.assert_allclose(np.abs(b.Q[:, 0]), [0, 1, 0], atol=1e-12)
    np.testing.assert_allclose(b.Q.T @ b.Q, np.eye(3), atol=1e-12)


def test_limbs_are_counted_where_their_end_sites_part():
    # a trunk carrying a head and two arms, each arm ending in a hand of two fingers: the
    # fingers part 0.05 from their ends (one limb), the arms 0.6 (two), the head 0.3
    offsets = [(0, 0, 0), (0, 0.5, 0), (0.2, 0, 0), (0.5, 0, 0), (-0.2, 0, 0), (-0.5, 0, 0)]
    sk = Skeleton(names=["hips", "chest", "l_arm", "l_hand", "r_arm", "r_hand"],
                  parents=[-1, 0, 1, 2, 1, 4], offsets=offsets,
                  end_sites=[[], [(0, 0.3, 0)], [], [(0.05, 0, 0), (0.05, 0.02, 0)], [],
                             [(-0.05, 0, 0), (-0.05, 0.02, 0)]])
    assert sk.height() == pytest.approx(1.5)  # so a limb's end sites part within 0.375
    np.testing.assert_array_equal(sk.limbs_below(), [3, 3, 1, 1, 1, 1])


def test_default_blobs_make_the_trunk_as_thick_as_a_trunk(cmu_walk):
    sk = skeleton_from_bvh(read_bvh(cmu_walk))
    H = sk.height()
    blobs = {b.name: b for b in sk.default_blobs()}
    # the spine (three limbs above it) and the short bones from the trunk to the legs and
    # to the neck: at least an adult trunk's radius across, half the bone long
    for name, child in (("lowerback", "Chest"), ("Chest", "Chest2"), ("LHipJoint", "LeftHip"),
                        ("RHipJoint", "RightHip"), ("lowerneck", "Neck")):
        L = np.linalg.norm(sk.offsets[sk.index(child)])
        assert blobs[name].radii[0] == pytest.approx(L / 2), name
        assert np.all(blobs[name].radii[1:] >= TRUNK_RADIUS * H - 1e-12), name
    # a limb's bones keep the length rule: half the bone long, 0.16 of it across
    for name, child in (("LeftHip", "LeftKnee"), ("LeftShoulder", "LeftElbow"),
                        ("LeftCollar", "LeftShoulder"), ("Head", None)):
        j = sk.index(name)
        L = np.linalg.norm(sk.offsets[sk.index(child)] if child else sk.end_sites[j][0])
        np.testing.assert_allclose(blobs[name].radii, [L / 2] + [max(0.16 * L, 0.022 * H)] * 2)
    limbs = sk.limbs_below()
    assert limbs[sk.index("Hips")] == 5 and limbs[sk.index("Chest2")] == 3
    assert limbs[sk.index("LeftWrist")] == 1 and limbs[sk.index("Neck")] == 1


def test_parents_must_precede_children():
    from core.skeleton import Skeleton

    with pytest.raises(ValueError, match="parents must come before"):
        Skeleton(names=["a", "b"], parents=[-1, 1], offsets=np.zeros((2, 3)))


def test_the_tracked_joints_are_those_with_degrees_of_freedom_in_joint_order():
    sk = human_template()
    dof_joints = sk.dof_joints_and_axes()[0]
    want = [sk.names[j] for j in sorted(set(dof_joints.tolist()))]
    assert sk.tracked_joint_names() == want
    assert len(want) == 9 and "LeftKnee" in want and sk.names[0] not in want


def _leg_pose(sk, thigh_twist, knee):
    """Rest rotations with the left thigh swung a little, then twisted ``thigh_twist`` about
    its bone, and the left knee at ``knee`` (radians)."""
    R = np.repeat(np.eye(3)[None], sk.n_joints, 0)
    along = sk.offsets[sk.index("LeftKnee")] / np.linalg.norm(sk.offsets[sk.index("LeftKnee")])
    R[sk.index("LeftHip")] = se3.exp_so3(np.array([0.3, 0.2, 0.1])) @ se3.exp_so3(
        thigh_twist * along)
    R[sk.index("LeftKnee")] = se3.exp_so3(knee * sk.axes[sk.index("LeftKnee")])
    return R


def _places(sk, R):
    """Every joint and end site, in the world."""
    M = sk.joint_frames(R, np.zeros(3))
    return np.vstack([M[:, :3, 3]] + [M[j, :3, :3] @ e + M[j, :3, 3]
                                      for j, es in enumerate(sk.end_sites) for e in es])


def test_a_hinge_bent_against_its_limits_under_a_parent_twisted_half_a_turn_is_untwisted():
    sk = human_template()
    knee, hip = sk.index("LeftKnee"), sk.index("LeftHip")
    along = sk.offsets[knee] / np.linalg.norm(sk.offsets[knee])
    R = _leg_pose(sk, np.radians(170), np.radians(-40))  # knee bent forward: outside 0..160
    U = sk.untwisted(R)
    assert np.degrees(sk.hinge_angle(knee, U[knee])) == pytest.approx(40)
    assert abs(np.degrees(twist_about(U[hip], along))) < 90  # the thigh no longer twisted
    np.testing.assert_allclose(_places(sk, U), _places(sk, R), atol=1e-12)
    # every blob is the same ellipsoid: any world point lies as far inside or out of it
    g_r, g_u = (sk.segment_motions(sk.joint_frames(R_, np.zeros(3))) for R_ in (R, U))
    x = np.random.default_rng(1).normal(0, 0.5, (50, 3))
    for b in sk.blobs:
        level = [np.linalg.norm((np.linalg.solve(g[b.joint][:3, :3], (x - g[b.joint][:3, 3]).T).T
                                 - b.centre) @ b.Q / b.radii, axis=1) for g in (g_r, g_u)]
        np.testing.assert_allclose(level[0], level[1], atol=1e-9)
    assert sk.same_body(R, U)
    untouched = [j for j in range(sk.n_joints) if j not in (knee, hip)]
    np.testing.assert_array_equal(U[untouched], R[untouched])


def test_a_hinge_outside_its_limits_under_an_untwisted_parent_is_left_as_it_is():
    sk = human_template()
    # a knee locked a little past straight: turning the thigh half a turn would put the knee
    # within its limits but twist the thigh, and the next bend would go the wrong way
    R = _leg_pose(sk, np.radians(10), np.radians(-5))
    np.testing.assert_array_equal(sk.untwisted(R), R)
    R = _leg_pose(sk, np.radians(170), np.radians(30))  # within its limits: nothing to do
    np.testing.assert_array_equal(sk.untwisted(R), R)


def test_a_blob_off_its_bone_keeps_the_parent_twisted():
    sk = human_template()
    hip = sk.index("LeftHip")
    thigh = next(b for b in sk.blobs if b.joint == hip)
    thigh.centre = thigh.centre + np.array([0.05, 0, 0])  # a thigh blob beside its bone
    R = _leg_pose(sk, np.radians(170), np.radians(-40))
    assert not sk.same_body(R, _leg_pose(sk, np.radians(-10), np.radians(40)))
    np.testing.assert_array_equal(sk.untwisted(R), R)


def test_twist_about_is_the_quaternions_twist():
    rng = np.random.default_rng(3)
    for _ in range(200):
        w = rng.normal(size=3)
        axis = rng.normal(size=3)
        axis /= np.linalg.norm(axis)
        R = se3.exp_so3(w)
        tau = twist_about(R, axis)
        # the swing left after taking the twist out moves the axis and turns nothing about it
        swing = R @ se3.exp_so3(-tau * axis)
        assert abs(se3.log_so3(swing) @ axis) < 1e-9


def test_a_bones_bend_gives_back_the_hinge_that_bent_it_whatever_its_twist():
    """A bone bent about an axis across it, then twisted about itself: the hinge read from
    its rest and turned directions is that axis (its sign the bend's) and angle, and turning
    the rest direction by it gives the turned one; a bone turned too little to show a plane,
    or right round, is refused."""
    rng = np.random.default_rng(3)
    for _ in range(20):
        d = rng.normal(size=3)
        d /= np.linalg.norm(d)
        axis = np.cross(d, rng.normal(size=3))
        axis /= np.linalg.norm(axis)
        angle = rng.uniform(np.radians(MIN_BEND) + 0.01, np.pi - np.radians(MIN_BEND) - 0.01)
        R = se3.exp_so3(axis * angle) @ se3.exp_so3(d * rng.uniform(-2, 2))  # twist first
        got_axis, got_angle = bend_hinge(3 * d, R)
        np.testing.assert_allclose(got_axis, axis, atol=1e-9)
        assert got_angle == pytest.approx(angle, abs=1e-9)
        np.testing.assert_allclose(se3.exp_so3(got_axis * got_angle) @ d, R @ d, atol=1e-9)
    d = np.array([0.0, -1.0, 0.0])
    for degrees in (0.0, MIN_BEND - 1, 180.0):
        with pytest.raises(ValueError, match="no bend shows its axis"):
            bend_hinge(d, se3.exp_so3(np.array([1.0, 0, 0]) * np.radians(degrees)))

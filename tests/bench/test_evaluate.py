"""The benchmark's scores against cases whose answer geometry gives."""

import sys
from pathlib import Path

import numpy as np

from core import se3
from core.bvh import read_bvh
from core.skeleton import BALL, skeleton_from_bvh

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))

import evaluate  # noqa: E402


def test_limbs_laid_into_the_image_plane_are_off_by_their_angle_out_of_it(cmu_walk):
    b = read_bvh(cmu_walk)
    sk = skeleton_from_bvh(b)
    R, p = b.frame_pose(0)
    R[:] = np.eye(3)  # the rest pose, in which the capture's thighs lie in the x-y plane
    R[sk.index("LeftHip")] = se3.exp_so3([0.0, 0.0, np.radians(30)])  # swung within it
    truth = (R[None], p[None])
    # seen along z the left thigh lies in the image plane; seen along x or y it leans out of
    # it by the angle its x or y component makes, which add up to 90 degrees
    along_z = evaluate.in_the_image_plane(sk, truth, [0, 0, 1])
    along_x = evaluate.in_the_image_plane(sk, truth, [1, 0, 0])
    along_y = evaluate.in_the_image_plane(sk, truth, [0, 1, 0])
    thigh = evaluate.limb_vectors(sk, *truth)["left thigh"][0]
    assert along_z["left thigh"] < 1e-6
    expected = np.degrees(np.arcsin(abs(thigh[0]) / np.linalg.norm(thigh)))
    assert abs(along_x["left thigh"] - expected) < 1e-6
    assert abs(along_y["left thigh"] - (90 - expected)) < 1e-6


def test_the_image_error_is_how_far_each_view_sees_the_limb_ends_moved(cmu_walk):
    from core.camera import View

    b = read_bvh(cmu_walk)
    sk = skeleton_from_bvh(b)
    R, p = b.frame_pose(600)
    truth = (R[None], p[None])
    side = View(se3.Similarity(150.0, np.diag([1.0, -1, -1]), np.zeros(3)), np.zeros(2))
    front = View(se3.Similarity(150.0, np.diag([1.0, -1, -1]) @ se3.exp_so3([0, np.pi / 2, 0]),
                                np.zeros(3)), np.zeros(2))
    # the whole body 2 cm along the first view's line of sight: that view sees nothing move,
    # one at right angles sees every limb end move 3 pixels
    moved = (R[None], (p + [0.0, 0.0, 0.02])[None])
    assert evaluate.image_error_px(sk, moved, truth, [side]) < 1e-9
    assert abs(evaluate.image_error_px(sk, moved, truth, [front]) - 3.0) < 1e-9
    assert abs(evaluate.image_error_px(sk, moved, truth, [side, front]) - 1.5) < 1e-9


def _thigh_swung_about_x(cmu_walk, degrees):
    """The rest pose with the left thigh turned about world x by each angle: seen along z,
    the thigh tilts out of the image plane by the angle, and back."""
    b = read_bvh(cmu_walk)
    sk = skeleton_from_bvh(b)
    R, p = b.frame_pose(0)
    R[:] = np.eye(3)  # the capture's thighs lie in the x-y plane here
    Rs = np.repeat(R[None], len(degrees), axis=0)
    for f, a in enumerate(degrees):
        Rs[f, sk.index("LeftHip")] = se3.exp_so3([np.radians(a), 0.0, 0.0])
    return sk, (Rs, np.repeat(p[None], len(degrees), axis=0))


def test_a_limb_lifted_from_one_image_has_its_depth_from_its_length(cmu_walk):
    # swung through the image plane at a steady rate: its length gives each frame's depth,
    # and going on through the plane is the steadier of the two paths the image allows
    sk, truth = _thigh_swung_about_x(cmu_walk, [25, 15, 5, -5, -15, -25])
    lifted = evaluate.lifted_from_the_image(sk, truth, [0, 0, 1])
    flat = evaluate.in_the_image_plane(sk, truth, [0, 0, 1])
    assert lifted["left thigh"] < 1e-6
    assert flat["left thigh"] > 5


def test_a_limb_turning_back_at_the_image_plane_is_lifted_as_its_mirror_image(cmu_walk):
    # out to the plane and back on the same side: every frame's image is the one above, so
    # the lift is too, and the frames after the turn read the mirror image, off by the angle
    # between the two
    sk, truth = _thigh_swung_about_x(cmu_walk, [25, 15, 5, 5, 15, 25])
    lifted = evaluate.lifted_from_the_image(sk, truth, [0, 0, 1])
    v = evaluate.limb_vectors(sk, *truth)["left thigh"]
    mirrored = v * [1.0, 1.0, -1.0]
    expected = np.degrees(se3.angle_between_vectors(v[3:], mirrored[3:])).sum() / len(v)
    assert expected > 5
    assert abs(lifted["left thigh"] - expected) < 1e-6



def test_a_limb_lifted_over_two_frames_starts_from_rest(cmu_walk):
    # no second frame to steady the path by: the limb is taken at rest before the first
    # frame, so the second keeps the first one's side of the image plane
    sk, truth = _thigh_swung_about_x(cmu_walk, [-25, -15])
    assert evaluate.lifted_from_the_image(sk, truth, [0, 0, 1])["left thigh"] < 1e-6


def test_one_views_best_fit_turns_limbs_in_the_image_plane_and_the_root_about_the_sight(
        cmu_walk):
    """Fitted as one view along z tracks it (side-on: the ball joints hinges about z, the root
    turning about z alone), a thigh swung about z is fitted exactly and one swung out of the
    image plane is off about as far as the limb laid into the image plane; a body turned in
    depth is off too. The 3-D fit, root free, reaches all three."""
    from core.camera import View
    from core.pose import BodyPose
    from core.side_on import side_on_skeleton

    sk, out_of_plane = _thigh_swung_about_x(cmu_walk, [0, 10, 20, 30, 40])
    for _, joint, _ in evaluate.LIMBS:
        sk.kinds[sk.index(joint)] = BALL
    R, p = out_of_plane[0].copy(), out_of_plane[1]
    in_plane, turned = R.copy(), R.copy()
    for f, a in enumerate(np.radians([0, 10, 20, 30, 40])):
        in_plane[f, sk.index("LeftHip")] = se3.exp_so3([0.0, 0.0, a])
        turned[f, 0] = se3.exp_so3([0.0, a, 0.0])  # about y: toward the view
    view = View(se3.Similarity(150.0, np.diag([1.0, -1, -1]), np.zeros(3)), np.zeros(2))
    body = side_on_skeleton(sk, BodyPose(R[0].copy(), p[0].copy(), [view]))
    assert body is not sk
    names = sk.tracked_joint_names()

    def off(fit_body, truth, axis, limb="left thigh"):
        scores = evaluate.score(sk, names, evaluate.best_fit(fit_body, truth, axis), truth)
        return scores.limb_deg[limb] if limb else scores.limb_mean_deg

    z = np.array([0.0, 0.0, 1.0])
    assert off(body, (in_plane, p), z) < 0.01
    laid = evaluate.in_the_image_plane(sk, out_of_plane, z)["left thigh"]
    # in the image plane, the thigh is nearest its true direction along its image; fitted to
    # the joints below it too, a little off that
    assert laid > 5 and laid - 1e-6 < off(body, out_of_plane, z) < laid + 1.5
    assert off(body, (turned, p), z, limb=None) > 3
    for truth in (out_of_plane, (in_plane, p), (turned, p)):
        assert off(sk, truth, None, limb=None) < 0.01


def test_heading_error_is_the_turn_about_the_vertical_beyond_the_reference():
    rng = np.random.default_rng(5)
    refs = np.array([se3.exp_so3(rng.normal(size=3)) for _ in range(4)])
    turns = np.array([30.0, -75.0, 0.0, 170.0])
    est = np.array([se3.exp_so3(evaluate.UP * np.radians(t)) @ r for t, r in zip(turns, refs)])
    np.testing.assert_allclose(evaluate.heading_errors_deg(est, refs), turns, atol=1e-6)
    # a lean about a level axis turns nothing about the vertical
    lean = np.array([se3.exp_so3(np.array([np.cos(a), 0.0, np.sin(a)]) * np.radians(25.0)) @ r
                     for a, r in zip((0.3, 1.2, 2.0, 4.0), refs)])
    np.testing.assert_allclose(evaluate.heading_errors_deg(lean, refs), 0.0, atol=1e-6)

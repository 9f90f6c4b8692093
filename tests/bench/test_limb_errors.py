"""A joint's turn split into its twist about the bone and its swing across it, against
rotations built from the two."""

import sys
from pathlib import Path

import numpy as np
import pytest

from core import se3

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

from limb_errors import swing_twist  # noqa: E402

AXIS = np.array([0.3, -0.5, 0.81])
AXIS /= np.linalg.norm(AXIS)
ACROSS = np.cross(AXIS, [1.0, 0.0, 0.0])
ACROSS /= np.linalg.norm(ACROSS)


def _turn(axis: np.ndarray, degrees: float) -> np.ndarray:
    return se3.exp_so3(axis * np.radians(degrees))


@pytest.mark.parametrize("twist", [0.0, 35.0, -120.0, 179.0])
@pytest.mark.parametrize("swing", [0.0, 20.0, 95.0])
def test_swing_after_twist_comes_apart(swing, twist):
    # a swing about any axis across the bone, after a twist about it
    across = _turn(AXIS, 40.0) @ ACROSS
    got = swing_twist(_turn(across, swing) @ _turn(AXIS, twist), AXIS)
    np.testing.assert_allclose(got, (swing, twist), atol=1e-6)


def test_twist_is_signed_about_the_axis_and_wraps():
    assert swing_twist(_turn(AXIS, -30.0), AXIS)[1] == pytest.approx(-30.0)
    assert swing_twist(_turn(-AXIS, 30.0), AXIS)[1] == pytest.approx(-30.0)
    assert swing_twist(_turn(AXIS, 190.0), AXIS)[1] == pytest.approx(-170.0)


def test_swing_is_how_far_the_bone_turns():
    rng = np.random.default_rng(3)
    for _ in range(20):
        R = se3.exp_so3(rng.normal(size=3))
        swing, _ = swing_twist(R, AXIS)
        assert swing == pytest.approx(np.degrees(np.arccos(np.clip(AXIS @ R @ AXIS, -1, 1))),
                                      abs=1e-6)


def test_the_prediction_carries_the_last_step_on_and_starts_from_rest():
    from limb_errors import predicted_roots
    lean = _turn(ACROSS, 20.0)
    # a body leaned, then turning 12 degrees a frame about its own axis
    roots = np.array([lean @ _turn(AXIS, 12.0 * f) for f in range(5)])
    pred = predicted_roots(roots)
    np.testing.assert_allclose(pred[0], roots[0])
    np.testing.assert_allclose(pred[1], roots[0])  # no step before the first tracked frame
    np.testing.assert_allclose(pred[2:], roots[2:], atol=1e-12)
    half = predicted_roots(roots, gain=0.5)
    np.testing.assert_allclose(half[3], roots[2] @ _turn(AXIS, 6.0), atol=1e-12)


def test_a_jump_is_told_moved_by_the_search_by_its_parents_turn_or_by_the_steps():
    from limb_errors import jumps
    limbs = [("thigh", "Hip", "Knee"), ("shank", "Knee", "Ankle"), ("arm", "Shoulder", "Elbow")]
    errors = np.array([[0, 0, 0], [2, 40, 1], [3, 41, 50], [4, 90, 51], [4, 91, 52.0]])
    searched = [[], ["Hip"], [], ["Knee"], []]
    assert jumps(limbs, errors, searched, 30.0) == [
        (1, "shank", 0.0, 40.0, "search (parent)"), (2, "arm", 1.0, 50.0, "steps"),
        (3, "shank", 41.0, 90.0, "search")]
    assert jumps(limbs, errors, searched, 60.0) == []


def test_the_share_of_each_turn_left_undone():
    from limb_errors import lag_share
    rng = np.random.default_rng(5)
    turn = rng.uniform(-12.0, 12.0, 40)  # the reference's turn each frame, degrees
    # a step that turns 85 % of the way, give or take a tenth of a degree
    beyond = -0.15 * turn + rng.normal(0.0, 0.1, 40)
    assert lag_share(beyond, turn) == pytest.approx(0.15, abs=0.01)
    assert lag_share(0.2 * turn, turn) == pytest.approx(-0.2)  # a step that overturns
    assert np.isnan(lag_share(np.ones(3), np.zeros(3)))  # nothing turned: nothing to share

"""Group identities of so(3) / se(3) / SE(3) against independent computations."""

import numpy as np
import pytest
from scipy.linalg import expm, logm

from core import se3

RNG = np.random.default_rng(42)
ROTVECS = [RNG.normal(size=3) for _ in range(6)] + [
    np.zeros(3),
    np.array([1e-9, 0, 0]),
    np.array([0, 3e-5, 1e-5]),
    np.array([np.pi, 0, 0]),
    np.pi * np.array([1, 1, 0]) / np.sqrt(2),
    (np.pi - 1e-7) * np.array([0, 0.6, 0.8]),
]
TWISTS = [np.concatenate([RNG.normal(size=3), w]) for w in ROTVECS]


def test_twist_convention_is_translation_first():
    G = se3.exp_se3(np.array([1.0, 2.0, 3.0, 0, 0, 0]))
    np.testing.assert_allclose(G[:3, 3], [1, 2, 3])
    np.testing.assert_allclose(G[:3, :3], np.eye(3))
    R = se3.exp_se3(np.array([0, 0, 0, 0, 0, np.pi / 2]))[:3, :3]
    np.testing.assert_allclose(R @ [1, 0, 0], [0, 1, 0], atol=1e-12)


GROUPS = {
    "so3": (se3.exp_so3, se3.log_so3, se3.hat3),
    "se3": (se3.exp_se3, se3.log_se3, se3.hat6),
}
CASES = [("so3", w) for w in ROTVECS] + [("se3", xi) for xi in TWISTS]


@pytest.mark.parametrize("group, x", CASES)
def test_exp_matches_the_matrix_exponential(group, x):
    exp, _, hat = GROUPS[group]
    np.testing.assert_allclose(exp(x), expm(hat(x)), atol=1e-10)


@pytest.mark.parametrize("group, x", CASES)
def test_log_inverts_exp_with_rotation_angle_at_most_pi(group, x):
    exp, log, _ = GROUPS[group]
    X = exp(x)
    y = log(X)
    np.testing.assert_allclose(exp(y), X, atol=1e-8)
    w, w_in = (y, x) if group == "so3" else (y[3:], x[3:])
    assert np.linalg.norm(w) <= np.pi + 1e-12
    if np.linalg.norm(w_in) < np.pi - 1e-3:
        np.testing.assert_allclose(y, x, atol=1e-8)


def test_log_se3_matches_matrix_log_for_a_generic_motion():
    xi = np.array([0.3, -0.2, 0.5, 0.4, -0.7, 0.2])
    np.testing.assert_allclose(se3.log_se3(se3.exp_se3(xi)), xi, atol=1e-10)
    np.testing.assert_allclose(se3.hat6(xi), np.real(logm(se3.exp_se3(xi))), atol=1e-9)


@pytest.mark.parametrize("xi", TWISTS[:6])
def test_adjoint_is_conjugation(xi):
    G = se3.exp_se3(RNG.normal(size=6))
    lhs = se3.hat6(se3.adjoint(G) @ xi)
    rhs = G @ se3.hat6(xi) @ np.linalg.inv(G)
    np.testing.assert_allclose(lhs, rhs, atol=1e-10)


def test_inverse_and_hat_vee():
    G = se3.exp_se3(RNG.normal(size=6))
    np.testing.assert_allclose(se3.inverse(G) @ G, np.eye(4), atol=1e-12)
    xi = RNG.normal(size=6)
    np.testing.assert_allclose(se3.vee6(se3.hat6(xi)), xi)
    w = RNG.normal(size=3)
    p = RNG.normal(size=3)
    np.testing.assert_allclose(se3.hat3(w) @ p, np.cross(w, p))


def test_twist_of_axis_rotates_about_its_line():
    q = np.array([1.0, 2.0, 0.0])
    xi = se3.twist_of_axis(np.array([0, 0, 1.0]), q)
    G = se3.exp_se3(xi * np.pi)
    np.testing.assert_allclose(G @ np.append(q, 1), np.append(q, 1), atol=1e-12)  # fixed
    np.testing.assert_allclose((G @ [2.0, 2.0, 0, 1])[:3], [0, 2, 0], atol=1e-12)


def test_rotation_angle_between_is_accurate_near_zero_and_pi():
    for angle in [1e-7, 1e-3, 1.0, np.pi - 1e-6]:
        R = se3.exp_so3(np.array([0, angle, 0]))
        assert se3.rotation_angle_between(np.eye(3), R) == pytest.approx(angle, rel=1e-6)
    a, b = np.array([1.0, 0, 0]), np.array([np.cos(1e-6), np.sin(1e-6), 0])
    assert se3.angle_between_vectors(a, b) == pytest.approx(1e-6, rel=1e-6)

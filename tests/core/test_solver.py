"""Damped least squares and the EM weights against direct computations."""

import numpy as np
import pytest

from core.solver import (
    DegenerateSystem,
    NormalEquations,
    channel_rows,
    mixture_cost,
    point_noise,
    solve,
    support_posterior,
    support_weights,
)


def test_solves_a_consistent_system_exactly_without_damping():
    rng = np.random.default_rng(0)
    A = rng.normal(size=(200, 7)) * [1, 10, 100, 0.1, 1, 5, 0.01]  # badly scaled columns
    x = rng.normal(size=7)
    ne = NormalEquations.zeros(7)
    ne.add(A, -(A @ x), np.ones(200))
    np.testing.assert_allclose(solve(ne, 0.0), x, rtol=1e-8)


def test_weights_and_damping_match_the_closed_form():
    rng = np.random.default_rng(1)
    A, r, w = rng.normal(size=(50, 4)), rng.normal(size=50), rng.uniform(0.1, 1, 50)
    ne = NormalEquations.zeros(4)
    ne.add(A[:20], r[:20], w[:20])
    ne.add(A[20:], r[20:], w[20:])
    H = A.T @ (w[:, None] * A)
    b = A.T @ (w * r)
    prior, offset, lam = np.array([0.0, 1.0, 2.0, 0.5]), rng.normal(size=4), 0.3
    expect = np.linalg.solve(H + lam * np.diag(np.diag(H)) + np.diag(prior),
                             -(b + prior * offset))
    np.testing.assert_allclose(solve(ne, lam, prior, offset), expect, rtol=1e-9)


def test_inactive_unknowns_stay_put_and_the_rest_solve_their_subsystem():
    rng = np.random.default_rng(2)
    A, r = rng.normal(size=(40, 5)), rng.normal(size=40)
    ne = NormalEquations.zeros(5)
    ne.add(A, r, np.ones(40))
    active = np.array([True, False, True, True, False])
    step = solve(ne, 0.0, active=active)
    assert step[1] == 0 and step[4] == 0
    sub = A[:, active]
    np.testing.assert_allclose(step[active], np.linalg.lstsq(sub, -r, rcond=None)[0], rtol=1e-9)


def test_equations_in_turned_unknowns_give_the_same_step_and_hold_a_direction():
    """``NormalEquations.changed``: solved in unknowns x with parameters T x (T orthogonal),
    the undamped step T x is the one solved directly; holding one of x holds the parameters
    to the plane T's other columns span, where the step is least squares (against lstsq on
    the rows A T with that column left out)."""
    rng = np.random.default_rng(4)
    A, r = rng.normal(size=(80, 5)), rng.normal(size=80)
    ne = NormalEquations.zeros(5)
    ne.add(A, r, np.ones(80))
    T = np.linalg.qr(rng.normal(size=(5, 5)))[0]
    turned = ne.changed(T)
    np.testing.assert_allclose(T @ solve(turned, 0.0), solve(ne, 0.0), rtol=1e-9)
    assert ne.changed(None) is ne
    active = np.array([True, True, False, True, True])
    step = T @ solve(turned, 0.0, active=active)
    assert abs(step @ T[:, 2]) < 1e-12
    x = np.linalg.lstsq((A @ T)[:, active], -r, rcond=None)[0]
    np.testing.assert_allclose(step, T[:, active] @ x, rtol=1e-9)


def test_an_unknown_only_rounding_errors_see_stays_put():
    """A column of rounding errors (1e-17 of the others: a root's translation along the line
    of sight of one view turned off the world's axes) is an unknown nothing sees; scaled like
    the rest it took a step of about a million, now none, and the others solve as without it."""
    rng = np.random.default_rng(3)
    A, r = rng.normal(size=(60, 4)), rng.normal(size=60)
    A[:, 2] = rng.normal(size=60) * 1e-17
    ne = NormalEquations.zeros(4)
    ne.add(A, r, np.ones(60))
    for lam in (1e-6, 1e-2):
        step = solve(ne, lam)
        assert abs(step[2]) < 1e-9
        rest = [0, 1, 3]
        H = A[:, rest].T @ A[:, rest]
        expect = np.linalg.solve(H + lam * np.diag(np.diag(H)), -(A[:, rest].T @ r))
        np.testing.assert_allclose(step[rest], expect, rtol=1e-9)


def test_no_rows_is_reported():
    with pytest.raises(DegenerateSystem, match="no usable pixels"):
        solve(NormalEquations.zeros(3), 1e-3)


def test_support_weights_are_the_irls_weights_of_the_mixture_cost():
    r = np.linspace(-0.1, 0.1, 41)
    sigma, c, h = 0.02, 0.1, 1e-7
    dcost = (mixture_cost(r + h, sigma, c) - mixture_cost(r - h, sigma, c)) / (2 * h)
    np.testing.assert_allclose(support_weights(r, sigma, c) * r, dcost, atol=1e-5)
    assert mixture_cost(np.array([0.0]), sigma, c)[0] == pytest.approx(0, abs=1e-15)
    assert support_weights(np.array([0.2]), sigma, c)[0] < 1e-3 * support_weights(
        np.array([0.0]), sigma, c)[0]


def test_a_pixels_channels_share_one_inlier_posterior_and_each_its_own_irls_weight():
    """A colour pixel's residuals (N, C) over their own noise scales: the cost is the
    one-channel cost of their combined standardised residual, and support_weights times r
    is the cost's gradient in each channel (central differences)."""
    rng = np.random.default_rng(0)
    r = rng.normal(0, 0.03, (50, 3))
    sigma = np.array([0.02, 0.05, 0.01]) * np.ones((50, 1))
    c, h = 0.1, 1e-7
    combined = np.sqrt(np.sum((r / sigma) ** 2, 1))  # one channel with sigma 1
    np.testing.assert_allclose(mixture_cost(r, sigma, c), mixture_cost(combined, 1.0, c),
                               rtol=1e-12)
    np.testing.assert_allclose(support_posterior(r, sigma, c),
                               support_posterior(combined, 1.0, c), rtol=1e-12)
    for ch in range(3):
        e = np.zeros(3)
        e[ch] = h
        dcost = (mixture_cost(r + e, sigma, c) - mixture_cost(r - e, sigma, c)) / (2 * h)
        np.testing.assert_allclose(support_weights(r, sigma, c)[:, ch] * r[:, ch], dcost,
                                   atol=1e-4)


def _normal_equations_of(rows: np.ndarray, r: np.ndarray, w: np.ndarray) -> NormalEquations:
    ne = NormalEquations.zeros(rows.shape[1])
    ne.add(rows, r, w)
    return ne


def test_two_rows_a_pixel_pose_its_channels_normal_equations():
    """Each pixel's C channel rows g_c^T J (J its own 2 x P image Jacobian) against the two
    rows ``channel_rows`` gives it, through the same J: the same A^T W A and A^T W r. Among
    the pixels, one whose channels' gradients all lie along one line and one with none."""
    rng = np.random.default_rng(3)
    M, C, P = 40, 3, 7
    J = rng.normal(size=(M, 2, P))
    grad = rng.normal(size=(M, C, 2))
    grad[1] = np.outer([1.0, -2.0, 0.5], [0.6, 0.8])  # rank one
    grad[2] = 0.0  # no gradient
    r, w = rng.normal(size=(M, C)), rng.uniform(0.1, 2.0, size=(M, C))
    channels = _normal_equations_of(np.einsum("mck,mkp->mcp", grad, J).reshape(-1, P),
                                    r.ravel(), w.ravel())
    g2, r2, w2 = channel_rows(grad, r, w)
    assert g2.shape == (2 * M, 2) and r2.shape == w2.shape == (2 * M,)
    two = _normal_equations_of(np.einsum("nk,nkp->np", g2, np.concatenate([J, J])), r2, w2)
    np.testing.assert_allclose(two.H, channels.H, rtol=1e-10, atol=1e-10)
    np.testing.assert_allclose(two.b, channels.b, rtol=1e-10, atol=1e-10)
    assert not g2[2].any() and not g2[M + 2].any() and r2[2] == r2[M + 2] == 0
    assert not g2[M + 1].any()  # the rank-one pixel's second row


def test_a_pixels_noise_adds_what_a_misplacement_makes_of_its_gradient():
    """Monte Carlo against the formula: ramps read at points misplaced by a Gaussian of
    ``misplaced`` pixels each way, with the image's own noise on top, vary as
    ``point_noise`` says; a flat pixel keeps its own noise."""
    rng = np.random.default_rng(3)
    sigma, misplaced, n = 0.02, 0.6, 200_000
    grads = np.array([[0.0, 0.0], [0.08, -0.05], [0.01, 0.02]])
    spread = [np.std((rng.normal(0.0, misplaced, (n, 2)) @ g) + rng.normal(0.0, sigma, n))
              for g in grads]
    noise = point_noise(np.full((3, 1), sigma), np.sum(grads**2, axis=1)[:, None], misplaced)
    np.testing.assert_allclose(spread, noise[:, 0], rtol=0.01)
    assert noise[0, 0] == sigma
    assert noise[1, 0] > 2.5 * sigma  # a steep edge's pixel weighs under a sixth of a flat one's
    np.testing.assert_array_equal(point_noise(noise, np.ones_like(noise), 0.0), noise)

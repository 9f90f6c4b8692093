"""Weighted, damped least squares over all views at once, and the pixel weights.

Each pixel's residual r (brightness in the new frame minus its template) is scored by the
negative log-likelihood of a two-component mixture: a Gaussian of scale sigma for pixels that
move with their segment and a flat density for everything else (background inside a blob,
occluders, shading changes). Iteratively reweighted least squares on that cost is the EM
support-map step of paper section 2.4: each row's weight is the posterior that its pixel
belongs to the body, over sigma^2.

The step solves the Levenberg-Marquardt normal equations (paper eqs. 6, 31, 34 with damping
and a prior)

.. math:: (A^T W A + \\lambda\\,\\mathrm{diag}(A^T W A) + P)\\,\\delta = -(A^T W r + P o)

where P is a diagonal prior weight pulling the accumulated offset o back toward the predicted
pose. A normal matrix that is not positive definite is reported, never silently inverted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg

UNSEEN = 1e-12  # an unknown whose information is under this share of the largest is unseen


class DegenerateSystem(RuntimeError):
    """The linear system has no usable solution (no pixels, or singular after damping)."""


@dataclass
class NormalEquations:
    """Accumulates A^T W A and A^T W r over blocks of rows."""

    H: np.ndarray
    b: np.ndarray
    rows: int = 0

    @classmethod
    def zeros(cls, n: int) -> NormalEquations:
        return cls(np.zeros((n, n)), np.zeros(n))

    def changed(self, T: np.ndarray | None) -> NormalEquations:
        """The same equations in unknowns x with parameters ``T`` x (T (P, P) orthogonal;
        None: these)."""
        if T is None:
            return self
        return NormalEquations(T.T @ self.H @ T, T.T @ self.b, self.rows)

    def add(self, A: np.ndarray, r: np.ndarray, w: np.ndarray) -> None:
        """Add rows A (N, P), residuals r (N,) and IRLS weights w (N,)."""
        Aw = A * w[:, None]
        self.H += Aw.T @ A
        self.b += Aw.T @ r
        self.rows += len(r)


def squared_residual(r: np.ndarray, sigma: float | np.ndarray) -> np.ndarray:
    """Per pixel, its residual over its noise scale squared, summed over its channels: r and
    sigma (N,) for one channel or (N, C) for C."""
    z = (r / sigma) ** 2
    return z if z.ndim == 1 else z.sum(axis=1)


def channel_rows(grad: np.ndarray, r: np.ndarray, w: np.ndarray
                 ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Two rows a pixel that pose the same normal equations as its C channels' rows.

    A channel's row is g_c^T J, J the pixel's 2 x P image Jacobian, so the channels add
    J^T T J to A^T W A and J^T v to A^T W r, with T = sum_c w_c g_c g_c^T (the pixel's 2 x 2
    structure tensor) and v = sum_c w_c r_c g_c: the rows l_k^T J of T's Cholesky factor
    L = [l_1 l_2], with residuals L^-1 v and unit weights, add the same. A tensor of rank one
    or none (gradients all along one line, or none) gives zero rows where L has no column.
    ``grad`` (M, C, 2) each channel's gradient, ``r`` and ``w`` (M, C) its residual and
    weight; returns gradients (2 M, 2), residuals and weights (2 M,): every pixel's first
    row, then every pixel's second."""
    gx, gy = grad[..., 0], grad[..., 1]
    t00, t01, t11 = (np.sum(w * a * b, axis=1) for a, b in ((gx, gx), (gx, gy), (gy, gy)))
    v0, v1 = np.sum(w * r * gx, axis=1), np.sum(w * r * gy, axis=1)
    tiny = UNSEEN * float(np.max(t00 + t11, initial=0.0))  # under it a column is rounding
    l11 = np.sqrt(np.maximum(t00, 0.0))
    first = t00 > tiny
    l11_or_1 = np.where(first, l11, 1.0)
    l21 = np.where(first, t01 / l11_or_1, 0.0)
    t22 = t11 - l21 * l21
    second = t22 > tiny
    l22 = np.sqrt(np.where(second, t22, 1.0))
    rho1 = np.where(first, v0 / l11_or_1, 0.0)
    rho2 = np.where(second, (v1 - rho1 * l21) / l22, 0.0)
    M = len(t00)
    out = np.zeros((2 * M, 2))
    out[:M, 0] = np.where(first, l11, 0.0)
    out[:M, 1] = l21
    out[M:, 1] = np.where(second, l22, 0.0)
    return out, np.concatenate([rho1, rho2]), np.ones(2 * M)


def mixture_cost(r: np.ndarray, sigma: float | np.ndarray, outlier: float) -> np.ndarray:
    """Per-pixel cost -log(exp(-z / 2) + outlier), shifted to 0 at z = 0, with z the pixel's
    ``squared_residual``: a pixel follows its blob in every channel or is an outlier in all.

    ``outlier`` is the flat density relative to the Gaussian's peak; a pixel that is hidden or
    off the image costs the full outlier price log((1 + outlier) / outlier)."""
    return np.log1p(outlier) - np.log(np.exp(-0.5 * squared_residual(r, sigma)) + outlier)


def support_posterior(r: np.ndarray, sigma: float | np.ndarray, outlier: float) -> np.ndarray:
    """Per pixel (N,), the posterior that it follows its blob under :func:`mixture_cost`'s
    mixture (the EM E-step): 1 / (1 + outlier) at r = 0, toward 0 far out."""
    g = np.exp(-0.5 * squared_residual(r, sigma))
    return g / (g + outlier)


def support_weights(r: np.ndarray, sigma: float | np.ndarray, outlier: float) -> np.ndarray:
    """IRLS weights of :func:`mixture_cost`, r's shape: the pixel's inlier posterior over
    each channel's sigma^2."""
    post = support_posterior(r, sigma, outlier)
    return (post if np.ndim(r) == 1 else post[:, None]) / sigma**2


def point_noise(sigma: np.ndarray, slope: np.ndarray, misplaced: float | np.ndarray
                ) -> np.ndarray:
    """Points' noise scales, ``sigma``'s shape: their measured ``sigma`` and, in
    quadrature, what a misplacement of ``misplaced`` pixels (standard deviation, each way;
    one for all points or one per point, broadcast against ``sigma``) makes of their
    brightness, whose squared gradient is ``slope`` (per pixel squared): a point
    misplaced by d changes by grad . d to first order, so its variance gains
    misplaced^2 |grad|^2 (Simoncelli, Adelson and Heeger, 1991). A steep edge's pixel,
    which the blobs' shapes misplace as much as any, varies most."""
    return np.sqrt(sigma**2 + misplaced**2 * slope)


def robust_scale(r: np.ndarray, floor: float) -> float:
    """Noise scale of residuals from their median absolute deviation, at least ``floor``."""
    if len(r) == 0:
        return floor
    return max(1.4826 * float(np.median(np.abs(r - np.median(r)))), floor)


def solve(
    ne: NormalEquations,
    damping: float,
    prior: np.ndarray | None = None,
    offset: np.ndarray | None = None,
    active: np.ndarray | None = None,
) -> np.ndarray:
    """The damped Gauss-Newton step for the accumulated normal equations.

    ``damping`` is Marquardt's lambda (relative to each unknown's own information);
    ``prior`` (P,) holds diagonal prior weights and ``offset`` (P,) the current offset from the
    prior's centre; unknowns outside the boolean mask ``active`` (P,) stay put. Raises
    DegenerateSystem when there are no rows or no finite solution.
    """
    if active is not None and not np.all(active):
        idx = np.flatnonzero(active)
        sub = NormalEquations(ne.H[np.ix_(idx, idx)], ne.b[idx], ne.rows)
        step = np.zeros(len(ne.b))
        step[idx] = solve(sub, damping, None if prior is None else prior[idx],
                          None if offset is None else offset[idx])
        return step
    H, b = ne.H, ne.b
    P = len(b)
    if ne.rows == 0 or not np.all(np.isfinite(H)) or not np.all(np.isfinite(b)):
        raise DegenerateSystem("no usable pixels in any view")
    d = np.diag(H).copy()
    pw = np.zeros(P) if prior is None else prior
    # Jacobi scaling keeps radians, pixels and scale on one footing for the factorisation;
    # an unknown no pixel sees gets a unit diagonal and stays put. "No pixel" includes a
    # column of rounding errors (a root's translation along the line of sight of one view
    # that is not aligned with the world's axes): scaled up, it was flung 1e5-1e11 metres
    diag = d * (1 + damping) + pw
    diag[diag <= UNSEEN * diag.max()] = 1.0
    S = 1 / np.sqrt(diag)
    M = (H - np.diag(d)) * S[:, None] * S[None, :] + np.eye(P)
    rhs = -(b + (pw * offset if offset is not None else 0.0)) * S
    try:
        c = scipy.linalg.cho_factor(M, check_finite=False)
    except np.linalg.LinAlgError:
        raise DegenerateSystem("the normal matrix is singular even after damping") from None
    step = S * scipy.linalg.cho_solve(c, rhs, check_finite=False)
    if not np.all(np.isfinite(step)):
        raise DegenerateSystem("the step is not finite")
    return step

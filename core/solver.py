"""Weighted, damped least squares over all views at once, and the pixel weights.

The step solves  (A^T W A + lambda D) delta = -A^T W r  (paper eqs. 6, 31, 34 with damping),
in Jacobi-scaled unknowns so that radians, pixels and scale mix well; an optional prior pulls
toward a given offset (the predicted pose) with the same scaling. A normal matrix that is not
positive definite after damping is reported, never silently inverted.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import scipy.linalg


class DegenerateSystem(RuntimeError):
    """The linear system has no usable solution (no pixels, or singular after damping)."""


@dataclass
class NormalEquations:
    """Accumulates A^T W A and A^T W r over blocks of rows (views, point sets)."""

    H: np.ndarray
    b: np.ndarray
    cost: float = 0.0
    weight: float = 0.0
    rows: int = 0

    @classmethod
    def zeros(cls, n: int) -> "NormalEquations":
        return cls(np.zeros((n, n)), np.zeros(n))

    def add(self, A: np.ndarray, r: np.ndarray, w: np.ndarray) -> None:
        """Add rows A (N, P), residuals r (N,) and weights w (N,)."""
        Aw = A * w[:, None]
        self.H += Aw.T @ A
        self.b += Aw.T @ r
        self.cost += float(np.sum(w * r * r))
        self.weight += float(np.sum(w))
        self.rows += len(r)


def solve(
    ne: NormalEquations,
    damping: float = 1e-3,
    prior: float = 0.0,
    offset: np.ndarray | None = None,
    floor: np.ndarray | None = None,
) -> np.ndarray:
    """The damped Gauss-Newton step.

    With S = diag(1 / sqrt(diag H + floor)), solves (S H S + (damping + prior) I) y =
    -S b - prior * offset / S and returns delta = S y. ``offset`` is the current parameter
    offset from the prior's centre; ``floor`` (P,) keeps unobserved unknowns finite.
    """
    H, b = ne.H, ne.b
    P = len(b)
    if ne.rows == 0 or not np.all(np.isfinite(H)) or not np.all(np.isfinite(b)):
        raise DegenerateSystem("no usable pixels in any view")
    d = np.diag(H).copy()
    d += floor if floor is not None else 1e-9 * max(float(d.max()), 1e-12)
    S = 1 / np.sqrt(d)
    Hs = H * S[:, None] * S[None, :] + (damping + prior) * np.eye(P)
    rhs = -S * b
    if prior and offset is not None:
        rhs -= prior * offset / S
    try:
        c, low = scipy.linalg.cho_factor(Hs, check_finite=False)
    except np.linalg.LinAlgError:
        raise DegenerateSystem("the normal matrix is singular even after damping") from None
    return S * scipy.linalg.cho_solve((c, low), rhs, check_finite=False)


def robust_scale(r: np.ndarray, floor: float) -> float:
    """Noise scale of residuals from their median absolute deviation, at least ``floor``."""
    if len(r) == 0:
        return floor
    return max(1.4826 * float(np.median(np.abs(r - np.median(r)))), floor)


def support_weights(r: np.ndarray, sigma: float, outlier_density: float = 0.1) -> np.ndarray:
    """EM posterior that each pixel follows the body's motion (paper section 2.4).

    Two-component mixture per pixel: a zero-mean Gaussian of scale sigma for pixels that move
    with their segment, and a flat density for everything else (background inside the blob,
    occluders, specularities). ``outlier_density`` is the flat density times sigma*sqrt(2 pi).
    """
    inlier = np.exp(-0.5 * (r / sigma) ** 2)
    return inlier / (inlier + outlier_density)

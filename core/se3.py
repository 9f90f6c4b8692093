"""Rigid-body mathematics: so(3), se(3), SE(3) and similarities, in closed form.

Convention, used everywhere in this project: a twist is **xi = (v, omega)**, translation part
first (Murray, Li and Sastry; Bregler, Malik and Pullen eq. 9). Rotations are 3x3 matrices,
rigid motions 4x4 homogeneous matrices; all arrays are float64. Functions accept one element or a
stack along the leading axes where that is natural (``hat3``, ``exp_so3`` on (..., 3)).
"""

from __future__ import annotations

import math

import numpy as np

_SMALL = 1e-8


def hat3(w: np.ndarray) -> np.ndarray:
    """Skew matrix [w]x with [w]x @ p == cross(w, p); w has shape (..., 3) -> (..., 3, 3)."""
    w = np.asarray(w, dtype=float)
    W = np.zeros(w.shape[:-1] + (3, 3))
    W[..., 0, 1], W[..., 0, 2], W[..., 1, 2] = -w[..., 2], w[..., 1], -w[..., 0]
    W[..., 1, 0], W[..., 2, 0], W[..., 2, 1] = w[..., 2], -w[..., 1], w[..., 0]
    return W


def vee3(W: np.ndarray) -> np.ndarray:
    """Inverse of :func:`hat3`: (..., 3, 3) skew matrix -> (..., 3) vector."""
    W = np.asarray(W, dtype=float)
    return np.stack([W[..., 2, 1], W[..., 0, 2], W[..., 1, 0]], -1)


def hat6(xi: np.ndarray) -> np.ndarray:
    """4x4 matrix of the twist xi = (v, omega) (paper eq. 9)."""
    xi = np.asarray(xi, dtype=float)
    X = np.zeros((4, 4))
    X[:3, :3] = hat3(xi[3:])
    X[:3, 3] = xi[:3]
    return X


def vee6(X: np.ndarray) -> np.ndarray:
    """Inverse of :func:`hat6`: 4x4 matrix in se(3) -> twist (v, omega)."""
    X = np.asarray(X, dtype=float)
    return np.concatenate([X[:3, 3], vee3(X[:3, :3])])


def _sinc_ab(theta: np.ndarray):
    """A = sin t / t and B = (1 - cos t) / t^2, series near 0."""
    t2 = theta * theta
    small = theta < 1e-4
    ts = np.where(small, 1.0, theta)
    A = np.where(small, 1 - t2 / 6 + t2 * t2 / 120, np.sin(ts) / ts)
    B = np.where(small, 0.5 - t2 / 24 + t2 * t2 / 720, (1 - np.cos(ts)) / ts**2)
    return A, B


def _sinc_terms(theta: np.ndarray):
    """``_sinc_ab``'s A and B, and C = (t - sin t) / t^3, series near 0."""
    A, B = _sinc_ab(theta)
    t2 = theta * theta
    small = theta < 1e-4
    ts = np.where(small, 1.0, theta)
    C = np.where(small, 1 / 6 - t2 / 120 + t2 * t2 / 5040, (ts - np.sin(ts)) / ts**3)
    return A, B, C


def exp_so3(w: np.ndarray) -> np.ndarray:
    """Rotation matrix of the rotation vector w (axis times angle, radians): Rodrigues' formula.

    .. math:: e^{[w]} = I + \\frac{\\sin t}{t}[w] + \\frac{1-\\cos t}{t^2}[w]^2,\\ t = |w|
    """
    w = np.asarray(w, dtype=float)
    if w.shape == (3,):  # the common case, without array overhead
        return _exp_so3_one(float(w[0]), float(w[1]), float(w[2]))
    theta = np.linalg.norm(w, axis=-1)
    A, B = _sinc_ab(theta)
    W = hat3(w)
    eye = np.broadcast_to(np.eye(3), W.shape)
    return eye + A[..., None, None] * W + B[..., None, None] * (W @ W)


def _exp_so3_one(x: float, y: float, z: float) -> np.ndarray:
    """Rodrigues' formula for one rotation vector, in plain floats."""
    t2 = x * x + y * y + z * z
    if t2 < 1e-8:
        A, B = 1 - t2 / 6 + t2 * t2 / 120, 0.5 - t2 / 24 + t2 * t2 / 720
    else:
        t = math.sqrt(t2)
        A, B = math.sin(t) / t, (1 - math.cos(t)) / t2
    return np.array([
        [1 - B * (y * y + z * z), B * x * y - A * z, B * x * z + A * y],
        [B * x * y + A * z, 1 - B * (x * x + z * z), B * y * z - A * x],
        [B * x * z - A * y, B * y * z + A * x, 1 - B * (x * x + y * y)],
    ])


def log_so3(R: np.ndarray) -> np.ndarray:
    """Rotation vector of a rotation matrix, angle in [0, pi]; exact at 0 and at pi."""
    R = np.asarray(R, dtype=float)
    cos_t = np.clip((np.trace(R) - 1) / 2, -1.0, 1.0)
    theta = np.arccos(cos_t)
    axis_sin = vee3(R - R.T) / 2  # sin(t) * axis
    if theta < 1e-4:
        return axis_sin * (1 + theta * theta / 6)
    if np.pi - theta > 1e-3:
        return axis_sin * theta / np.sin(theta)
    # Near pi: R = I + 2 a a^T - ... ; recover the axis from the symmetric part.
    S = (R + R.T) / 2 - cos_t * np.eye(3)  # = (1 - cos t) a a^T
    k = int(np.argmax(np.diag(S)))
    a = S[:, k] / np.linalg.norm(S[:, k])
    if axis_sin @ a < 0:
        a = -a
    return a * theta


def exp_se3(xi: np.ndarray) -> np.ndarray:
    """4x4 rigid motion e^{hat(xi)} of the twist xi = (v, omega) (paper eq. 10, closed form)."""
    xi = np.asarray(xi, dtype=float)
    v, w = xi[:3], xi[3:]
    theta = np.linalg.norm(w)
    A, B, C = _sinc_terms(np.asarray(theta))
    W = hat3(w)
    V = np.eye(3) + B * W + C * (W @ W)
    G = np.eye(4)
    G[:3, :3] = np.eye(3) + A * W + B * (W @ W)
    G[:3, 3] = V @ v
    return G


def log_se3(G: np.ndarray) -> np.ndarray:
    """Twist (v, omega) with exp_se3(xi) == G, rotation angle in [0, pi]."""
    G = np.asarray(G, dtype=float)
    w = log_so3(G[:3, :3])
    theta = np.linalg.norm(w)
    W = hat3(w)
    A, B = _sinc_ab(np.asarray(theta))
    if theta < 1e-4:
        coef = 1 / 12 + theta * theta / 720
    else:
        coef = (1 - A / (2 * B)) / theta**2
    V_inv = np.eye(3) - 0.5 * W + coef * (W @ W)
    return np.concatenate([V_inv @ G[:3, 3], w])


def adjoint(G: np.ndarray) -> np.ndarray:
    """6x6 adjoint of a rigid motion, acting on twists (v, omega) (paper eq. 25).

    .. math:: Ad_G = \\begin{bmatrix} R & [p]R \\\\ 0 & R \\end{bmatrix},\\
              \\widehat{Ad_G \\xi} = G \\hat\\xi G^{-1}
    """
    R, p = G[:3, :3], G[:3, 3]
    Ad = np.zeros((6, 6))
    Ad[:3, :3] = R
    Ad[:3, 3:] = hat3(p) @ R
    Ad[3:, 3:] = R
    return Ad


def inverse(G: np.ndarray) -> np.ndarray:
    """Inverse of a 4x4 rigid motion without a general matrix inverse."""
    R, p = G[:3, :3], G[:3, 3]
    Gi = np.eye(4)
    Gi[:3, :3] = R.T
    Gi[:3, 3] = -R.T @ p
    return Gi


def rigid(R: np.ndarray, p: np.ndarray) -> np.ndarray:
    """4x4 rigid motion from a rotation and a translation."""
    G = np.eye(4)
    G[:3, :3] = R
    G[:3, 3] = p
    return G


def rotation_about_point(R: np.ndarray, c: np.ndarray) -> np.ndarray:
    """4x4 motion rotating by R about the point c: x -> R (x - c) + c."""
    return rigid(R, c - R @ c)


def twist_of_axis(omega: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Twist of a pure rotation about the line through q with unit direction omega (eq. 20).

    xi = (-omega x q, omega).
    """
    omega = np.asarray(omega, dtype=float)
    return np.concatenate([-np.cross(omega, q), omega])


def frame_along(u: np.ndarray) -> np.ndarray:
    """Rows: the unit vector along u and two unit vectors across it, a right-handed frame."""
    u = np.asarray(u, dtype=float) / np.linalg.norm(u)
    v = np.cross(u, np.eye(3)[int(np.argmin(np.abs(u)))])
    v /= np.linalg.norm(v)
    return np.stack([u, v, np.cross(u, v)])


def is_rotation(R: np.ndarray, tol: float = 1e-4) -> bool:
    """Whether R is a 3x3 rotation matrix: orthonormal within ``tol``, determinant +1."""
    R = np.asarray(R, dtype=float)
    return bool(R.shape == (3, 3) and np.allclose(R @ R.T, np.eye(3), atol=tol)
                and np.linalg.det(R) > 0)


def rotation_angle_between(R1: np.ndarray, R2: np.ndarray) -> np.ndarray:
    """Angle (radians) of R1^T R2, robust in float32 via atan2; works on stacks (..., 3, 3)."""
    D = np.swapaxes(R1, -1, -2) @ R2
    c = (np.trace(D, axis1=-2, axis2=-1) - 1) / 2
    s = np.linalg.norm(vee3(D - np.swapaxes(D, -1, -2)), axis=-1) / 2
    return np.arctan2(s, c)


def angle_between_vectors(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Angle (radians) between vectors along the last axis, via atan2 (accurate near 0 and pi)."""
    return np.arctan2(np.linalg.norm(np.cross(a, b), axis=-1), np.sum(a * b, axis=-1))


class Similarity:
    """A scaled rigid motion x -> s * (R x + t): scale s (>0), rotation R, translation t.

    Used for a view's scaled orthographic pose: reference (world) frame to scaled camera frame.
    """

    __slots__ = ("s", "R", "t")

    def __init__(self, s: float, R: np.ndarray, t: np.ndarray):
        self.s = float(s)
        self.R = np.asarray(R, dtype=float).reshape(3, 3)
        self.t = np.asarray(t, dtype=float).reshape(3)

    def apply(self, X: np.ndarray) -> np.ndarray:
        """Map points (..., 3) to the scaled frame."""
        return self.s * (X @ self.R.T + self.t)

    def compose(self, G: np.ndarray) -> Similarity:
        """self o G for a 4x4 rigid motion G applied first."""
        return Similarity(self.s, self.R @ G[:3, :3], self.R @ G[:3, 3] + self.t)

    def matrix(self) -> np.ndarray:
        """4x4 matrix of the similarity (top-left block s R)."""
        M = rigid(self.s * self.R, self.s * self.t)
        return M

    def copy(self) -> Similarity:
        return Similarity(self.s, self.R.copy(), self.t.copy())

"""Cameras: how a view maps world points to pixels. Two models behind one interface.

Pixels have x right and y down, origin at the top-left pixel's centre; a camera frame has x
right, y down, z away from the camera (OpenCV's convention).

* ``View``, scaled orthographic (the paper's): pixel = s * (R X + t)[:2] + center.
  q = s * (R X + t) is a point's *scaled camera* coordinate: its x, y are pixels relative to
  ``center`` and its z is depth in pixel units. Its pose may be tracked per view
  (``core.pose``'s independent mode).
* ``Pinhole``, perspective: x_cam = R X + t, pixel = (K x_cam / z)[:2]. Always calibrated (the
  body's root is tracked in the world). Lens distortion is not part of it: footage filmed
  through a distorting lens is undistorted as it is read (``core.lens``) and tracked through
  the ideal pinhole.

What the tracker asks of a camera: ``project``, ``pullback`` (image gradients carried to the
world through the projection's Jacobian), ``scale_at`` (pixels per world unit at a point),
``orientation`` (the camera's axes in the world), ``ray`` and ``ray_lines`` (the world ray of a
pixel, affine in the pixel), ``ellipses`` (an ellipsoid's outline), ``at_level`` and ``copy``.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .se3 import Similarity, exp_so3, log_so3

IN_PLACE_PIXELS = 0.5  # parallax of a turning camera's backdrop still taken for none


@dataclass
class View:
    """A scaled orthographic camera: its similarity (world to scaled camera frame) and
    principal point."""

    pose: Similarity
    center: np.ndarray  # (2,) pixel coordinates of the optical axis

    central = False  # its rays are parallel

    def scaled(self, X: np.ndarray) -> np.ndarray:
        """Scaled camera coordinates (..., 3) of world points (..., 3)."""
        return self.pose.apply(X)

    def project(self, X: np.ndarray) -> np.ndarray:
        """Pixels (..., 2) of world points (..., 3)."""
        return self.scaled(X)[..., :2] + self.center

    def pullback(self, X: np.ndarray, grad: np.ndarray) -> np.ndarray:
        """Image gradients ``grad`` (N, 2) at the pixels of world points X (N, 3) carried to
        the world: m (N, 3) with grad . (pixel motion) = m . (world displacement) (the
        projection's Jacobian, transposed, applied to each gradient)."""
        return grad @ (self.pose.s * self.pose.R[:2])

    def scale_at(self, X: np.ndarray) -> float:
        """Pixels per world unit, wherever the point X (3,) is."""
        return float(self.pose.s)

    @property
    def orientation(self) -> np.ndarray:
        """(3, 3): the camera's x, y and z (line of sight) axes in the world, as rows."""
        return self.pose.R

    def ray_lines(self) -> tuple[np.ndarray, ...]:
        """Pixel (u, v)'s world ray X(l) = o + l d with o = o0 + u ox + v oy and
        d = d0 + u dx + v dy: (o0, ox, oy, d0, dx, dy). Here o lies on the plane z_cam = 0 and
        d is the unit line of sight, the same for every pixel."""
        s, R, t = self.pose.s, self.pose.R, self.pose.t
        o0 = R.T @ (np.array([-self.center[0] / s, -self.center[1] / s, 0.0]) - t)
        zero = np.zeros(3)
        return o0, R[0] / s, R[1] / s, R[2].copy(), zero, zero

    def ray(self, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World rays of pixels (..., 2): origins (..., 3) and unit directions (..., 3) pointing
        away from the camera; a point's distance along its ray is its depth."""
        return _rays(self, pixels)

    def ellipses(self, A: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Outlines of ellipsoids given by world-to-normalised maps A (..., 3, 3) and world
        centres C (..., 3) (``raycast.blob_frames``): pixel p is inside ellipsoid e's when
        (p - c_e)^T P_e (p - c_e) <= 1; returns c (..., 2) and P (..., 2, 2), the camera-frame
        quadric with depth eliminated."""
        AR = _rows_times(A, self.pose.R.T) / self.pose.s  # normalised coordinates per
        # scaled-camera unit
        M = np.swapaxes(AR, -1, -2) @ AR
        P = M[..., :2, :2] - M[..., :2, 2:] * M[..., 2:, :2] / M[..., 2:, 2:]
        return self.project(C), P

    def copy(self) -> View:
        return View(self.pose.copy(), np.array(self.center, dtype=float))

    def extrapolated(self, prev: View, gain: float) -> View:
        """This view moved again by ``gain`` times the step from ``prev`` to it (a tracked
        view's constant-velocity prediction)."""
        step = self.pose.matrix() @ np.linalg.inv(prev.pose.matrix())
        sR = step[:3, :3]
        s = np.cbrt(np.linalg.det(sR))
        w = log_so3(sR / s)
        st = np.eye(4)
        st[:3, :3] = s**gain * exp_so3(gain * w)
        st[:3, 3] = gain * step[:3, 3]
        M = st @ self.pose.matrix()
        sn = np.cbrt(np.linalg.det(M[:3, :3]))
        return View(Similarity(sn, M[:3, :3] / sn, M[:3, 3] / sn), self.center.copy())

    def at_level(self, level: int) -> View:
        """The same camera on pyramid level ``level``: pixel p of the full image is pixel
        p / 2**level there (see core.image)."""
        f = 0.5**level
        pose = Similarity(self.pose.s * f, self.pose.R, self.pose.t)
        return View(pose, np.asarray(self.center) * f)


@dataclass
class Pinhole:
    """A perspective camera: intrinsics K (3, 3: focal lengths and principal point in pixels,
    upper triangular), and the world-to-camera rotation R and translation t (x_cam = R X + t,
    X in the skeleton's units)."""

    K: np.ndarray
    R: np.ndarray
    t: np.ndarray

    central = True  # its rays all start at its centre

    @property
    def centre(self) -> np.ndarray:
        """The camera's centre in the world (3,)."""
        return -self.R.T @ self.t

    def camera_points(self, X: np.ndarray) -> np.ndarray:
        """Camera-frame coordinates (..., 3) of world points (..., 3)."""
        return X @ self.R.T + self.t

    def project(self, X: np.ndarray) -> np.ndarray:
        """Pixels (..., 2) of world points (..., 3) in front of the camera."""
        p = self.camera_points(X) @ self.K.T
        return p[..., :2] / p[..., 2:]

    def pullback(self, X: np.ndarray, grad: np.ndarray) -> np.ndarray:
        """As ``View.pullback``; the Jacobian is K's top-left block times
        (1/z) [[1, 0, -x/z], [0, 1, -y/z]] times R at each point's camera coordinates."""
        x = self.camera_points(X)
        iz = 1.0 / x[:, 2]
        g = grad @ self.K[:2, :2]  # the gradient per unit of x/z, y/z
        gz = np.stack([g[:, 0] * iz, g[:, 1] * iz,
                       -(g[:, 0] * x[:, 0] + g[:, 1] * x[:, 1]) * iz * iz], 1)
        return gz @ self.R

    def scale_at(self, X: np.ndarray) -> float:
        """Pixels per world unit at the point X (3,): the focal length over its depth."""
        return float(np.sqrt(self.K[0, 0] * self.K[1, 1]) / self.camera_points(X)[2])

    @property
    def orientation(self) -> np.ndarray:
        """(3, 3): the camera's x, y and z (optical axis) axes in the world, as rows."""
        return self.R

    def ray_lines(self) -> tuple[np.ndarray, ...]:
        """Pixel (u, v)'s world ray X(l) = o + l d (see ``View.ray_lines``): o is the camera's
        centre for every pixel and d = R^T K^-1 (u, v, 1), so that l is the camera-frame
        depth z."""
        Ki = np.linalg.inv(self.K)
        d = Ki.T @ self.R  # rows: R^T K^-1 times each unit vector
        zero = np.zeros(3)
        return self.centre, zero, zero, d[2].copy(), d[0].copy(), d[1].copy()

    def ray(self, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World rays of pixels (..., 2): origins (..., 3), all the camera's centre, and unit
        directions (..., 3) away from it; a point's distance along its ray is its depth."""
        return _rays(self, pixels)

    def ellipses(self, A: np.ndarray, C: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Outlines of ellipsoids in front of the camera, as ``View.ellipses``: the cone of
        rays tangent to each ellipsoid, (p^T G p - 1) G - G p p^T G for the ellipsoid
        (x - p)^T G (x - p) = 1 in the camera frame, carried to pixels by K^-1 and written
        about its centre."""
        AR = _rows_times(A, self.R.T)
        G = np.swapaxes(AR, -1, -2) @ AR
        p = self.camera_points(C)
        Gp = np.einsum("...ab,...b->...a", G, p)
        cone = (np.sum(p * Gp, -1) - 1)[..., None, None] * G - Gp[..., :, None] * Gp[..., None, :]
        Ki = np.linalg.inv(self.K)
        Q = Ki.T @ cone @ Ki  # pixel (u, v) is inside where (u, v, 1) Q (u, v, 1) < 0
        P0, q = Q[..., :2, :2], Q[..., :2, 2]
        c = -np.linalg.solve(P0, q[..., None])[..., 0]
        k = -np.sum(q * c, -1) - Q[..., 2, 2]
        return c, P0 / k[..., None, None]

    def copy(self) -> Pinhole:
        return Pinhole(np.array(self.K, dtype=float), np.array(self.R, dtype=float),
                       np.array(self.t, dtype=float))

    def extrapolated(self, prev: Pinhole, gain: float) -> Pinhole:
        """A pinhole is calibrated, never tracked: itself."""
        return self.copy()

    def at_level(self, level: int) -> Pinhole:
        """The same camera on pyramid level ``level`` (pixel p there is p * 2**level in the
        full image)."""
        return Pinhole(np.diag([0.5**level, 0.5**level, 1.0]) @ self.K, self.R, self.t)


Camera = View | Pinhole


def intrinsics_problem(K: np.ndarray) -> str:
    """'' for intrinsics K a ``Pinhole`` can take, else what is wrong with them."""
    K = np.asarray(K, dtype=float)
    if K.shape != (3, 3) or not np.all(np.isfinite(K)):
        return "expected a 3x3 matrix [[fx, 0, cx], [0, fy, cy], [0, 0, 1]]"
    if K[1, 0] != 0 or K[2, 0] != 0 or K[2, 1] != 0 or K[2, 2] != 1:
        return f"expected an upper triangular matrix with last row [0, 0, 1], got {K.tolist()}"
    if not (K[0, 0] > 0 and K[1, 1] > 0):
        return f"the focal lengths fx = {K[0, 0]:g}, fy = {K[1, 1]:g} (pixels) must be > 0"
    return ""


def turn_homography(src: Pinhole, dst: Pinhole) -> np.ndarray:
    """(3, 3) map of ``src``'s pixels to ``dst``'s, homogeneous, for two pinholes with one
    centre (a camera turned on a tripod): K_dst R_dst R_src^T K_src^-1, the same for scene
    points at every depth."""
    return dst.K @ dst.R @ src.R.T @ np.linalg.inv(src.K)


def turns_in_place(cameras: Sequence[Camera], point: np.ndarray) -> bool:
    """Whether ``cameras`` (one camera on every frame) are pinholes that only turn: their
    centres so close together that anything at or beyond ``point`` (3,) moves less than
    ``IN_PLACE_PIXELS`` between them against what ``turn_homography`` says."""
    if not all(isinstance(c, Pinhole) for c in cameras):
        return False
    centres = np.array([c.centre for c in cameras])
    shift = np.max(np.linalg.norm(centres - centres[0], axis=1))
    return all(shift * c.scale_at(point) <= IN_PLACE_PIXELS for c in cameras)


def _rows_times(A: np.ndarray, B: np.ndarray) -> np.ndarray:
    """A @ B for a stack A (..., 3, 3) and one B (3, 3), as one product of A's rows: numpy
    calls BLAS once instead of once per matrix, and each entry is the same sum."""
    return (A.reshape(-1, 3) @ B).reshape(A.shape)


def _rays(camera: Camera, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """``ray`` of either camera, from its ``ray_lines``."""
    pixels = np.asarray(pixels, dtype=float)
    o0, ox, oy, d0, dx, dy = camera.ray_lines()
    u, v = pixels[..., :1], pixels[..., 1:2]
    d = d0 + u * dx + v * dy
    return o0 + u * ox + v * oy, d / np.linalg.norm(d, axis=-1, keepdims=True)

"""A view: scaled orthographic projection of world points to pixels.

pixel = s * (R X + t)[:2] + center, X in world units, pixels with x right and y down, origin
at the top-left pixel's centre; the camera frame has x right, y down, z away from the camera.
q = s * (R X + t) is a point's *scaled camera* coordinate: its x, y are pixels relative to
``center`` and its z is depth in pixel units.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .se3 import Similarity


@dataclass
class View:
    """One camera: its similarity (world to scaled camera frame) and principal point."""

    pose: Similarity
    center: np.ndarray  # (2,) pixel coordinates of the optical axis

    def scaled(self, X: np.ndarray) -> np.ndarray:
        """Scaled camera coordinates (..., 3) of world points (..., 3)."""
        return self.pose.apply(X)

    def project(self, X: np.ndarray) -> np.ndarray:
        """Pixels (..., 2) of world points (..., 3)."""
        return self.scaled(X)[..., :2] + self.center

    def ray(self, pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """World ray of each pixel: origin on the plane z_cam = 0 (..., 3) and unit direction (3,)
        pointing away from the camera."""
        q = np.concatenate(
            [(pixels - self.center) / self.pose.s, np.zeros(pixels.shape[:-1] + (1,))], -1
        )
        origin = (q - self.pose.t) @ self.pose.R
        return origin, self.pose.R[2].copy()

    def copy(self) -> View:
        return View(self.pose.copy(), np.array(self.center, dtype=float))

    def at_level(self, level: int) -> View:
        """The same camera on pyramid level ``level``: pixel p of the full image is pixel
        p / 2**level there (see core.image)."""
        f = 0.5**level
        pose = Similarity(self.pose.s * f, self.pose.R, self.pose.t)
        return View(pose, np.asarray(self.center) * f)

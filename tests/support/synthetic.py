"""Synthetic footage for core tests: the skeleton's own blobs, textured in their reference
frame, rendered through the real ray caster. Lets a test know the exact motion."""

from __future__ import annotations

import cv2
import numpy as np

from core import raycast, se3
from core.camera import Pinhole, View
from core.image import to_uint8
from core.pose import BodyPose

# Footage drawn from the tracker's own blobs misplaces no pixel: where a test reads how
# closely the tracker recovers such footage's motion, it tracks without the misplacement
# that real footage's misfit of blobs to body calls for (``TrackerSettings.registration_noise``).
EXACT = {"registration_noise": 0.0}


def texture(ref: np.ndarray, seed: int = 0, wavelength: float = 0.08) -> np.ndarray:
    """Cloth-like smooth random texture of reference-frame points (N, 3): plane waves of
    random directions with wavelengths from a third to once ``wavelength`` (world units)."""
    rng = np.random.default_rng(seed)
    k = rng.normal(size=(12, 3))
    k *= (2 * np.pi / wavelength) / np.linalg.norm(k, axis=1, keepdims=True)
    k *= rng.uniform(1.0, 3.0, size=(12, 1))
    phase = rng.uniform(0, 2 * np.pi, 12)
    v = np.sin(ref @ k.T + phase).mean(1)
    return 0.5 + 0.8 * v


def _surface(skeleton, pose: BodyPose, view_index: int, shape) -> tuple[np.ndarray, np.ndarray]:
    """Which pixels of an image of ``shape`` show the body in one view (H, W), and the
    reference-frame points (N, 3) they show, row by row."""
    view = pose.views[view_index]
    g = skeleton.segment_motions(skeleton.joint_frames(pose.rotations, pose.root_position))
    H, W = shape
    xs, ys = np.meshgrid(np.arange(W), np.arange(H))
    pix = np.stack([xs.ravel(), ys.ravel()], 1).astype(float)
    hits = raycast.cast(view, pix, skeleton.blobs, g)
    ok = hits.label >= 0
    joints = np.array([b.joint for b in skeleton.blobs])[hits.label[ok]]
    gj = g[joints]
    ref = np.einsum("nba,nb->na", gj[:, :3, :3], hits.world[ok] - gj[:, :3, 3])
    return ok.reshape(H, W), ref


def render(skeleton, pose: BodyPose, view_index: int, shape=(360, 320), background=0.3,
           noise=0.0, seed=0) -> np.ndarray:
    """Render one view as a float32 grey image."""
    on, ref = _surface(skeleton, pose, view_index, shape)
    img = np.full(shape, background)
    img[on] = texture(ref)
    if noise:
        img = img + np.random.default_rng(seed).normal(0, noise, img.shape)
    return np.clip(img, 0, 1).astype(np.float32)


def render_hues(skeleton, pose: BodyPose, view_index: int, shape=(360, 320)) -> np.ndarray:
    """Render one view as uint8 BGR whose every pixel has one brightness: the body's cloth
    differs from itself and from the grey backdrop in hue alone (two textures as its
    chroma channels), so that a grey image of it is flat."""
    on, ref = _surface(skeleton, pose, view_index, shape)
    ycrcb = np.full(shape + (3,), 0.5, np.float32)
    ycrcb[on, 1] += 0.15 * (texture(ref, seed=1) - 0.5)
    ycrcb[on, 2] += 0.15 * (texture(ref, seed=2) - 0.5)
    bgr = cv2.cvtColor(np.clip(ycrcb, 0, 1), cv2.COLOR_YCrCb2BGR)
    return to_uint8(bgr)


def side_view(scale=160.0, center=(160, 180), yaw_deg=90.0, height=0.9) -> View:
    """Orthographic camera looking horizontally at a y-up body (world y up -> image y down),
    turned ``yaw_deg`` about the vertical axis; the world point (0, height, 0) maps to center."""
    flip = np.diag([1.0, -1.0, -1.0])  # y up to y down, looking along -z
    R = flip @ se3.exp_so3(np.array([0, np.radians(yaw_deg), 0]))
    t = -R @ np.array([0, height, 0]) + np.array([0, 0, 5.0])
    return View(se3.Similarity(scale, R, t), np.array(center, dtype=float))


def side_pinhole(scale=160.0, center=(160, 180), yaw_deg=90.0, height=0.9, distance=3.0
                 ) -> Pinhole:
    """``side_view``'s pinhole twin: the camera ``distance`` world units from (0, height, 0),
    with the focal length that shows that point's depth at ``scale`` pixels per unit."""
    flip = np.diag([1.0, -1.0, -1.0])
    R = flip @ se3.exp_so3(np.array([0, np.radians(yaw_deg), 0]))
    t = -R @ np.array([0, height, 0]) + np.array([0, 0, distance])
    f = scale * distance
    return Pinhole(np.array([[f, 0, center[0]], [0, f, center[1]], [0, 0, 1.0]]), R, t)

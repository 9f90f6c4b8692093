"""Walk cycles from tracked motion: the gait period, a partial cycle completed by mirroring
left and right, a seamless loop, and zero-phase smoothing.

Curves are arrays (frames, channels) sampled at a fixed rate; rotations are unit quaternions
(frames, 4) or 3x3 matrices. Which joints pair across the body is the caller's to say.
"""

from __future__ import annotations

from collections.abc import Callable

import numpy as np
from scipy.signal import butter, filtfilt

from .errors import InputError


class CycleError(InputError):
    """Curves that hold no usable cycle, or settings that do not fit them."""


def gait_period(curves: np.ndarray, min_frames: int = 4) -> float:
    """Period in frames (sub-frame) of the repetition in ``curves`` (F, C): the first peak of
    the mean normalised autocorrelation past its first zero crossing that reaches 80 % of the
    highest there (later peaks are multiples), refined by a parabola through its neighbours."""
    x = np.asarray(curves, float).reshape(len(curves), -1)
    x = (x - x.mean(0)) / np.maximum(x.std(0), 1e-12)
    F = len(x)
    ac = np.array([np.mean(x[: F - k] * x[k:]) for k in range(F // 2)])
    below = np.flatnonzero(ac < 0)
    start = max(int(below[0]), min_frames) if len(below) else len(ac)
    tail = ac[start:]
    if not len(tail):
        raise CycleError(f"the curves do not repeat within half their length ({F} frames)")
    peaks = [i for i in range(1, len(tail) - 1)
             if tail[i - 1] <= tail[i] >= tail[i + 1] and tail[i] >= 0.8 * tail.max()]
    k = start + (peaks[0] if peaks else int(np.argmax(tail)))
    if k + 1 < len(ac):
        a, b, c = ac[k - 1], ac[k], ac[k + 1]
        if a - 2 * b + c < 0:
            return float(k + 0.5 * (a - c) / (a - 2 * b + c))
    return float(k)


def sample(curve: np.ndarray, t: np.ndarray) -> np.ndarray:
    """Linear interpolation of a curve (F, C) at fractional frames t (clamped)."""
    F = len(curve)
    t = np.clip(t, 0, F - 1)
    i = np.minimum(np.floor(t).astype(int), F - 2)
    f = (t - i)[:, None]
    return curve[i] * (1 - f) + curve[i + 1] * f


def complete_by_mirroring(curves: np.ndarray, period: float,
                          mirror: Callable[[np.ndarray], np.ndarray]) -> np.ndarray:
    """Complete a gait recorded over less than a cycle (the paper completed a 60 % walk this
    way): at frame t past the recording the body moves as it did at t - period / 2, mirrored.
    ``curves`` (F, C) hold every channel of the body, F >= period / 2; ``mirror`` maps rows
    (k, C) onto the mirrored body's rows (sides swapped and reflected, see ``mirror_poses``).
    Returns one period (round(period) rows): the recorded frames as they were, then the rest."""
    half = period / 2
    F = len(curves)
    if F < half:
        raise CycleError(f"{F} frames are less than half a period ({half:.1f} frames)")
    t = np.arange(F, int(round(period)), dtype=float)
    recorded = np.asarray(curves, float)[: int(round(period))]
    if not len(t):
        return recorded
    return np.concatenate([recorded, mirror(sample(recorded, t - half))])


def reflection(normal: np.ndarray) -> np.ndarray:
    """3x3 reflection across the plane through the origin with the given normal."""
    n = np.asarray(normal, float) / np.linalg.norm(normal)
    return np.eye(3) - 2 * np.outer(n, n)


def mirror_poses(turns: np.ndarray, root: np.ndarray, partners: np.ndarray,
                 normal: np.ndarray, centre: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The body's mirror image across its sagittal plane, pose by pose.

    turns (k, J, 3, 3): each joint's rotation from its rest pose, written in the body's rest
    axes (the rest body symmetric across x = 0), so that a joint's world orientation is the
    product of the turns from the root down; joint 0 is the root, whose turn also carries the
    heading. root (k, 3): the root's position. partners (J,): each joint's other-side joint
    (itself on the midline). normal, centre: the sagittal plane the motion is mirrored across,
    in the root's parent axes. Joint j of the mirror image turns as S turns[partners[j]] S
    (S flips rest x); the root as S_p turns[0] S (S_p reflects across the plane); its position
    is reflected across the plane."""
    S = np.diag([-1.0, 1.0, 1.0])
    Sp = reflection(normal)
    out = S @ turns[:, partners] @ S
    out[:, 0] = Sp @ turns[:, 0] @ S
    c = np.asarray(centre, float)
    return out, c + (np.asarray(root, float) - c) @ Sp.T


def make_loop(cycle: np.ndarray, blend: int) -> np.ndarray:
    """The cycle (F, C) with its last ``blend`` frames replaced by a cubic Hermite bridge from
    frame F - blend - 1 (its value and slope) to the cycle's start seen as frame F (value and
    slope of frames 0 and 1), so that repeating it is continuous in value and slope."""
    x = np.asarray(cycle, float).copy()
    F = len(x)
    if not 1 <= blend < F - 2:
        raise CycleError(f"blend must be between 1 and {F - 3} frames")
    a = F - blend - 1
    p0, m0 = x[a], x[a] - x[a - 1]
    p1, m1 = x[0], x[1] - x[0]
    L = F - a  # frames from the bridge's start to the next cycle's first frame
    u = (np.arange(1, blend + 1) / L)[:, None]
    x[a + 1:] = ((2 * u**3 - 3 * u**2 + 1) * p0 + (u**3 - 2 * u**2 + u) * L * m0
                 + (-2 * u**3 + 3 * u**2) * p1 + (u**3 - u**2) * L * m1)
    return x


def lowpass(curves: np.ndarray, cutoff_hz: float, fps: float) -> np.ndarray:
    """Zero-phase Butterworth low-pass (second order, run forward and back) of curves (F, C)."""
    if not 0 < cutoff_hz < fps / 2:
        raise CycleError(f"the cutoff must be between 0 and {fps / 2} Hz (half the frame rate)")
    b, a = butter(2, cutoff_hz / (fps / 2))
    return filtfilt(b, a, np.asarray(curves, float), axis=0,
                    padlen=min(len(curves) - 1, 3 * max(len(a), len(b))))


def continuous_quaternions(q: np.ndarray) -> np.ndarray:
    """A rotation track (F, 4) with each quaternion put on the side of its predecessor (q and
    -q are one rotation), so that the components change smoothly."""
    q = np.asarray(q, float).copy()
    for i in range(1, len(q)):
        if q[i] @ q[i - 1] < 0:
            q[i] = -q[i]
    return q


def lowpass_quaternions(q: np.ndarray, cutoff_hz: float, fps: float) -> np.ndarray:
    """Low-pass a rotation track (F, 4): made continuous (``continuous_quaternions``), then
    filtered and normalised."""
    f = lowpass(continuous_quaternions(q), cutoff_hz, fps)
    return f / np.linalg.norm(f, axis=1, keepdims=True)

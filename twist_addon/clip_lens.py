"""A movie clip's lens distortion, as Blender's Movie Clip editor holds it (typed in, or
solved by its camera solver), undone as a view's footage is read.

Blender's tracking library (libmv) distorts a point of the clip's pixel grid with y up from
the bottom row and pixel centres on integers, normalised about the principal point by the
focal length in pixels, (x, y) -> (x d(r) + tx, y d(r) + ty) with r^2 = x^2 + y^2:

- Polynomial: d = 1 + k1 r^2 + k2 r^4 + k3 r^6, no tangential terms;
- Division: d = 1 / (1 + k1 r^2 + k2 r^4), no tangential terms;
- Brown: d = 1 + k1 r^2 + ... + k4 r^8; tx = p1 (r^2 + 2 x^2) + 2 p2 x y,
  ty = p2 (r^2 + 2 y^2) + 2 p1 x y.

With y down (OpenCV's pixels, ``core.lens``) the radial part is unchanged (Division is
OpenCV's rational model with only the denominator's k4, k5) and Brown's tangential part is
OpenCV's with p1 = -Brown's p2 and p2 = Brown's p1 (the y flip turns the sign of every term
odd in y). Blender's Nuke model, Brown's r^8 term and non-square pixels have no OpenCV
counterpart: such footage is tracked as filmed, with a note.
"""

from __future__ import annotations

import numpy as np

from ..core.image import read_source
from ..core.lens import Undistorted
from .bridge import BridgeError


def distorting_clip(camera_obj):
    """The first movie clip behind the camera object whose lens distortion is set, or None."""
    for bg in camera_obj.data.background_images if camera_obj is not None else ():
        clip = bg.clip if bg.source == "MOVIE_CLIP" else None
        if clip is not None and any(abs(k) > 1e-9 for k in _coefficients(clip.tracking.camera)):
            return clip
    return None


def _coefficients(tc) -> tuple[float, ...]:
    return {"POLYNOMIAL": (tc.k1, tc.k2, tc.k3),
            "DIVISION": (tc.division_k1, tc.division_k2),
            "NUKE": (tc.nuke_k1, tc.nuke_k2),
            "BROWN": (tc.brown_k1, tc.brown_k2, tc.brown_k3, tc.brown_k4, tc.brown_p1,
                      tc.brown_p2)}.get(tc.distortion_model, ())


def opencv_lens(clip) -> tuple[np.ndarray, np.ndarray] | str:
    """The clip's lens as OpenCV's K (3, 3) and distortion (k1, k2, p1, p2, k3[, k4, k5,
    k6]) on the clip's pixels (x right, y down, origin at the top-left pixel's centre); or,
    where OpenCV's model cannot hold it, why not."""
    tc = clip.tracking.camera
    if abs(tc.pixel_aspect - 1.0) > 1e-6:
        return f"its pixels are not square (aspect {tc.pixel_aspect:g})"
    if tc.distortion_model == "POLYNOMIAL":
        dist = [tc.k1, tc.k2, 0.0, 0.0, tc.k3]
    elif tc.distortion_model == "DIVISION":
        dist = [0.0, 0.0, 0.0, 0.0, 0.0, tc.division_k1, tc.division_k2, 0.0]
    elif tc.distortion_model == "BROWN" and abs(tc.brown_k4) <= 1e-9:
        dist = [tc.brown_k1, tc.brown_k2, -tc.brown_p2, tc.brown_p1, tc.brown_k3]
    else:
        model = "Brown with k4" if tc.distortion_model == "BROWN" else \
            tc.distortion_model.title()
        return f"its distortion model ({model}) is not one the tracker can undo"
    f = tc.focal_length_pixels
    if f <= 0:
        return "its focal length is not set"
    height = clip.size[1]
    px, py = tc.principal_point_pixels  # y up from the bottom row
    K = np.array([[f, 0.0, px], [0.0, f, height - 1 - py], [0.0, 0.0, 1.0]])
    return K, np.array(dist, dtype=float)


def undistorted(view_pg, images) -> tuple[object, str]:
    """A view's footage (``footage_frames``) read through the lens of the movie clip behind
    its camera, and a note on it: the frames undistorted where the clip's distortion can be
    undone, as filmed where it cannot, and unchanged ('' for the note) without distortion.
    BridgeError when the footage is not the clip's size."""
    cam = view_pg.camera
    clip = distorting_clip(cam)
    if clip is None:
        return images, ""
    lens = opencv_lens(clip)
    if isinstance(lens, str):
        return images, (f"the clip '{clip.name}' behind '{cam.name}' has lens distortion that "
                        f"the tracker does not undo ({lens}): it tracked the footage as if "
                        "through an ideal lens (give the clip Polynomial, Division or Brown "
                        "distortion, render it undistorted, or add the views from a "
                        "calibration file)")
    height, width = read_source(images[0]).shape[:2]
    if tuple(clip.size) != (width, height):
        raise BridgeError(f"the clip '{clip.name}' behind '{cam.name}' is {clip.size[0]}x"
                          f"{clip.size[1]} but that view's footage is {width}x{height}: its "
                          "lens distortion is given for the clip's pixels; use the clip's own "
                          "footage for the view")
    return Undistorted(images, *lens), (
        f"the footage behind '{cam.name}' was undistorted through the lens of the clip "
        f"'{clip.name}' ({clip.tracking.camera.distortion_model.title()}) as it was read")

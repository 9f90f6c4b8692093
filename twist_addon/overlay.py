"""The blobs' outlines drawn over the viewport, so the user sees whether the body lines up,
and, looking through a view's camera, that view's joint markers of the current frame.

Seen through an orthographic camera, an ellipsoid's outline is the curve on it where the view
direction is tangent: in the blob's normalised frame (a unit sphere) a great circle across the
view direction. Drawn in 3D, that curve lands exactly on the projected support map.
"""

from __future__ import annotations

import numpy as np

from ..core.raycast import blob_frames
from ..core.se3 import frame_along
from ..core.skeleton import Skeleton

_HANDLE = None


def silhouette_loops(sk: Skeleton, R: np.ndarray, root: np.ndarray, view_dir: np.ndarray,
                     n: int = 48) -> np.ndarray:
    """World points (blobs, n, 3) of every blob's outline seen along ``view_dir``."""
    g = sk.segment_motions(sk.joint_frames(R, root))
    A, C = blob_frames(sk.blobs, g)
    t = np.linspace(0, 2 * np.pi, n, endpoint=False)
    out = np.empty((len(sk.blobs), n, 3))
    for i in range(len(sk.blobs)):
        _, a, b = frame_along(A[i] @ view_dir)  # the great circle across the view
        Y = np.cos(t)[:, None] * a + np.sin(t)[:, None] * b
        out[i] = np.linalg.solve(A[i], Y.T).T + C[i]
    return out


MARKER_PIXELS = 6.0  # half the size of a marker's cross, in footage pixels


def marker_crosses(cam, scene, markers: dict, depth_point) -> np.ndarray:
    """Line segments (markers * 4, 3): a cross of ``MARKER_PIXELS`` on each marker's pixel,
    placed among the bones (at the depth of ``depth_point``) along the camera's rays."""
    from .markers import point_of_pixel

    ends = []
    for p in markers.values():
        for d in ((MARKER_PIXELS, 0.0), (0.0, MARKER_PIXELS)):
            ends += [p - d, p + d]
    if not ends:
        return np.zeros((0, 3))
    return point_of_pixel(cam, scene, np.array(ends), depth_point)  # one camera read


def _draw():
    import bpy
    import gpu
    from gpu_extras.batch import batch_for_shader

    context = bpy.context
    scene = context.scene
    tw = getattr(scene, "twist", None)
    if tw is None or not tw.show_overlay or tw.armature is None:
        return
    rv3d = context.region_data
    if rv3d is None:
        return
    from .bridge import BridgeError, pose_from_armature, skeleton_from_armature

    try:
        sk = skeleton_from_armature(tw.armature)
    except BridgeError:
        return
    R, root = pose_from_armature(tw.armature, sk)
    view_dir = -np.array(rv3d.view_matrix.inverted().col[2][:3])
    loops = silhouette_loops(sk, R, root, view_dir)
    lines = np.concatenate([np.stack([lp, np.roll(lp, -1, 0)], 1).reshape(-1, 3)
                            for lp in loops]).astype(np.float32)
    shader = gpu.shader.from_builtin("UNIFORM_COLOR")
    batch = batch_for_shader(shader, "LINES", {"pos": lines})
    shader.uniform_float("color", (0.2, 1.0, 0.3, 0.9))
    gpu.state.line_width_set(1.5)
    batch.draw(shader)
    from .markers import markers_at, view_of_camera

    view = view_of_camera(scene, scene.camera)
    if rv3d.view_perspective == "CAMERA" and view is not None:
        try:
            crosses = marker_crosses(scene.camera, scene, markers_at(view, scene.frame_current),
                                     np.array(tw.armature.matrix_world.translation))
        except BridgeError:
            return
        if len(crosses):
            batch = batch_for_shader(shader, "LINES", {"pos": crosses.astype(np.float32)})
            shader.uniform_float("color", (1.0, 0.85, 0.1, 1.0))
            batch.draw(shader)


def register():
    global _HANDLE
    import bpy

    _HANDLE = bpy.types.SpaceView3D.draw_handler_add(_draw, (), "WINDOW", "POST_VIEW")


def unregister():
    global _HANDLE
    import bpy

    if _HANDLE is not None:
        bpy.types.SpaceView3D.draw_handler_remove(_HANDLE, "WINDOW")
        _HANDLE = None


CLASSES = ()

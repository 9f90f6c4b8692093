"""Fit the armature's pose on the current frame to joint markers placed in each view: the
paper's initialisation from clicked joints (section 2.6); on request its bone lengths too,
written into the rest pose (each bone's head moved along its offset from its parent's head,
so bone directions, rolls and therefore keyed rotations stay as they were).

Markers (see ``markers``) are kept per view and frame; the fit uses the current frame's.
"""

from __future__ import annotations

import csv
from pathlib import Path

import bpy
import numpy as np

from ..core.init_fit import FitError, fit_pose, least_certain
from ..core.pose import BodyPose, world_pose
from .armature_action import ArmatureAction
from .bridge import (
    BridgeError,
    pose_from_armature,
    set_pose,
    skeleton_from_armature,
    tracking_mode,
    view_from_camera,
)
from .markers import markers_at, set_marker


def read_markers_csv(path: Path, scene) -> int:
    """Load markers from a CSV of ``view, bone, x, y[, frame]`` rows (view: 1-based number or
    camera name; bone: a bone's name for its head, ``<bone>/end`` for the tail of one that
    ends a limb; frame: the scene frame, the current one if left out; a header row is
    skipped) into the scene's views; returns how many were read."""
    tw = scene.twist
    by_name = {v.camera.name: v for v in tw.views if v.camera}
    count = 0
    with open(path, newline="") as f:
        for i, row in enumerate(csv.reader(f), 1):
            if not row or row[0].strip().lower() == "view":
                continue
            if len(row) not in (4, 5):
                raise BridgeError(f"{path.name}, row {i}: expected view, bone, x, y[, frame]")
            key, bone, x, y = (c.strip() for c in row[:4])
            view = by_name.get(key) or (tw.views[int(key) - 1] if key.isdigit()
                                        and 0 < int(key) <= len(tw.views) else None)
            if view is None:
                raise BridgeError(f"{path.name}, row {i}: no view '{key}'")
            try:
                xy = float(x), float(y)
                frame = int(row[4]) if len(row) == 5 else scene.frame_current
            except ValueError:
                raise BridgeError(f"{path.name}, row {i}: x and y must be numbers, frame a "
                                  "whole number") from None
            set_marker(view, bone, frame, *xy)
            count += 1
    return count


def scale_bones(arm, factors: dict[str, float]) -> None:
    """Move each bone's head away from its parent's head by ``factors[bone]`` (1 if absent)
    times their rest distance; a tail on a child's head follows that head, any other tail
    keeps its bone's length (as the core skeleton keeps its end sites)."""
    view_layer = bpy.context.view_layer
    active, view_layer.objects.active = view_layer.objects.active, arm
    bpy.ops.object.mode_set(mode="EDIT")
    bones = arm.data.edit_bones
    old = {b.name: (np.array(b.head), np.array(b.tail)) for b in bones}
    head = {}
    for b in bones:  # parents come before their children
        if b.parent is None:
            head[b.name] = old[b.name][0]
        else:
            p = b.parent.name
            head[b.name] = head[p] + factors.get(b.name, 1.0) * (old[b.name][0] - old[p][0])
    for b in bones:
        h, t = old[b.name]
        on_child = [c.name for c in b.children if np.allclose(old[c.name][0], t, atol=1e-6)]
        tail = head[on_child[0]] if on_child else head[b.name] + (t - h)
        roll = b.roll
        b.head, b.tail, b.roll = head[b.name].tolist(), tail.tolist(), roll
    bpy.ops.object.mode_set(mode="OBJECT")
    view_layer.objects.active = active


def fit_armature(scene, fit_lengths: bool = False) -> tuple[float, dict[str, float], str]:
    """Pose the scene's armature to its views' markers, and with ``fit_lengths`` scale its
    bones to them too; returns the RMS pixel error, the length factor of every bone whose
    length changed, and which bones the markers pin least (``init_fit.least_certain``)."""
    tw = scene.twist
    arm = tw.armature
    if arm is None:
        raise BridgeError("no armature is set (Twist Mocap > Armature)")
    sk = skeleton_from_armature(arm)
    views = [view_from_camera(v.camera, scene) for v in tw.views if v.camera]
    if not views:
        raise BridgeError("there are no views with cameras to place markers in")
    clicks = [markers_at(v, scene.frame_current) for v in tw.views if v.camera]
    for c in clicks:
        for name in c:
            bone = name.partition("/")[0]  # a tip's marker: fit_pose checks it has one
            if bone not in sk.names:
                raise BridgeError(f"a marker names bone '{bone}', which '{arm.name}' lacks")
    R, root = pose_from_armature(arm, sk)
    mode = tracking_mode(scene, views)
    try:
        res = fit_pose(sk, BodyPose(R, root, views), clicks, mode, fit_lengths=fit_lengths)
    except FitError as e:
        raise BridgeError(str(e)) from None
    changed = {n: f for n, f in res.lengths.items() if abs(f - 1) > 1e-4}
    if changed:
        scale_bones(arm, changed)
        sk = skeleton_from_armature(arm)
    R_fit, root_fit = world_pose(mode, views[0], res.pose)
    set_pose(arm, sk, R_fit, root_fit)
    return res.residual_px, changed, least_certain(res.direction_uncertainty, views=len(views))


class TWIST_OT_import_markers(ArmatureAction, bpy.types.Operator):
    """Read joint markers from a CSV file of view, bone, x, y[, frame] rows (pixels, y down)"""

    bl_idname = "twist.import_markers"
    bl_label = "Import Markers"

    filepath: bpy.props.StringProperty(name="CSV File", subtype="FILE_PATH",
                                       description="The markers: view, bone, x, y[, frame] "
                                                   "per row")

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def run(self, context) -> str:
        n = read_markers_csv(Path(bpy.path.abspath(self.filepath)), context.scene)
        return f"read {n} markers"


class TWIST_OT_fit_pose(ArmatureAction, bpy.types.Operator):
    """Pose the armature on the current frame so that its joints land on the markers"""

    bl_idname = "twist.fit_pose"
    bl_label = "Fit Pose to Markers"

    fit_lengths: bpy.props.BoolProperty(
        name="Fit Bone Lengths", default=False,
        description="Also scale the bones to the markers (left and right alike) and write "
                    "the lengths into the armature's rest pose")

    def run(self, context) -> str:
        rms, changed, uncertain = fit_armature(context.scene, self.fit_lengths)
        context.view_layer.update()
        lengths = (", ".join(f"{n} x{f:.3f}" for n, f in sorted(changed.items()))
                   if changed else "")
        return (f"fitted: joints {rms:.1f} px from their markers (RMS)"
                + (f"; lengths {lengths}" if lengths else "") + f"; least certain: {uncertain}")


CLASSES = (TWIST_OT_import_markers, TWIST_OT_fit_pose)

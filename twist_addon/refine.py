"""Refine Skeleton: learn the armature's joint centres and hinge axes from the footage (the
paper's section 2.7, ``core.refine``), write them into its rest pose, and track again so
that the keys fit the new rest pose.

A refined bone's head moves to the new centre (disconnected from its parent, whose tail
stays, so the parent keeps its shape); a hinge's free axis turns by re-rolling the bone (a
hinge about the bone's own length cannot turn). Children keep their heads.
"""

from __future__ import annotations

import bpy
import numpy as np
from mathutils import Vector

from ..core.pose import CALIBRATED
from ..core.refine import SETTLED_SHIFT, SETTLED_TURN, RefineError, refine
from ..core.skeleton import BALL, HINGE, Skeleton
from . import keyframes
from .armature_action import ArmatureAction
from .bridge import BridgeError, set_pose, skeleton_from_armature
from .track import TrackSession


def write_rest_pose(arm, old: Skeleton, new: Skeleton) -> list[str]:
    """Move the bones whose joint centre or hinge axis differs between the two skeletons
    (core skeletons of ``arm``, world units and axes); returns their names."""
    W = np.array(arm.matrix_world)
    W_inv = np.linalg.inv(W)
    changed = [j for j in range(1, old.n_joints)
               if not np.allclose(old.rest_positions[j], new.rest_positions[j], atol=1e-7)
               or not np.allclose(old.axes[j], new.axes[j], atol=1e-9)]
    if not changed:
        return []
    view_layer = bpy.context.view_layer
    active, view_layer.objects.active = view_layer.objects.active, arm
    bpy.ops.object.mode_set(mode="EDIT")
    bones = arm.data.edit_bones
    for j in changed:
        eb = bones[old.names[j]]
        eb.use_connect = False
        eb.head = Vector((W_inv @ np.append(new.rest_positions[j], 1))[:3])
        if old.kinds[j] == HINGE:
            free = [k for k in range(3) if not arm.pose.bones[eb.name].lock_rotation[k]][0]
            axis = W_inv[:3, :3] @ new.axes[j]
            along = np.array(eb.tail - eb.head)
            if free == 2:
                eb.align_roll(Vector(axis))
            elif free == 0:  # local x along the axis: z = x cross y
                eb.align_roll(Vector(np.cross(axis, along)))
    bpy.ops.object.mode_set(mode="OBJECT")
    view_layer.objects.active = active
    return [old.names[j] for j in changed]


def refine_armature(scene, only_selected: bool, planar: bool, rounds: int,
                    progress=None) -> tuple[dict[str, float], str]:
    """Refine the scene armature's tracked joints (the selected bones only, if asked) over
    the frames from the current one to the end (or start, tracking backward), one round at a
    time, writing each round into the rest pose so that the bones' blobs follow their heads,
    until the joints settle or ``rounds`` are done; ``progress(rounds_done)`` after each.
    Returns each refined bone's move in world units over all rounds, and why the rounds
    stopped early ('' if they did not): a round that cannot refine (its tracking diverged)
    keeps the rounds before it; only a first round's error is raised, with nothing changed."""
    start, moves, stopped = None, {}, ""
    for r in range(rounds):
        session = TrackSession.from_scene(scene)
        tracker = session.tracker
        if tracker.mode != CALIBRATED:
            raise BridgeError("refining the skeleton needs calibrated views (Footage & Views "
                              "> Views: Calibrated)")
        arm, sk = session.armature, tracker.given_skeleton
        start = sk.rest_positions if start is None else start
        names = [n for n, k in zip(sk.names[1:], sk.kinds[1:]) if k in (HINGE, BALL)
                 and (not only_selected or arm.pose.bones[n].select)]
        if not names:
            raise BridgeError("no tracked bone is selected to refine: select the bones "
                              "whose joints to refine in Pose Mode" if only_selected
                              else "no tracked bone to refine")
        try:
            result = refine(sk, tracker.seq.images, session.initial, names, tracker.settings,
                            planar, rounds=1)
        except RefineError as e:
            if r == 0:
                raise BridgeError(str(e)) from None
            stopped = f"round {r + 1} could not refine ({e}); the skeleton of round {r} is kept"
            break
        moved = write_rest_pose(arm, sk, result.skeleton)
        new_sk = skeleton_from_armature(arm)
        set_pose(arm, new_sk, result.initial.rotations, result.initial.root_position)
        for n in moved:
            j = sk.index(n)
            moves[n] = float(np.linalg.norm(new_sk.rest_positions[j] - start[j]))
        if progress:
            progress(r + 1)
        if result.settled():
            break
    # tracking's keys of the range go (the first frame's too: the refined pose is set there,
    # and Track keys it again); the user's stay
    keyframes.clear(arm, new_sk, set(session.frames))
    return moves, stopped


class TWIST_OT_refine_skeleton(ArmatureAction, bpy.types.Operator):
    """Learn the joint centres and hinge axes from the footage: track, refine, repeat; then
    write them into the armature's rest pose and track again from the current frame"""

    bl_idname = "twist.refine_skeleton"
    bl_label = "Refine Skeleton"

    only_selected: bpy.props.BoolProperty(
        name="Only Selected Bones", default=True,
        description="Refine the selected bones only (select them in Pose Mode); off, every "
                    "tracked bone, which needs every limb tracked well")
    planar: bpy.props.BoolProperty(
        name="Planar", default=False,
        description="One view seeing the body side-on: joints move in the image plane and "
                    "hinge axes stay along the view")
    rounds: bpy.props.IntProperty(
        name="Rounds", default=10, min=1, max=30,
        description="Track-and-refine rounds, at most: each tracks the whole range, and "
                    "refining stops once a round moves no joint "
                    f"{1000 * SETTLED_SHIFT:g} mm and turns no axis {SETTLED_TURN:g} degrees")

    def invoke(self, context, event):
        return context.window_manager.invoke_props_dialog(self)

    def run(self, context) -> str:
        wm = context.window_manager
        wm.progress_begin(0, self.rounds)
        try:
            moved, stopped = refine_armature(context.scene, self.only_selected, self.planar,
                                             self.rounds, wm.progress_update)
        finally:
            wm.progress_end()
        # the rest pose has changed: what goes wrong from here is reported, not undone
        if stopped:
            self.report({"WARNING"}, stopped)
        tracked = bpy.ops.twist.track() == {"FINISHED"}
        if not tracked:
            self.report({"WARNING"}, "the refined skeleton could not be tracked again: "
                        "see Results, then Track")
        shown = ", ".join(f"{n} {100 * d:.1f} cm" for n, d in moved.items()) or "nothing"
        return f"refined{' and tracked again' if tracked else ''}; joints moved: {shown}"


CLASSES = (TWIST_OT_refine_skeleton,)

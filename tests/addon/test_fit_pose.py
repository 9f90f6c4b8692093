"""twist.import_markers and twist.fit_pose: markers in three views bring the armature back to
the pose they were projected from."""

import re

import numpy as np
import pytest

from support.views import one_view_example, projected_points
from support.views import three_view_scene as _scene_with_views


def _random_pose(bpy, arm, sk, rng, ball: float, hinge: float) -> None:
    """Turn every ball joint up to ``ball`` radians about a random axis, every hinge between
    0.2 and ``hinge`` radians."""
    from mathutils import Quaternion

    for name, kind in zip(sk.names, sk.kinds):
        pb = arm.pose.bones[name]
        if kind == "ball":
            pb.rotation_quaternion = Quaternion(rng.normal(0, 0.3, 3), ball)
        elif kind == "hinge":
            pb.rotation_euler[2] = rng.uniform(0.2, hinge)
    bpy.context.view_layer.update()


def test_fitting_markers_recovers_the_pose(bpy_module, registered, tmp_path, capfd):
    bpy = bpy_module

    scene, arm = _scene_with_views(bpy, registered)
    tw = registered.twist_addon
    sk = tw.bridge.skeleton_from_armature(arm)
    rng = np.random.default_rng(0)
    _random_pose(bpy, arm, sk, rng, 0.5, 1.0)
    R, root = tw.bridge.pose_from_armature(arm, sk)
    truth = sk.world_positions(R, root)
    rows = ["view,bone,x,y"]
    for i, v in enumerate(scene.twist.views):
        view = tw.bridge.view_from_camera(v.camera, scene)
        for j, name in enumerate(sk.names):
            if (i + j) % 5:  # each view misses a few joints
                x, y = view.project(truth[j]) + rng.normal(0, 0.5, 2)
                rows.append(f"{i + 1 if i else v.camera.name},{name},{x:.3f},{y:.3f}")
    (tmp_path / "markers.csv").write_text("\n".join(rows) + "\n")
    for pb in arm.pose.bones:  # back to the rest pose: the fit starts from there
        pb.rotation_quaternion = (1, 0, 0, 0)
        pb.rotation_euler = (0, 0, 0)
    assert bpy.ops.twist.import_markers(filepath=str(tmp_path / "markers.csv")) == {"FINISHED"}
    assert sum(len(v.markers) for v in scene.twist.views) == len(rows) - 1
    for v in scene.twist.views:  # markers of another frame, far off: the fit ignores them
        for name in sk.names:
            registered.twist_addon.markers.set_marker(v, name, scene.frame_current + 5, 0, 0)
    capfd.readouterr()
    assert bpy.ops.twist.fit_pose() == {"FINISHED"}
    bpy.context.view_layer.update()
    R2, root2 = tw.bridge.pose_from_armature(arm, sk)
    got = sk.world_positions(R2, root2)
    assert np.abs(got - truth).max() < 0.01  # metres
    # the message names the bones the markers pin least (tests/core/test_init_fit.py checks
    # the numbers against the fit's scatter)
    said = re.search(r"least certain: (\w+) \+-[\d.]+, (\w+) \+-[\d.]+, (\w+) \+-[\d.]+ "
                     r"degrees per pixel of click error", capfd.readouterr().out)
    assert said and set(said.groups()) <= set(sk.tracked_joint_names()), said


def test_bad_markers_are_refused(bpy_module, registered, tmp_path):
    bpy = bpy_module
    scene, arm = _scene_with_views(bpy, registered)
    (tmp_path / "bad.csv").write_text("1,LeftKnee,12,nope\n")
    with pytest.raises(RuntimeError, match="bad.csv, row 1: x and y must be numbers"):
        bpy.ops.twist.import_markers(filepath=str(tmp_path / "bad.csv"))
    (tmp_path / "few.csv").write_text("1,LeftKnee,100,200\n2,Neck,300,100\n")
    bpy.ops.twist.import_markers(filepath=str(tmp_path / "few.csv"))
    with pytest.raises(RuntimeError, match="click at least"):
        bpy.ops.twist.fit_pose()


def test_fitting_bone_lengths_writes_them_into_the_rest_pose(bpy_module, registered):
    """Markers projected from the template with longer thighs and shorter upper arms (left and
    right alike), 1 px of noise: the fit scales the limbs to within 2 % (the 10 cm trunk
    bones, 25 px long, within 6 %), keeps every bone's rest direction and roll, and its joints
    land within a centimetre."""
    bpy = bpy_module

    scene, arm = _scene_with_views(bpy, registered)
    tw = registered.twist_addon
    truth_factors = {"LeftKnee": 1.08, "RightKnee": 1.08, "LeftElbow": 0.92,
                     "RightElbow": 0.92}
    rest_before = {b.name: np.array(b.matrix_local)[:3, :3] for b in arm.data.bones}
    lengths_before = {b.name: b.length for b in arm.data.bones}
    tw.fit.scale_bones(arm, truth_factors)
    true_lengths = {b.name: b.length for b in arm.data.bones}
    assert true_lengths["LeftHip"] == pytest.approx(1.08 * lengths_before["LeftHip"])
    sk = tw.bridge.skeleton_from_armature(arm)
    rng = np.random.default_rng(1)
    _random_pose(bpy, arm, sk, rng, 0.4, 0.9)
    truth = sk.world_positions(*tw.bridge.pose_from_armature(arm, sk))
    for v in scene.twist.views:
        view = tw.bridge.view_from_camera(v.camera, scene)
        for j, name in enumerate(sk.names):
            tw.markers.set_marker(v, name, scene.frame_current,
                                  *view.project(truth[j]) + rng.normal(0, 1.0, 2))
    tw.fit.scale_bones(arm, {n: 1 / f for n, f in truth_factors.items()})  # the guess
    for pb in arm.pose.bones:
        pb.rotation_quaternion, pb.rotation_euler = (1, 0, 0, 0), (0, 0, 0)
    assert bpy.ops.twist.fit_pose(fit_lengths=True) == {"FINISHED"}
    bpy.context.view_layer.update()
    for b in arm.data.bones:
        limb = b.name.endswith(("Hip", "Knee", "Shoulder", "Elbow"))
        assert b.length == pytest.approx(true_lengths[b.name], rel=0.02 if limb else 0.06), (
            b.name)
        np.testing.assert_allclose(np.array(b.matrix_local)[:3, :3], rest_before[b.name],
                                   atol=1e-5)
    sk = tw.bridge.skeleton_from_armature(arm)
    got = sk.world_positions(*tw.bridge.pose_from_armature(arm, sk))
    assert np.abs(got - truth).max() < 0.01


def test_tip_markers_pose_the_bones_that_end_the_limbs(bpy_module, registered):
    """The horse example's quadruped, one side view: its lower legs and head end in their
    tails, which only tip markers (``<bone>/end``) can place. Markers on every head and tip
    of a bent pose bring every tip back onto its marker; heads alone leave the hooves off."""
    bpy = bpy_module
    scene, arm, view_pg, view, sk = one_view_example(bpy, registered, "muybridge_horse.blend")
    tw = registered.twist_addon
    leaves = [n for j, n in enumerate(sk.names) if sk.end_sites[j]]
    assert len(leaves) == 5  # four hooves and the head
    ends = [f"{n}/end" for n in leaves]

    def tips_and_heads():
        points = projected_points(tw.bridge, arm, sk, view, sk.names + ends)
        return ({n: points[n] for n in sk.names}, {n: points[n] for n in ends})

    _random_pose(bpy, arm, sk, np.random.default_rng(4), 0.3, 0.6)
    heads, tips = tips_and_heads()

    def fit(markers):
        view_pg.markers.clear()
        for name, xy in markers.items():
            tw.markers.set_marker(view_pg, name, scene.frame_current, *xy)
        for pb in arm.pose.bones:
            pb.rotation_quaternion, pb.rotation_euler = (1, 0, 0, 0), (0, 0, 0)
        assert bpy.ops.twist.fit_pose() == {"FINISHED"}
        bpy.context.view_layer.update()
        return tips_and_heads()[1]

    got = fit({**heads, **tips})
    assert max(np.linalg.norm(got[n] - tips[n]) for n in tips) < 0.5  # pixels
    got = fit(heads)
    assert max(np.linalg.norm(got[n] - tips[n]) for n in tips) > 5
    # placing markers runs from a limb's last bone to its tip, then on to the next bone
    assert tw.markers.next_target(arm, leaves[0], False) == (leaves[0], True)
    assert tw.markers.next_target(arm, leaves[0], True)[1] is False
    assert tw.markers.next_target(arm, sk.names[0], False) == (sk.names[1], False)

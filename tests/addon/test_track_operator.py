"""bpy.ops.twist.track and clear_track on a scene built from rendered walk footage: an armature
imported from the capture, posed on the first frame, three orthographic cameras."""

import sys
import types
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT / "bench"))

from walk_footage import JOINTS, backdrop, render, tracking_scene  # noqa: E402

from core import se3  # noqa: E402
from support.layout import Recorder, draw_panel  # noqa: E402
from support.legs import leg_errors  # noqa: E402

VIEWS = ["lateral", "endon", "oblique60"]
TRACKED = list(JOINTS)


@pytest.fixture(scope="module")
def footage(tmp_path_factory):
    folder = tmp_path_factory.mktemp("walk")
    render(folder, 560, 580, 4, VIEWS)  # six frames at 30 fps of steady walking
    return folder


@pytest.fixture(scope="module")
def long_footage(tmp_path_factory):
    folder = tmp_path_factory.mktemp("walk_long")
    render(folder, 560, 640, 4, VIEWS)  # 21 frames: a knee flexes and extends
    return folder


@pytest.fixture(scope="module")
def perspective_footage(tmp_path_factory):
    """The walk of ``footage`` filmed by perspective cameras 3.5 m from the stage, the
    lateral one panning 2 degrees a frame."""
    folder = tmp_path_factory.mktemp("walk_perspective")
    render(folder, 560, 580, 4, VIEWS, distance=3.5, pan=2.0)
    return folder


def _scene(bpy, addon, folder: Path, frames: int = 6):
    bpy.ops.wm.read_factory_settings(use_empty=True)
    return tracking_scene(bpy, folder, VIEWS, frames)


def _channel_frames(arm):
    from bpy_extras import anim_utils

    ad = arm.animation_data
    bag = anim_utils.action_get_channelbag_for_slot(ad.action, ad.action_slot)
    out = {}
    for fc in bag.fcurves:
        bone = fc.data_path.split('"')[1]
        out.setdefault(bone, set()).update(
            (int(k.co[0]), k.type) for k in fc.keyframe_points)
    return out


def test_track_keys_exactly_the_tracked_bones_and_frames(bpy_module, registered, footage):
    bpy = bpy_module
    scene, arm = _scene(bpy, registered, footage)
    arm.pose.bones["LeftCollar"].keyframe_insert("rotation_quaternion", frame=3)  # the user's
    assert bpy.ops.twist.track() == {"FINISHED"}
    keys = _channel_frames(arm)
    root = arm.data.bones[0].name
    assert set(keys) == set(TRACKED) | {root, "LeftCollar"}
    for bone in TRACKED + [root]:  # the first frame keeps the user's pose, as tracking's key
        assert keys[bone] == {(f, "GENERATED") for f in range(1, 7)}, bone
    assert keys["LeftCollar"] == {(3, "KEYFRAME")}
    # the tracked legs follow the capture
    legs = leg_errors(scene, registered.twist_addon.bridge, arm, footage, range(2, 7))
    assert np.all(legs < 8.0), legs  # measured: at most 6.5


def test_perspective_cameras_one_panning_track_through_the_operators(bpy_module, registered,
                                                                    perspective_footage):
    """Three perspective cameras as Blender's, the lateral one's pan keyed on every frame:
    Track reads each camera as it stood on each frame, keeps the panning view's silhouette
    (the camera turns about its centre, its backdrop with it), and the legs follow the
    capture as closely as through orthographic cameras."""
    bpy = bpy_module
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene, arm = tracking_scene(bpy, perspective_footage, VIEWS, 6, distance=3.5, pan=2.0)
    bridge = registered.twist_addon.bridge
    cams = [v.camera for v in scene.twist.views]
    assert all(c.data.type == "PERSP" for c in cams)
    frames = list(range(1, 7))
    path = bridge.camera_path(cams[0], scene, frames)
    assert path is not None and [bridge.camera_path(c, scene, frames) for c in cams[1:]] == [
        None, None]
    turn = np.degrees(se3.angle_between_vectors(path[0].R[2], path[-1].R[2]))
    assert turn == pytest.approx(10.0, abs=0.01) and scene.frame_current == 1
    assert bpy.ops.twist.track() == {"FINISHED"}
    assert scene.twist.result.frames_tracked == 5
    # the camera pans about its own centre: its backdrop is turned with it, nothing left out
    assert "its camera moves" not in scene.twist.result.notes
    legs = leg_errors(scene, bridge, arm, perspective_footage, range(2, 7))
    assert np.all(legs < 8.0), legs


def test_a_camera_turned_by_a_constraint_keeps_its_silhouette(bpy_module, registered,
                                                             perspective_footage):
    """The panning camera's turn given by a constraint instead of its own keys (as a Tripod
    camera solve's constraint gives it): Track reads it on every frame, finds that it only
    turns (no note), and the legs follow the capture."""
    bpy = bpy_module
    bpy.ops.wm.read_factory_settings(use_empty=True)
    scene, arm = tracking_scene(bpy, perspective_footage, VIEWS, 6, distance=3.5, pan=2.0)
    cam = scene.twist.views[0].camera
    turn = bpy.data.objects.new("turn", None)
    scene.collection.objects.link(turn)
    turn.rotation_mode = cam.rotation_mode
    for f in range(1, 7):
        scene.frame_set(f)
        turn.rotation_euler = cam.rotation_euler
        turn.keyframe_insert("rotation_euler", frame=f)
    cam.animation_data_clear()
    cam.constraints.new("COPY_ROTATION").target = turn
    scene.frame_set(1)
    bridge = registered.twist_addon.bridge
    assert bridge.camera_path(cam, scene, list(range(1, 7))) is not None
    assert bpy.ops.twist.track() == {"FINISHED"}
    assert scene.twist.result.frames_tracked == 5
    assert "its camera moves" not in scene.twist.result.notes
    legs = leg_errors(scene, bridge, arm, perspective_footage, range(2, 7))
    assert np.all(legs < 8.0), legs


def test_one_view_tracks_and_notes_the_joints_it_cannot_see_turn_in_depth(bpy_module,
                                                                          registered, footage):
    """Track's note on one line of sight reaches the scene's result, and the Results panel
    shows it; three views leave no note."""
    bpy = bpy_module
    _scene(bpy, registered, footage)
    scene = bpy.context.scene
    scene.frame_end = 3
    assert bpy.ops.twist.track() == {"FINISHED"} and scene.twist.result.notes == ""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    tracking_scene(bpy, footage, VIEWS[:1], 3)
    scene = bpy.context.scene
    assert bpy.ops.twist.track() == {"FINISHED"}
    assert scene.twist.result.frames_tracked == 2
    notes = scene.twist.result.notes.splitlines()
    named = notes[0].split(": ", 1)[1].split(" tracked as hinges")[0].split(", ")
    # the balls; the knees and elbows are hinges about axes across the body, which the side
    # view looks along
    assert len(notes) == 1 and set(named) == {j for j, kind in JOINTS.items() if kind == "ball"}
    panel = registered.twist_addon.panels.TWIST_PT_results
    lines = [k["text"] for name, _, k in draw_panel(bpy, panel) if name == "label"]
    check, begun = scene.twist.result.frames_to_check, scene.twist.result.doubts_begin
    # wrapped into the sidebar's lines, nothing lost; the frames to check first
    assert " ".join(lines) == (f"Check frames {check} Look first where doubt begins: {begun} "
                               if check else "") + notes[0]


def test_one_view_tracked_side_on_keys_turns_about_the_line_of_sight(bpy_module, registered,
                                                                       footage):
    """With Side On, one view's balls are tracked as hinges about the camera's line of
    sight: every ball's keyed turn from the first frame is about that line, a hinge's about
    its own axis, and the bones keep their own channels (quaternions, a hinge's Euler z)."""
    bpy = bpy_module
    bpy.ops.wm.read_factory_settings(use_empty=True)
    tracking_scene(bpy, footage, VIEWS[:1], 4)
    scene = bpy.context.scene
    scene.twist.tracker.side_on = True
    arm = scene.twist.armature
    bridge = registered.twist_addon.bridge
    sk = bridge.skeleton_from_armature(arm)
    R0, p0 = bridge.pose_from_armature(arm, sk)
    sight = np.array(scene.twist.views[0].camera.matrix_world.to_3x3())[:, 2]
    world0 = sk.joint_frames(R0, p0)[:, :3, :3]
    assert bpy.ops.twist.track() == {"FINISHED"}
    assert scene.twist.result.frames_tracked == 3  # frames 2-4
    assert scene.twist.result.notes.startswith("side-on: ")
    turned = 0
    for f in range(2, 5):
        scene.frame_set(f)
        R, _ = bridge.pose_from_armature(arm, sk)
        for bone in TRACKED:
            j = sk.index(bone)
            # a ball's: the line of sight in the bone's frame at frame 1
            axis = world0[j].T @ sight if JOINTS[bone] == "ball" else sk.axes[j]
            w = se3.log_so3(R0[j].T @ R[j])
            assert np.linalg.norm(np.cross(w, axis)) < 1e-4 * max(1, np.linalg.norm(w)), bone
            turned += np.linalg.norm(w) > 0.01
    assert turned > 5  # the bones did turn
    keyed = _channel_frames(arm)
    assert all(keyed[b] == {(f, "GENERATED") for f in range(1, 5)} for b in TRACKED)


def _quaternions(addon, arm, bones, frame):
    """Each bone's quaternion keyed on ``frame``, and the types of those keys."""
    bag = addon.twist_addon.keyframes.channelbag(arm)
    out = {}
    for bone in bones:
        path = f'pose.bones["{bone}"].rotation_quaternion'
        keys = [next(k for k in bag.fcurves.find(path, index=i).keyframe_points
                     if int(k.co[0]) == frame) for i in range(4)]
        out[bone] = (np.array([k.co[1] for k in keys]), {k.type for k in keys})
    return out


def test_a_keyed_correction_holds_its_frame_and_stays_the_users(bpy_module, registered,
                                                               footage, capfd):
    """Track with one iteration a level, re-pose the left hip on frame 4 and Key Correction,
    track again with three: frame 4 keeps the keyed pose (the hip as the user set it, the
    other bones as the scene showed them, not tracked again) in keys of the user's type,
    which Clear Track keeps; the frames around it are tracked anew."""
    from mathutils import Quaternion

    bpy = bpy_module
    scene, arm = _scene(bpy, registered, footage)
    scene.twist.tracker.iterations = 1
    assert bpy.ops.twist.track() == {"FINISHED"}
    first = {f: _quaternions(registered, arm, ["LeftHip", "RightHip"], f) for f in (3, 4)}
    scene.frame_set(4)
    hip = arm.pose.bones["LeftHip"]
    hip.rotation_quaternion = hip.rotation_quaternion @ Quaternion((1, 0, 0), 0.4)
    keyed = np.array(hip.rotation_quaternion)
    assert bpy.ops.twist.key_correction() == {"FINISHED"}
    scene.twist.tracker.iterations = 3
    scene.frame_set(1)
    capfd.readouterr()
    assert bpy.ops.twist.track() == {"FINISHED"}
    message = capfd.readouterr().out
    assert "tracked 5 of 5 frames; 1 frame (4) held at the pose you keyed" in message
    again = {f: _quaternions(registered, arm, ["LeftHip", "RightHip"], f) for f in (3, 4, 5)}
    assert np.allclose(again[4]["LeftHip"][0], keyed, atol=1e-6)
    assert np.allclose(again[4]["RightHip"][0], first[4]["RightHip"][0], atol=1e-6)
    assert again[4]["LeftHip"][1] == again[4]["RightHip"][1] == {"KEYFRAME"}
    assert np.abs(again[3]["RightHip"][0] - first[3]["RightHip"][0]).max() > 1e-4  # re-tracked
    assert again[3]["RightHip"][1] == again[5]["RightHip"][1] == {"GENERATED"}
    assert bpy.ops.twist.clear_track() == {"FINISHED"}
    assert _channel_frames(arm)["LeftHip"] == {(4, "KEYFRAME")}


def test_key_correction_keys_every_tracked_bone_as_the_users(bpy_module, registered):
    """On the human template (ball hips, hinge knees): every tracked channel is keyed on the
    frame as the user's, over a tracked key there too, and reads back as that frame's
    correction with every tracked bone; a bone not tracked is not keyed."""
    bpy = bpy_module
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.twist.add_template_armature(template="HUMAN")
    scene, arm = bpy.context.scene, bpy.context.scene.twist.armature
    addon = registered.twist_addon
    sk = addon.bridge.tracked_skeleton(arm)
    knee = arm.pose.bones["LeftKnee"]
    free = [k for k in range(3) if not knee.lock_rotation[k]][0]
    knee.rotation_mode = "XYZ"
    knee.keyframe_insert("rotation_euler", index=free, frame=5, keytype="GENERATED")
    scene.frame_set(5)
    knee.rotation_euler[free] = 0.7
    assert bpy.ops.twist.key_correction() == {"FINISHED"}
    bag = addon.keyframes.channelbag(arm)
    keyed = {(fc.data_path, fc.array_index): [(k.co[0], k.co[1], k.type)
                                              for k in fc.keyframe_points]
             for fc in bag.fcurves}
    tracked = {(path, i) for _, path, i in addon.keyframes.channels(arm, sk)}
    assert set(keyed) == tracked
    assert all(keys == [(5.0, keys[0][1], "KEYFRAME")] for keys in keyed.values())
    assert keyed['pose.bones["LeftKnee"].rotation_euler', free][0][1] == pytest.approx(0.7)
    tracked_bones = {name for j, (name, kind) in enumerate(zip(sk.names, sk.kinds))
                     if j == 0 or kind != "fixed"}
    assert addon.keyframes.user_keys(arm, sk) == {5: frozenset(tracked_bones)}
    # offered in pose mode's right-click menu for the tracked armature
    menu = bpy.types.VIEW3D_MT_pose_context_menu
    assert addon.track.draw_pose_menu_entry in menu.draw._draw_funcs
    layout = Recorder()
    addon.track.draw_pose_menu_entry(types.SimpleNamespace(layout=layout), bpy.context)
    assert ("operator", ("twist.key_correction",)) in [(n, a) for n, a, _ in layout.calls]


def _pose_values(arm):
    """Every pose bone's own values, as the scene holds them at the current frame."""
    return {pb.name: (pb.rotation_mode, *(tuple(round(x, 5) for x in v) for v in (
        pb.location, pb.rotation_quaternion, pb.rotation_euler, pb.scale)))
        for pb in arm.pose.bones}


def _all_keys(addon, arm):
    bag = addon.twist_addon.keyframes.channelbag(arm)
    return {(fc.data_path, fc.array_index): np.array([k.co for k in fc.keyframe_points])
            for fc in bag.fcurves}


def test_track_twice_and_clear_never_move_the_users_pose(bpy_module, registered, footage):
    """The user's pose on the first frame stays as set after Track; a second Track from that
    frame writes the same keys as the first; Clear Track leaves the bones as before Track."""
    bpy = bpy_module
    scene, arm = _scene(bpy, registered, footage)
    before = _pose_values(arm)
    assert bpy.ops.twist.track() == {"FINISHED"}
    scene.frame_set(1)
    bridge = registered.twist_addon.bridge
    sk = bridge.tracked_skeleton(arm)
    arm_before = bridge.pose_from_armature  # the start pose, read as Track reads it
    first_keys = _all_keys(registered, arm)
    R1, p1 = arm_before(arm, sk)
    assert bpy.ops.twist.track() == {"FINISHED"}
    scene.frame_set(1)
    R2, p2 = arm_before(arm, sk)
    np.testing.assert_array_equal(R2, R1)  # the very same start
    np.testing.assert_array_equal(p2, p1)
    again = _all_keys(registered, arm)
    assert again.keys() == first_keys.keys()
    for k in again:
        np.testing.assert_array_equal(again[k], first_keys[k], err_msg=str(k))
    scene.frame_set(4)
    assert bpy.ops.twist.clear_track() == {"FINISHED"}
    assert arm.animation_data.action is None or not len(
        registered.twist_addon.keyframes.channelbag(arm).fcurves)
    for f in (1, 4):
        scene.frame_set(f)
        assert _pose_values(arm) == before, f


def test_clear_removes_only_what_tracking_wrote(bpy_module, registered, footage):
    bpy = bpy_module
    scene, arm = _scene(bpy, registered, footage)
    arm.pose.bones["LeftHip"].keyframe_insert("rotation_quaternion", frame=1)  # the user's
    arm.pose.bones["LeftCollar"].keyframe_insert("rotation_quaternion", frame=4)
    scene.frame_end = 3
    assert bpy.ops.twist.track() == {"FINISHED"}
    assert ("LeftHip" in _channel_frames(arm))
    assert bpy.ops.twist.clear_track() == {"FINISHED"}
    keys = _channel_frames(arm)
    assert keys == {"LeftHip": {(1, "KEYFRAME")}, "LeftCollar": {(4, "KEYFRAME")}}


@pytest.mark.parametrize("breakage, message", [
    (lambda s, a: setattr(s.twist.views[0].camera.data, "type", "PANO"),
     "'lateral' is panoramic"),
    (lambda s, a: (setattr(s.twist.views[0].camera.data, "type", "PERSP"),
                   setattr(s.twist, "mode", "INDEPENDENT")),
     "perspective cameras are placed where they filmed from: set Views to Calibrated"),
    (lambda s, a: setattr(s.twist.views[1], "images", ""), "the view of 'endon' has no footage"),
    (lambda s, a: setattr(s, "frame_end", 9), "no image for frame 7"),
    (lambda s, a: [setattr(pb, "lock_rotation", (True,) * 3) for pb in a.pose.bones],
     "no bone of .* is free to turn"),
])
def test_bad_scenes_are_refused_and_nothing_changes(bpy_module, registered, footage, breakage,
                                                    message, capsys):
    bpy = bpy_module
    scene, arm = _scene(bpy, registered, footage)
    breakage(scene, arm)
    with pytest.raises(RuntimeError, match=message):
        bpy.ops.twist.track()
    assert arm.animation_data is None or arm.animation_data.action is None


def test_refine_skeleton_brings_a_misplaced_knee_back_and_tracks_again(bpy_module, registered,
                                                                        long_footage):
    """The left knee, a hinge about the capture's axis as the scene rigs it, its head moved
    4 cm across that axis and its bone (a move along the axis changes no motion; its
    parent's tail stays): two rounds of Refine Skeleton on the selected knee bring it back
    most of the way (measured 2.1 cm; a third round 2.0), the other bones keep their heads,
    and every frame is keyed again."""
    bpy = bpy_module
    from mathutils import Vector

    scene, arm = _scene(bpy, registered, long_footage, 21)
    truth = {b.name: np.array(b.head_local) for b in arm.data.bones}
    bpy.context.view_layer.objects.active = arm
    sk = registered.twist_addon.bridge.skeleton_from_armature(arm)
    bpy.ops.object.mode_set(mode="EDIT")
    knee = arm.data.edit_bones["LeftKnee"]
    knee.use_connect = False
    W = np.array(arm.matrix_world.to_3x3())
    across = np.cross(sk.axes[sk.index("LeftKnee")], W @ np.array(knee.tail - knee.head))
    knee.head = knee.head + Vector(np.linalg.inv(W) @ (0.04 * across / np.linalg.norm(across)))
    bpy.ops.object.mode_set(mode="OBJECT")
    for b in arm.pose.bones:
        b.select = b.name == "LeftKnee"
    before = np.linalg.norm(np.array(arm.data.bones["LeftKnee"].head_local) - truth["LeftKnee"])
    assert bpy.ops.twist.refine_skeleton(rounds=2) == {"FINISHED"}
    after = np.linalg.norm(np.array(arm.data.bones["LeftKnee"].head_local) - truth["LeftKnee"])
    assert after < 0.6 * before, (before, after)
    for name in ("Hips", "LeftHip", "RightKnee", "LeftAnkle"):
        np.testing.assert_allclose(arm.data.bones[name].head_local, truth[name], atol=1e-6)
    keyed = _channel_frames(arm)
    assert all(set(range(2, 22)) <= {f for f, _ in keyed[b]} for b in TRACKED)
    for b in arm.pose.bones:
        b.select = False
    with pytest.raises(RuntimeError, match="no tracked bone is selected to refine"):
        bpy.ops.twist.refine_skeleton()


def test_a_refine_round_that_fails_keeps_the_rounds_before_it(bpy_module, registered,
                                                              long_footage, monkeypatch):
    """A later round whose tracking diverges (staged here: the footage's own rounds settle)
    leaves the armature as the rounds before it made it, keyed again; a first round that
    fails changes nothing."""
    bpy = bpy_module
    module = sys.modules[registered.twist_addon.__name__ + ".refine"]
    real, calls, fail_at = module.refine, [], 1

    def round_fails(*args, **kwargs):
        calls.append(1)
        if len(calls) == fail_at:
            raise module.RefineError("tracking diverged at frame 9 of the range")
        return real(*args, **kwargs)

    monkeypatch.setattr(module, "refine", round_fails)
    scene, arm = _scene(bpy, registered, long_footage, 21)
    for b in arm.pose.bones:
        b.select = b.name in ("LeftKnee", "RightHip")
    head = {b.name: np.array(b.head_local) for b in arm.data.bones}
    with pytest.raises(RuntimeError, match="tracking diverged at frame 9"):
        bpy.ops.twist.refine_skeleton(rounds=3)
    assert all(np.array_equal(b.head_local, head[b.name]) for b in arm.data.bones)
    assert arm.animation_data is None or arm.animation_data.action is None

    calls.clear()
    fail_at = 2
    assert bpy.ops.twist.refine_skeleton(rounds=3) == {"FINISHED"}
    assert len(calls) == 2  # the third round was not tried
    moved = [n for n in ("LeftKnee", "RightHip")
             if not np.allclose(arm.data.bones[n].head_local, head[n], atol=1e-6)]
    assert moved  # round 1's refinement is in the rest pose
    np.testing.assert_allclose(arm.data.bones["LeftAnkle"].head_local, head["LeftAnkle"],
                               atol=1e-6)
    keyed = _channel_frames(arm)
    assert all(set(range(2, 22)) <= {f for f, _ in keyed[b]} for b in TRACKED)


def test_clean_plates_are_read_as_the_views_backdrops(bpy_module, registered, footage,
                                                      tmp_path):
    """Each view given the stage without the body (the renderer's backdrop): Track reads
    them as the silhouette's backdrops and the legs follow the capture; a plate that is not
    there is named before anything is keyed."""
    import cv2

    bpy = bpy_module
    scene, arm = _scene(bpy, registered, footage)
    plate = tmp_path / "stage.png"
    cv2.imwrite(str(plate), backdrop().astype(np.uint8))
    for view in scene.twist.views:
        view.backdrop = str(plate)
    session = registered.twist_addon.track.TrackSession.from_scene(scene)
    assert session.tracker.clean_plates == [str(plate)] * len(VIEWS)
    assert bpy.ops.twist.track() == {"FINISHED"}
    legs = leg_errors(scene, registered.twist_addon.bridge, arm, footage, range(2, 7))
    assert np.all(legs < 8.0), legs
    bpy.ops.twist.clear_track()
    scene.frame_set(1)
    scene.twist.views[1].backdrop = str(tmp_path / "nowhere.png")
    with pytest.raises(RuntimeError, match="nowhere.png: the clean plate of the view of "
                                           f"'{scene.twist.views[1].camera.name}' is not found"):
        bpy.ops.twist.track()
    assert not any(_channel_frames(arm).values())  # nothing keyed

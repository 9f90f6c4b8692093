"""Export round trips: the tracked armature's motion written by twist.export_bvh / export_fbx,
read back by Blender's importers and by a reader that shares no code with the exporter."""

import re

import numpy as np
import pytest

from core import se3
from core.bvh import read_bvh, write_bvh
from core.skeleton import skeleton_from_bvh

FRAMES = 8


@pytest.fixture
def animated(bpy_module, registered, cmu_walk, tmp_path):
    """The CMU walk imported as an animated armature (frames 1..FRAMES), set to export; with
    its bones' parents and, per frame, the world direction of every bone."""
    bpy = bpy_module
    b = read_bvh(cmu_walk)
    b.motion = b.motion[600:600 + FRAMES]
    write_bvh(b, tmp_path / "walk.bvh")
    bpy.ops.import_anim.bvh(filepath=str(tmp_path / "walk.bvh"), axis_forward="Y",
                            axis_up="Z", frame_start=1)
    arm = bpy.context.view_layer.objects.active
    scene = bpy.context.scene
    scene.frame_start, scene.frame_end = 1, FRAMES
    scene.twist.armature = arm
    parents = {b.name: b.parent.name if b.parent else None for b in arm.data.bones}
    source = [_bone_directions(_blender_heads(bpy, scene, arm, f), parents)
              for f in range(1, FRAMES + 1)]
    return bpy, scene, arm, parents, source


def _bone_directions(heads: dict, parents: dict) -> dict:
    return {n: heads[n] - heads[p] for n, p in parents.items()
            if p and np.linalg.norm(heads[n] - heads[p]) > 1e-4}


def _blender_heads(bpy, scene, arm, frame):
    scene.frame_set(frame)
    W = np.array(arm.matrix_world)
    return {pb.name: (W @ np.append(np.array(pb.head), 1))[:3] for pb in arm.pose.bones}


def _max_angle(a: dict, b: dict) -> float:
    keys = sorted(a)
    return float(np.degrees(se3.angle_between_vectors(np.array([a[k] for k in keys]),
                                                      np.array([b[k] for k in keys]))).max())


def test_bvh_round_trip_through_blender_and_an_independent_reader(animated, tmp_path):
    bpy, scene, arm, parents, source = animated
    out = tmp_path / "out.bvh"
    assert bpy.ops.twist.export_bvh(filepath=str(out)) == {"FINISHED"}
    # the project's own reader (no code shared with Blender's exporter)
    got = read_bvh(out)
    assert len(got.motion) == FRAMES
    sk = skeleton_from_bvh(got)
    R, p = got.poses()
    for f in range(FRAMES):
        X = sk.world_positions(R[f], p[f])
        heads = dict(zip(sk.names, X))
        dirs = _bone_directions(heads, {n: sk.names[sk.parents[j]] if j else None
                                        for j, n in enumerate(sk.names)})
        common = {k: dirs[k] for k in source[f] if k in dirs}
        assert len(common) >= 20
        assert _max_angle(common, {k: source[f][k] for k in common}) < 0.01
    # Blender's own importer
    bpy.ops.import_anim.bvh(filepath=str(out), axis_forward="Y", axis_up="Z", frame_start=1)
    back = bpy.context.view_layer.objects.active
    assert back != arm
    for f in range(1, FRAMES + 1):
        dirs = _bone_directions(_blender_heads(bpy, scene, back, f), parents)
        assert _max_angle(dirs, {k: source[f - 1][k] for k in dirs}) < 0.01


UFBX_READER = """
import json, sys, ufbx
scene = ufbx.load_file(sys.argv[1])
stack = scene.anim_stacks[0]
names = sys.argv[2].split(",")
fps = float(sys.argv[3])
frames, alive = [], []  # ufbx 0.0.5 frees a scene's nodes under live references: keep all
for f in range(int(sys.argv[4])):
    ev = ufbx.evaluate_scene(scene, stack.anim, stack.time_begin + f / fps)
    alive.append(ev)
    pos = {}
    for i in range(len(ev.nodes)):
        n = ev.nodes[i]
        if n.name in names:
            c3 = list(n.node_to_world)[3]  # (reading matrix fields directly crashes ufbx 0.0.5)
            pos[n.name] = [c3.x, c3.y, c3.z]
    frames.append(pos)
print(json.dumps({"fps": scene.settings.frames_per_second,
                  "span": stack.time_end - stack.time_begin, "frames": frames}))
"""


def _kabsch(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The rotation taking directions a (N, 3) onto b (N, 3) best (least squares)."""
    u, _, vt = np.linalg.svd(a.T @ b)
    d = np.sign(np.linalg.det(vt.T @ u.T))
    return vt.T @ np.diag([1, 1, d]) @ u.T


def test_fbx_round_trip_through_blender_and_ufbx(animated, tmp_path):
    import json
    import subprocess
    import sys

    bpy, scene, arm, parents, source = animated
    out = tmp_path / "out.fbx"
    assert bpy.ops.twist.export_fbx(filepath=str(out)) == {"FINISHED"}
    # an independent reader, in its own process (it can crash its interpreter)
    proc = subprocess.run([sys.executable, "-c", UFBX_READER, str(out), ",".join(parents),
                           str(scene.render.fps), str(FRAMES)], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr[-2000:]
    read = json.loads(proc.stdout)
    assert read["fps"] == pytest.approx(scene.render.fps)
    assert read["span"] == pytest.approx((FRAMES - 1) / scene.render.fps, abs=1e-3)
    got = [_bone_directions({k: np.array(v) for k, v in fr.items()}, parents)
           for fr in read["frames"]]
    keys = sorted(set(got[0]) & set(source[0]))
    assert len(keys) >= 20
    # FBX is y up in centimetres: one fixed rotation (found on the first frame) maps its axes
    rot = _kabsch(np.array([got[0][k] for k in keys]), np.array([source[0][k] for k in keys]))
    for f in range(FRAMES):
        mapped = {k: rot @ got[f][k] for k in keys}
        assert _max_angle(mapped, {k: source[f][k] for k in keys}) < 0.1, f
    # Blender's own importer: it adds anim_offset to the file's frames (measured with 5.0.1:
    # frame 1 comes back on frame 1 + anim_offset), so no offset gives the source frames
    bpy.ops.import_scene.fbx(filepath=str(out), anim_offset=0)
    back = next(o for o in bpy.context.selected_objects if o.type == "ARMATURE")
    assert back != arm
    for f in range(1, FRAMES + 1):
        dirs = _bone_directions(_blender_heads(bpy, scene, back, f), parents)
        common = sorted(set(dirs) & set(source[f - 1]))
        assert len(common) >= 20
        assert _max_angle({k: dirs[k] for k in common},
                          {k: source[f - 1][k] for k in common}) < 0.1, f


def test_export_one_cycle_of_a_chosen_armature(bpy_module, registered, tmp_path):
    bpy = bpy_module
    from support.walking import walking_template

    scene, arm = walking_template(bpy, registered, frames=60)
    assert bpy.ops.twist.make_cycle() == {"FINISHED"}
    bag = registered.twist_addon.keyframes.channelbag(arm)
    keys = sorted({int(k.co[0]) for fc in bag.fcurves for k in fc.keyframe_points})
    bpy.ops.twist.add_template_armature(template="WALKER")  # now the scene's tracked armature
    out = tmp_path / "cycle.bvh"
    assert bpy.ops.twist.export_bvh(filepath=str(out), armature=arm.name,
                                    only_cycle=True) == {"FINISHED"}
    got = read_bvh(out)
    assert len(got.motion) == len(keys) - 1  # one period; its closing key is the next start
    assert "LeftKnee" in got.names and "LeftAnkle" not in got.names  # the human, not the walker
    assert (scene.frame_start, scene.frame_end) == (1, 60)  # the scene's range is untouched
    with pytest.raises(RuntimeError, match="'Walker' has no animation to export"):
        bpy.ops.twist.export_bvh(filepath=str(out), only_cycle=True)


def test_export_acts_on_the_active_armature_else_the_tracked_one(bpy_module, registered,
                                                                 tmp_path):
    """As Blender's exporters do: the selected (active) armature is what File > Export writes;
    with no armature active, the scene's tracked one."""
    bpy = bpy_module
    from support.walking import walking_template

    scene, human = walking_template(bpy, registered, frames=5)
    bpy.ops.twist.add_template_armature(template="WALKER")
    walker = scene.twist.armature
    scene.twist.armature = human  # the human is tracked, the walker active
    assert bpy.context.view_layer.objects.active == walker
    out = tmp_path / "active.bvh"
    assert bpy.ops.twist.export_bvh(filepath=str(out)) == {"FINISHED"}
    assert "LeftAnkle" in read_bvh(out).names  # the walker's
    bpy.context.view_layer.objects.active = None
    assert bpy.ops.twist.export_bvh(filepath=str(out)) == {"FINISHED"}
    assert "LeftAnkle" not in read_bvh(out).names and "LeftKnee" in read_bvh(out).names
    human.select_set(True)
    bpy.context.view_layer.objects.active = human
    assert bpy.ops.twist.export_bvh(filepath=str(out), armature=walker.name) == {"FINISHED"}
    assert bpy.context.view_layer.objects.active == human  # the selection is left as it was
    assert human.select_get() and not walker.select_get()


@pytest.mark.parametrize("op", ["export_bvh", "export_fbx"])
def test_an_export_with_nowhere_to_go_says_so_and_changes_nothing(animated, tmp_path, op):
    bpy, scene, arm, _, _ = animated
    ext = op[-3:]
    selected = [o.name for o in bpy.context.view_layer.objects if o.select_get()]
    for path, says in [("", f"no file to export to: give a file path ending in .{ext}"),
                       (str(tmp_path / "no" / f"walk.{ext}"),
                        f"the folder {tmp_path / 'no'} does not exist")]:
        with pytest.raises(RuntimeError, match=re.escape(says)):
            getattr(bpy.ops.twist, op)(filepath=path)
    assert [o.name for o in bpy.context.view_layer.objects if o.select_get()] == selected
    assert not (tmp_path / "no").exists()

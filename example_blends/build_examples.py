"""Build the example scenes in this folder (run from the repository with its virtual
environment): ``python example_blends/build_examples.py``.

walk_3view.blend: three orthographic views of the CMU walk, rendered by bench/walk_footage.py
(one second of steady walking at 15 frames per second, JPEG frames in walk_3view/), the
capture's armature posed on frame 1 with its lower back free as well as the paper's 19
degrees of freedom (bench/walk_footage.py's SPINE_JOINTS), ready for Track. The capture's
frames that were rendered are kept as walk_3view/truth.bvh.

muybridge_woman.blend: Muybridge's woman jumping behind one orthographic camera, with the
19-degree-of-freedom human placed over her on the first frame; her skirt hides her legs, so
she is left for the user (its text 'About this example' says why).

muybridge_baboon.blend, muybridge_camel.blend, muybridge_mule.blend: a printed plate of
muybridge_plates/ cut into its cells by Add View from Plate (the frames in
muybridge_plates/plate_NAME_frames/); muybridge_horse.blend: "Sallie Gardner at a Gallop",
its frames already cut (muybridge_horse/). Each with the planar quadruped of bench/plates.py
standing on the joints clicked on its first frame (bench/data/plates/NAME.json; the clicks
are the view's markers there, so Fit Pose to Markers gives the pose back), a centimetre per
pixel; tracked from there through the real Track operator and the view's still camera
(Muybridge's cameras stood in a row beside the track: the animal is as large in every cell),
with a volumetric body riding on it. The horse's, the baboon's and the camel's strides are
also made into a cycle, an action of its own in the file, exported as
exports/NAME_cycle.bvh and .fbx; the mule bucks, which is no gait. Each scene's text 'About
this example' says what it holds.

Paths are relative to each .blend, so the folder can move.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

import cv2
import numpy as np

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "bench"))
sys.path.insert(0, str(ROOT / "scripts"))

from addon_dev import load_addon  # noqa: E402
from plates import DATA as PLATE_CLICKS  # noqa: E402
from plates import cut_frames, planar_body  # noqa: E402
from walk_footage import SPINE_JOINTS, render, tracking_scene  # noqa: E402

WALK = dict(first=540, last=660, step=8)  # capture frames: one second at 15 fps
VIEWS = ["lateral", "endon", "oblique60"]
PLATE_UNIT = 0.01  # metres per pixel of a plate's frames: the animals about a metre long
EXPORTS = HERE / "exports"  # the plate examples' cycles as BVH and FBX


def build_walk(bpy) -> Path:
    out = HERE / "walk_3view"
    with tempfile.TemporaryDirectory() as tmp:
        info = render(Path(tmp), WALK["first"], WALK["last"], WALK["step"], VIEWS)
        if out.exists():
            shutil.rmtree(out)
        for v in VIEWS:
            (out / v).mkdir(parents=True)
            for i, f in enumerate(info["frames"]):
                img = cv2.imread(str(Path(tmp) / v / f"{f:04d}.png"))
                cv2.imwrite(str(out / v / f"{i + 1:04d}.jpg"), img,
                            [cv2.IMWRITE_JPEG_QUALITY, 92])
        shutil.copy(Path(tmp) / "truth.bvh", out / "truth.bvh")
    bpy.ops.wm.read_factory_settings(use_empty=True)
    path = HERE / "walk_3view.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))  # so that // paths mean this folder
    scene, arm = tracking_scene(bpy, out, VIEWS, len(info["frames"]), "*.jpg", SPINE_JOINTS)
    for view in scene.twist.views:
        view.images = bpy.path.relpath(view.images)
    scene.render.fps = 15
    scene.camera = scene.twist.views[0].camera
    bpy.ops.wm.save_as_mainfile(filepath=str(path), relative_remap=True)
    return path


def build_woman(bpy) -> Path:
    """The woman jumping behind one orthographic camera, with the 19-degree-of-freedom human
    placed over her on the first frame (hips near (85, 193), feet on the frames' bottom, 160
    pixels per metre down the frames, padded to 202 x 376; turned to face the image's
    right), its limbs left for the user, and a text saying why it is not tracked here."""
    out = HERE / "muybridge_woman"
    files = sorted(out.glob("*.png"))
    bpy.ops.wm.read_factory_settings(use_empty=True)
    path = HERE / "muybridge_woman.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    bpy.ops.twist.add_view(filepath=str(files[0]), first_frame=1)
    scene = bpy.context.scene
    cam = scene.twist.views[0].camera
    cam.data.ortho_scale = 376 / 160
    cam.location = (0.097125, -10.0, 0.984375)
    bpy.ops.twist.add_template_armature(template="HUMAN")
    scene.twist.armature.rotation_euler[2] = np.radians(90)
    scene.twist.mode = "INDEPENDENT"
    scene.twist.tracker.side_on = True  # one view of a body seen from the side
    scene.frame_start, scene.frame_end = 1, len(files)
    scene.render.fps = 15
    scene.camera = cam
    bpy.data.texts.new("About this example").write(ABOUT_WOMAN)
    scene.frame_set(1)
    bpy.ops.wm.save_as_mainfile(filepath=str(path), relative_remap=True)
    return path


ABOUT_WOMAN = """Muybridge's woman jumping (example_blends/muybridge_woman/), added with Add
View, and the human template placed over her on the first frame, not posed and not tracked
here: her long skirt hides the hips, thighs and knees on every frame, and the digitised
frames have the figure cut out onto black, so there is neither a leg to click nor a
backdrop to hold a silhouette against. Pose the arms, head and trunk over the first frame
(Place Markers, Fit Pose to Markers) to try; Track flags the frames it is unsure of.
"""


def pose_on_plate(scene, twist_addon, spec: dict, name: str):
    """Over a scene whose one view is a plate's frames (``Add View from Plate``), the planar
    quadruped of ``spec`` (``bench/plates.py``) standing on the joints clicked on its first
    frame, the clicks as the view's markers there, the camera at ``PLATE_UNIT`` metres per
    pixel; returns the armature."""
    view = scene.twist.views[0]
    W, H = scene.render.resolution_x, scene.render.resolution_y
    cam = view.camera  # looking along +y, x right, z up: pixel (x, y) at (x, -y) / unit
    cam.data.ortho_scale = W * PLATE_UNIT
    cam.location = ((W - 1) / 2 * PLATE_UNIT, -10.0, -(H - 1) / 2 * PLATE_UNIT)
    sk, _ = planar_body(spec, PLATE_UNIT)
    arm = twist_addon.bridge.armature_from_skeleton(sk, name.title(), scene.collection)
    scene.twist.armature = arm
    scene.twist.mode = "CALIBRATED"  # the animal as large in every cell: no scale to drift
    scene.twist.tracker.side_on = True
    for bone, xy in spec["clicks"].items():
        twist_addon.markers.set_marker(view, bone, 1, *xy)
    return arm


def build_plate(bpy, twist_addon, name: str, gait: bool) -> Path:
    """A printed plate cut into a view (or frames already cut, added as they are), with the
    planar quadruped clicked on its first frame (see the module's docstring), tracked through
    the real operators from that pose, a volumetric body riding on it; for a ``gait``, the
    track made into a cycle kept as its own action and exported as BVH and FBX into
    ``EXPORTS``."""
    import json

    spec = json.loads((PLATE_CLICKS / f"{name}.json").read_text())
    bpy.ops.wm.read_factory_settings(use_empty=True)
    path = HERE / f"muybridge_{name}.blend"
    bpy.ops.wm.save_as_mainfile(filepath=str(path))
    if "plate" in spec:
        bpy.ops.twist.add_plate_view(filepath=str(ROOT / spec["plate"]), first_frame=1)
    else:  # frames already cut
        bpy.ops.twist.add_view(filepath=str(cut_frames(spec)[0]), first_frame=1)
    scene = bpy.context.scene
    arm = pose_on_plate(scene, twist_addon, spec, name)
    scene.render.fps = 15
    cam = scene.twist.views[0].camera
    scene.camera = cam
    scene.frame_set(1)
    assert bpy.ops.twist.track() == {"FINISHED"}, name
    assert bpy.ops.twist.add_volumetric_body() == {"FINISHED"}, name
    about = ((ABOUT_PLATE if "plate" in spec else ABOUT_FRAMES) + ABOUT_TRACKED).format(
        name=name, source=spec.get("plate", spec.get("frames")), frames=scene.frame_end,
        tracked=scene.twist.result.frames_tracked + 1)
    if gait:
        about += ABOUT_CYCLE.format(name=name)
        make_cycle(bpy, scene, arm, EXPORTS / f"{name}_cycle")
    else:
        about += ABOUT_NO_CYCLE
    bpy.data.texts.new("About this example").write(about)
    scene.frame_set(1)
    bpy.ops.wm.save_as_mainfile(filepath=str(path), relative_remap=True)
    return path


ABOUT_PLATE = """Muybridge's plate of the {name} ({source}), cut into its {frames} cells by
Add View from Plate."""
ABOUT_FRAMES = """Muybridge's {name} ({source}/, {frames} frames as digitised), added with Add
View; the rider is not modelled."""
ABOUT_TRACKED = """ The quadruped stands on the joints clicked by hand on the first frame
(the view's markers there; Fit Pose to Markers gives the pose back). Track ran from frame
1, side-on (one view), and kept frames 1-{tracked}; the Results panel lists the frames whose
limbs it is unsure of. The volumetric body (collection Twist body) rides on the armature. To
track again: Clear Track, go to frame 1, Track.
"""
ABOUT_CYCLE = """
The frames hold about one stride: Make Walk Cycle (the frame range as one cycle) made the
track into the action '{name} cycle', kept in this file (pick it in the Action editor to
watch it loop), exported as exports/{name}_cycle.bvh and .fbx.
"""
ABOUT_NO_CYCLE = """
A buck is not a gait, so no cycle is made of it. Its legs turn further from cell to cell
than the tracker can follow: the frames it doubts are listed in the Results panel and marked
on the timeline, and a run stops where the body is lost.
"""


def make_cycle(bpy, scene, arm, stem: Path) -> None:
    """Make the armature's track, over the scene's range taken as one cycle, into a looping
    action of its own (named '<armature> cycle', kept in the file) and export that cycle
    as ``stem``.bvh and .fbx; the armature keeps its tracked action."""
    tracked = arm.animation_data.action
    cycle = tracked.copy()
    cycle.name = f"{arm.name.lower()} cycle"
    cycle.use_fake_user = True
    slot = arm.animation_data.action_slot.identifier
    arm.animation_data.action = cycle
    arm.animation_data.action_slot = cycle.slots[slot]
    assert bpy.ops.twist.make_cycle(range_is_cycle=True) == {"FINISHED"}
    stem.parent.mkdir(exist_ok=True)
    for ext, op in ((".bvh", bpy.ops.twist.export_bvh), (".fbx", bpy.ops.twist.export_fbx)):
        assert op(filepath=str(stem.with_suffix(ext)), only_cycle=True) == {"FINISHED"}
    arm.animation_data.action = tracked
    arm.animation_data.action_slot = tracked.slots[slot]


def main() -> int:
    import bpy

    addon = load_addon()
    addon.register()  # its classes outlive the factory resets below
    print(build_walk(bpy))
    print(build_woman(bpy))
    for name, gait in (("horse", True), ("baboon", True), ("camel", True), ("mule", False)):
        print(build_plate(bpy, addon.twist_addon, name, gait))
    return 0


if __name__ == "__main__":
    sys.exit(main())

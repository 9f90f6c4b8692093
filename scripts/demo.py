"""The demo: the bundled example tracked through the add-on's operators, headless.

    python scripts/demo.py [--out .cache/demo]

Opens example_blends/walk_3view.blend, runs Track, saves the tracked .blend, exports the
motion as BVH and FBX with Blender's exporters, draws the tracked blobs over the footage into
a contact sheet, and prints where each file went and how far the tracked limbs are from the
motion capture the footage was rendered from. Then the same for a Muybridge plate,
example_blends/muybridge_camel.blend, scored by how well each frame's tracked outline
covers the camel.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import cv2
import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path[:0] = [str(ROOT), str(ROOT / "bench"), str(ROOT / "scripts")]

import evaluate  # noqa: E402
from addon_dev import load_addon  # noqa: E402

from core import raycast  # noqa: E402
from core.bvh import read_bvh  # noqa: E402
from core.image import load_grey  # noqa: E402
from core.pose import BodyPose  # noqa: E402
from core.skeleton import skeleton_from_bvh  # noqa: E402

EXAMPLE = ROOT / "example_blends" / "walk_3view.blend"
PLATE_EXAMPLE = ROOT / "example_blends" / "muybridge_camel.blend"


def contact_sheet(twist_addon, scene, path: Path, frames: list[int]) -> None:
    """Rows of frames, one column per view: the footage with the tracked blobs' outlines."""
    bridge, tw = twist_addon.bridge, scene.twist
    rows = []
    for f in frames:
        scene.frame_set(f)
        sk = bridge.skeleton_from_armature(tw.armature)
        R, root = bridge.pose_from_armature(tw.armature, sk)
        g = sk.segment_motions(sk.joint_frames(R, root))
        row = []
        for v in tw.views:
            img = cv2.imread(str(twist_addon.views.footage_frames(v, [f])[0]))
            view = bridge.view_from_camera(v.camera, scene)
            pix, hits, _ = raycast.render_labels(view, sk.blobs, g, img.shape[:2])
            lab = np.full(img.shape[:2], -1)
            lab[pix[:, 1].astype(int), pix[:, 0].astype(int)] = hits.label
            edge = cv2.morphologyEx((lab + 1).astype(np.uint8), cv2.MORPH_GRADIENT,
                                    np.ones((3, 3), np.uint8)) > 0
            img[edge] = (60, 230, 80)
            cv2.putText(img, f"frame {f}", (8, 20), cv2.FONT_HERSHEY_SIMPLEX, 0.5,
                        (255, 255, 255), 1)
            row.append(img)
        rows.append(np.hstack(row))
    cv2.imwrite(str(path), np.vstack(rows))


def export(bpy, scene, paths: dict) -> None:
    """The tracked .blend, and the armature's motion as BVH and FBX, to ``paths``."""
    bpy.ops.wm.save_as_mainfile(filepath=str(paths["tracked .blend"]), copy=True)
    arm = scene.twist.armature
    bpy.ops.object.select_all(action="DESELECT")
    arm.select_set(True)
    bpy.context.view_layer.objects.active = arm
    bpy.ops.export_anim.bvh(filepath=str(paths["BVH"]), frame_start=scene.frame_start,
                            frame_end=scene.frame_end)
    bpy.ops.export_scene.fbx(filepath=str(paths["FBX"]), use_selection=True,
                             object_types={"ARMATURE"}, add_leaf_bones=False, bake_anim=True,
                             bake_anim_simplify_factor=0.0)


def open_and_track(bpy, path: Path):
    """Open an example scene and Track it from its first frame; the scene, or None when
    Track did not go through."""
    bpy.ops.wm.open_mainfile(filepath=str(path))
    scene = bpy.context.scene
    scene.frame_set(scene.frame_start)
    print(f"\ntracking {path.name}: {len(scene.twist.views)} view(s), frames "
          f"{scene.frame_start}-{scene.frame_end}", flush=True)
    return scene if bpy.ops.twist.track() == {"FINISHED"} else None


def plate_demo(bpy, twist_addon, out: Path) -> int:
    """The camel's plate tracked, exported and drawn; prints each frame's overlap of the
    tracked outline with the camel."""
    import plates

    scene = open_and_track(bpy, PLATE_EXAMPLE)
    if scene is None:
        return 1
    stem = PLATE_EXAMPLE.stem
    paths = {"tracked .blend": out / f"{stem}_tracked.blend", "BVH": out / f"{stem}.bvh",
             "FBX": out / f"{stem}.fbx", "contact sheet": out / f"{stem}_contact_sheet.png"}
    export(bpy, scene, paths)
    n = scene.frame_end - scene.frame_start + 1
    contact_sheet(twist_addon, scene, paths["contact sheet"],
                  [scene.frame_start + i * (n - 1) // 3 for i in range(4)])
    bridge, view_pg = twist_addon.bridge, scene.twist.views[0]
    view = bridge.view_from_camera(view_pg.camera, scene)
    arm = scene.twist.armature
    sk = bridge.skeleton_from_armature(arm)
    frames = range(scene.frame_start, scene.frame_start + scene.twist.result.frames_tracked + 1)
    overlaps = []
    for f, image in zip(frames, twist_addon.views.footage_frames(view_pg, list(frames))):
        scene.frame_set(f)
        R, root = bridge.pose_from_armature(arm, sk)
        sil = plates.silhouette(load_grey(image))
        pose = BodyPose(R, root, [view])
        overlaps.append(plates.overlap(sk, pose, sil))
    for label, p in paths.items():
        print(f"{label:14s} {p}")
    print(f"overlap of the tracked outline with the camel, frame by frame: "
          f"{', '.join(f'{o:.2f}' for o in overlaps)} (the first frame is the clicked pose)")
    return 0


def main(argv=None) -> int:
    import bpy

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--out", type=Path, default=ROOT / ".cache" / "demo")
    a = ap.parse_args(argv)
    a.out.mkdir(parents=True, exist_ok=True)
    addon = load_addon()
    addon.register()
    twist_addon = addon.twist_addon
    bridge = twist_addon.bridge
    scene = open_and_track(bpy, EXAMPLE)
    if scene is None:
        return 1
    result = scene.twist.result
    paths = {
        "tracked .blend": a.out / "walk_3view_tracked.blend",
        "BVH": a.out / "walk_3view.bvh",
        "FBX": a.out / "walk_3view.fbx",
        "contact sheet": a.out / "walk_3view_contact_sheet.png",
    }
    export(bpy, scene, paths)
    arm = scene.twist.armature
    n = scene.frame_end - scene.frame_start + 1
    contact_sheet(twist_addon, scene, paths["contact sheet"],
                  [scene.frame_start + i * (n - 1) // 3 for i in range(4)])

    truth_bvh = read_bvh(ROOT / "example_blends" / "walk_3view" / "truth.bvh")
    truth = truth_bvh.poses()
    sk = skeleton_from_bvh(truth_bvh)
    est_R, est_p = [], []
    tracked = bridge.skeleton_from_armature(arm)
    for f in range(scene.frame_start, scene.frame_end + 1):
        scene.frame_set(f)
        R, root = bridge.pose_from_armature(arm, tracked)
        est_R.append(R)
        est_p.append(root)
    names = tracked.tracked_joint_names()
    got = evaluate.score(sk, names, (np.array(est_R), np.array(est_p)), truth)
    still = evaluate.score(sk, names, evaluate.held_still(truth), truth)
    print(f"\ntracked {result.frames_tracked} frames; last residual {result.last_residual:.4f}"
          + (f"; stopped at {result.diverged_frames}" if result.diverged_frames else ""))
    for label, p in paths.items():
        print(f"{label:14s} {p}")
    legs = ["left thigh", "right thigh", "left shank", "right shank"]
    print(f"limb-direction error against the capture: legs "
          f"{np.mean([got.limb_deg[k] for k in legs]):.1f} deg, all eight limbs "
          f"{got.limb_mean_deg:.1f} deg (first frame held still: {still.limb_mean_deg:.1f} deg)")
    print("per limb (deg): " + ", ".join(f"{k} {v:.1f}" for k, v in got.limb_deg.items()))
    return plate_demo(bpy, twist_addon, a.out)


if __name__ == "__main__":
    sys.exit(main())

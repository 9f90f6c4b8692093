"""Render Muybridge-style footage of the CMU walk with Blender, and write tracking jobs for it.

The body is *not* the tracker's model: tapered elliptical capsules over the capture's bones,
skinned to the armature with weights that blend each bone into its parent at the joint,
coloured with a cloth-like pattern, lit by Workbench's studio light, in front of a dark
backdrop ruled with light lines (as Muybridge's were), with sensor noise added. Three
orthographic views at 480x360 (lateral, end-on at 90 degrees, oblique at 60 degrees) see a
fixed stage.

Blender's world is the BVH's world (imported without axis change: y up, metres), so the job's
cameras and the ground truth need no conversion. Run with the project's virtual environment:

    python bench/walk_footage.py --out .cache/walk --first 300 --last 772 --step 4

Writes OUT/<view>/NNNN.png, OUT/truth.bvh (the capture's frames that were rendered, the
ground truth) and OUT/cameras.json. Frames already rendered with the same settings are kept.
``write_job`` writes a tracking job for such footage, ``tracking_scene`` a Blender scene.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "scripts"))

from addon_dev import load_addon  # noqa: E402

from core import se3  # noqa: E402
from core.bvh import read_bvh, write_bvh  # noqa: E402
from core.skeleton import skeleton_from_bvh  # noqa: E402

CMU_WALK = ROOT / "bench" / "data" / "cmu_131_01_walk.bvh"  # see SOURCES.md there
WIDTH, HEIGHT = 480, 360
PIXELS_PER_METRE = 150.0
STAGE_CENTRE = np.array([0.5, 0.85, -0.55])  # world point at the middle of every image
NOISE_SIGMA = 2.0  # sensor noise, grey levels of 255
GRID_PIXELS = 24  # spacing of the backdrop's ruled lines
CAPTURE_FPS = 120

# The paper's 19 degrees of freedom on the CMU skeleton: ball hips, shoulders and neck; knees
# and elbows as hinges about the capture's own flexion axes (local frame).
JOINTS = {
    "LeftHip": "ball", "RightHip": "ball", "LeftShoulder": "ball", "RightShoulder": "ball",
    "Neck": "ball",
    # limits as anatomy has them (the knees bend one way, the elbows the other, from straight)
    "LeftKnee": {"kind": "hinge", "axis": [0.94, 0.34, 0.0], "limits": [0, 160]},
    "RightKnee": {"kind": "hinge", "axis": [0.94, -0.34, 0.0], "limits": [0, 160]},
    "LeftElbow": {"kind": "hinge", "axis": [0.87, 0.0, -0.5], "limits": [-160, 0]},
    "RightElbow": {"kind": "hinge", "axis": [0.87, 0.0, 0.5], "limits": [-160, 0]},
}
# The same body with the lower back a ball too (22 degrees of freedom): as it walks, the
# capture's pelvis turns and tilts against its chest, and a trunk rigid from the hips to the
# neck can only split the difference (on steady walking its pelvis was tracked 11 degrees
# off in yaw and 5 in roll, and the hips' centres, which the thighs hang from, with it)
SPINE_JOINTS = {**JOINTS, "lowerback": "ball"}
# blob short radii a user would set to line the blobs up with this body (metres)
BLOBS = {
    "LHipJoint": {"radius": 0.1}, "RHipJoint": {"radius": 0.1},
    "lowerback": {"radii": [0.12, 0.09], "length": 0.2},
    "Chest": {"radii": [0.13, 0.09], "length": 0.2},
    "lowerneck": {"radii": [0.12, 0.08], "length": 0.16},  # the upper chest
    "LThumb": False, "RThumb": False,
    "LeftHip": {"radius": 0.075}, "RightHip": {"radius": 0.075},
    "LeftKnee": {"radius": 0.05}, "RightKnee": {"radius": 0.05},
    "LeftAnkle": False, "RightAnkle": False,
    "LeftShoulder": {"radius": 0.045}, "RightShoulder": {"radius": 0.045},
    "LeftElbow": {"radius": 0.037}, "RightElbow": {"radius": 0.037},
    "Neck": {"radius": 0.05}, "Head": {"radius": 0.085},
    "LeftCollar": {"radius": 0.06}, "RightCollar": {"radius": 0.06},
    "LeftToe": False, "RightToe": False, "LeftWrist": False, "RightWrist": False,
}

# body radii (metres, across and front to back) by CMU joint name; others get DEFAULT_RADIUS
RADII = {
    "Hips": (0.12, 0.10), "LHipJoint": (0.11, 0.09), "RHipJoint": (0.11, 0.09),
    "LeftHip": (0.085, 0.085), "RightHip": (0.085, 0.085),
    "LeftKnee": (0.055, 0.055), "RightKnee": (0.055, 0.055),
    "LeftAnkle": (0.045, 0.045), "RightAnkle": (0.045, 0.045),
    "LeftToe": (0.035, 0.03), "RightToe": (0.035, 0.03),
    "lowerback": (0.11, 0.09), "Chest": (0.12, 0.09), "Chest2": (0.12, 0.09),
    "lowerneck": (0.06, 0.06), "Neck": (0.05, 0.05), "Head": (0.085, 0.09),
    "LeftCollar": (0.07, 0.06), "RightCollar": (0.07, 0.06),
    "LeftShoulder": (0.045, 0.045), "RightShoulder": (0.045, 0.045),
    "LeftElbow": (0.04, 0.04), "RightElbow": (0.04, 0.04),
    "LeftWrist": (0.032, 0.032), "RightWrist": (0.032, 0.032),
}
DEFAULT_RADIUS = (0.03, 0.03)
SKIPPED = ("Fingers", "Thumb", "hand")  # small parts left out of the body


def backdrop(zoom: int = 1) -> np.ndarray:
    """Muybridge's stage: a dark backdrop ruled with light lines every GRID_PIXELS, BGR 0..255
    (HEIGHT, WIDTH, 3), each ``zoom`` times larger. Static in every view: the tracker must
    ignore it inside its blobs."""
    img = np.full((HEIGHT * zoom, WIDTH * zoom, 3), 22.0)
    grid = GRID_PIXELS * zoom
    img[grid // 2 :: grid, :] = 120.0
    img[:, grid // 2 :: grid] = 120.0
    return img


def camera_rotations() -> dict[str, np.ndarray]:
    """World-to-camera rotations (rows: image x right, image y down, viewing direction)."""
    up = np.array([0.0, 1.0, 0.0])

    def look(direction):
        z = direction / np.linalg.norm(direction)
        y = -up
        x = np.cross(y, z)
        return np.stack([x, y, z])

    a = np.radians(60)
    return {
        "lateral": look(np.array([1.0, 0, 0])),  # walker moves left to right
        "endon": look(np.array([0, 0, -1.0])),  # the walker comes toward the camera
        "oblique60": look(np.array([np.cos(a), 0, -np.sin(a)])),
    }


def job_camera(R: np.ndarray, zoom: int = 1, distance: float | None = None,
               pans: list[float] | None = None) -> dict:
    """The job's camera dict, with STAGE_CENTRE mid-image (footage ``zoom`` times the size:
    the same stage in more pixels): scaled orthographic, pixel = s (R X + t)[:2] + center;
    or, ``distance`` metres from the centre, a pinhole as ``add_camera`` makes it, turned
    by ``pans`` (degrees, one per frame: R and t given per frame) where it pans."""
    center = [WIDTH * zoom / 2 - 0.5, HEIGHT * zoom / 2 - 0.5]
    if distance is None:
        return {"model": "scaled_orthographic", "R": R.tolist(),
                "t": (-R @ STAGE_CENTRE).tolist(), "scale": PIXELS_PER_METRE * zoom,
                "center": center}
    Rs = [R] if pans is None else [panned(R, a) for a in pans]
    return pinhole_job_camera(Rs, STAGE_CENTRE - distance * R[2],
                              PIXELS_PER_METRE * zoom * distance, center)


def pinhole_job_camera(Rs: list[np.ndarray], position: np.ndarray, f: float, center) -> dict:
    """A job's pinhole camera standing at ``position`` with focal length ``f`` and principal
    point ``center`` (pixels), turned by ``Rs``: one world-to-camera rotation, or one per
    frame for a camera that turns (R and t then given per frame)."""
    K = [[f, 0.0, center[0]], [0.0, f, center[1]], [0.0, 0.0, 1.0]]
    R, t = [r.tolist() for r in Rs], [(-r @ position).tolist() for r in Rs]
    return {"model": "pinhole", "K": K, "R": R if len(Rs) > 1 else R[0],
            "t": t if len(Rs) > 1 else t[0]}


def cloth_colour(P: np.ndarray, seed: int = 7) -> np.ndarray:
    """A woven, blotchy pattern of rest-pose positions (N, 3) -> RGB in [0, 1] (N, 3)."""
    rng = np.random.default_rng(seed)
    stripes = 0.5 + 0.5 * np.sign(np.sin(P[:, 1] * 2 * np.pi / 0.07)) * np.sign(
        np.sin((P[:, 0] + P[:, 2]) * 2 * np.pi / 0.09))
    k = rng.normal(size=(10, 3))
    k *= 2 * np.pi / 0.05 / np.linalg.norm(k, axis=1, keepdims=True)
    k *= rng.uniform(0.6, 1.6, (10, 1))
    blotch = np.sin(P @ k.T + rng.uniform(0, 6.3, 10)).mean(1)
    base = np.array([0.45, 0.28, 0.2]) + 0.4 * stripes[:, None] * np.array([0.6, 0.9, 1.0])
    return np.clip(base + 0.6 * blotch[:, None], 0.02, 0.98)


def _capsule_body(sk, radii: dict = RADII, spacing: float = 0.01, around: int = 32):
    """A body of tapered elliptical capsules, one per bone (joint to child or end site), with
    ``radii`` (metres, across and front to back) by joint name.

    Returns vertices (N, 3) in the rest pose, quad faces (M, 4) and, per vertex, its joint and
    weight and its parent joint and weight (blended over the first fifth of the bone, so that
    joints bend smoothly)."""
    verts, faces, groups = [], [], []
    for j, name in enumerate(sk.names):
        if any(x in name for x in SKIPPED):
            continue
        a = sk.rest_positions[j]
        tips = [(sk.rest_positions[c], sk.names[c]) for c in sk.children(j)
                if not any(x in sk.names[c] for x in SKIPPED)]
        tips += [(a + e, None) for e in sk.end_sites[j]]
        ra = np.array(radii.get(name, DEFAULT_RADIUS))
        for tip, tip_name in tips:
            L = float(np.linalg.norm(tip - a))
            if L < 1e-4:
                continue
            rb = np.array(radii.get(tip_name, 0.8 * ra)) if tip_name else 0.8 * ra
            u = (tip - a) / L
            v = np.array([1.0, 0, 0]) - u[0] * u
            if np.linalg.norm(v) < 0.3:
                v = np.array([0, 0, 1.0]) - u[2] * u
            v /= np.linalg.norm(v)
            w = np.cross(u, v)
            rings = []  # (axial position, radius scale, taper parameter)
            for th in np.linspace(-80, 0, 6, endpoint=False):
                rings.append((ra.mean() * np.sin(np.radians(th)), np.cos(np.radians(th)), 0.0))
            for t in np.linspace(0, 1, max(int(L / spacing), 2)):
                rings.append((t * L, 1.0, t))
            for th in np.linspace(0, 80, 6)[1:]:
                rings.append((L + rb.mean() * np.sin(np.radians(th)), np.cos(np.radians(th)), 1.0))
            phi = np.linspace(0, 2 * np.pi, around, endpoint=False)
            base = len(verts)
            parent = int(sk.parents[j])
            for s_ax, c, t in rings:
                r = (1 - t) * ra + t * rb
                ring = (a + s_ax * u)[None] + c * (np.cos(phi)[:, None] * r[0] * v
                                                   + np.sin(phi)[:, None] * r[1] * w)
                verts.extend(ring)
                wp = min(0.5, max(0.0, 0.5 * (1 - s_ax / (0.2 * L)))) if parent >= 0 else 0.0
                groups.extend([(j, 1 - wp, parent, wp)] * around)
            for i in range(len(rings) - 1):
                r0, r1 = base + i * around, base + (i + 1) * around
                for k in range(around):
                    k1 = (k + 1) % around
                    faces.append((r0 + k, r0 + k1, r1 + k1, r1 + k))
    return np.array(verts), np.array(faces), groups


def build_scene(bpy, bvh_path: Path, zoom: int = 1, radii: dict = RADII,
                width: int = WIDTH, height: int = HEIGHT):
    """Import the capture, build the skinned body (``radii`` by joint name), set up
    Workbench for ``zoom`` times width x height; returns the armature and the body."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    bpy.ops.import_anim.bvh(filepath=str(bvh_path), axis_forward="Y", axis_up="Z",
                            frame_start=1, rotate_mode="NATIVE")
    arm = bpy.context.selected_objects[0]
    sk = skeleton_from_bvh(read_bvh(bvh_path))

    P, faces, groups = _capsule_body(sk, radii)
    mesh = bpy.data.meshes.new("body")
    mesh.from_pydata(P.tolist(), [], faces.tolist())
    mesh.shade_smooth()
    body = bpy.data.objects.new("body", mesh)
    bpy.context.collection.objects.link(body)

    # cloth-like colours, from the rest pose so they ride with the body
    col = body.data.color_attributes.new("cloth", "FLOAT_COLOR", "POINT")
    rgba = np.concatenate([cloth_colour(P), np.ones((len(P), 1))], 1)
    col.data.foreach_set("color", rgba.astype(np.float32).ravel())
    body.data.color_attributes.active_color = col

    vgroups = {}
    for vi, (j, wj, pj, wp) in enumerate(groups):
        for jj, w in ((j, wj), (pj, wp)):
            if jj < 0 or w <= 0:
                continue
            name = sk.names[jj]
            if name not in vgroups:
                vgroups[name] = body.vertex_groups.new(name=name)
            vgroups[name].add([vi], float(w), "ADD")
    mod = body.modifiers.new("armature", "ARMATURE")
    mod.object = arm
    body.parent = arm
    arm.hide_render = True

    scene = bpy.context.scene
    scene.render.engine = "BLENDER_WORKBENCH"
    scene.display.shading.light = "STUDIO"
    scene.display.shading.color_type = "VERTEX"
    scene.display.shading.show_shadows = False
    scene.display.shading.show_cavity = False
    scene.render.resolution_x, scene.render.resolution_y = width * zoom, height * zoom
    scene.render.resolution_percentage = 100
    scene.render.image_settings.file_format = "PNG"
    scene.render.image_settings.color_mode = "RGBA"
    scene.render.film_transparent = True  # the backdrop is composited behind the body
    scene.display_settings.display_device = "sRGB"
    scene.view_settings.view_transform = "Standard"
    world = bpy.data.worlds.new("stage")
    world.color = (0.18, 0.17, 0.16)
    scene.world = world
    return arm, body


def add_camera(bpy, name: str, R: np.ndarray, centre: np.ndarray = STAGE_CENTRE,
               metres_across: float = WIDTH / PIXELS_PER_METRE, distance: float | None = None):
    """A camera with world-to-camera rotation ``R`` looking at ``centre`` and showing
    ``metres_across`` across there: orthographic (``distance`` None) or perspective,
    ``distance`` metres from ``centre``."""
    cam_data = bpy.data.cameras.new(name)
    cam_data.type = "ORTHO" if distance is None else "PERSP"
    cam_data.ortho_scale = metres_across
    if distance is not None:  # the focal length that shows the centre's depth that wide
        cam_data.sensor_fit = "HORIZONTAL"
        cam_data.lens = cam_data.sensor_width * distance / metres_across
    cam_data.clip_start, cam_data.clip_end = 0.01, 100.0
    cam = bpy.data.objects.new(name, cam_data)
    bpy.context.collection.objects.link(cam)
    place_camera(cam, R, centre - (10.0 if distance is None else distance) * R[2])
    return cam


def place_camera(cam, R: np.ndarray, position: np.ndarray) -> None:
    """Put ``cam`` at ``position`` with world-to-camera rotation ``R`` (rows: image x, image
    y down, viewing direction)."""
    from mathutils import Matrix

    # Blender's camera looks down its local -z with +y up: columns x, -y, -z of ours
    M = np.eye(4)
    M[:3, :3] = R.T @ np.diag([1.0, -1.0, -1.0])
    M[:3, 3] = position
    cam.matrix_world = Matrix(M.tolist())


def panned(R: np.ndarray, degrees: float) -> np.ndarray:
    """The rotation ``R`` of a camera turned ``degrees`` about its own image's vertical (a
    pan: positive turns the view to the image's right)."""
    return R @ se3.exp_so3(np.radians(degrees) * R[1]).T


def render(out: Path, first: int, last: int, step: int, views: list[str], zoom: int = 1,
           distance: float | None = None, pan: float = 0.0) -> dict:
    """Render the capture's frames first..last (every ``step``-th) in each view into OUT
    (``zoom`` times WIDTH x HEIGHT, the same stage), keeping frames already rendered with
    the same settings; returns the frames, the job cameras and how many were rendered.
    Cameras are orthographic, or perspective ``distance`` metres from the stage's centre;
    the first view's camera pans ``pan`` degrees a frame (``panned``)."""
    import bpy
    import cv2

    out.mkdir(parents=True, exist_ok=True)
    frames = list(range(first, last + 1, step))
    meta = {"bvh": str(CMU_WALK), "frames": frames, "width": WIDTH * zoom,
            "height": HEIGHT * zoom, "noise": NOISE_SIGMA, "version": 2,
            "filming": [distance, pan]}
    stamp = out / "footage.json"
    rots = camera_rotations()
    pans = {v: [pan * k for k in range(len(frames))] if pan and v == views[0] else None
            for v in views}
    todo = [(v, f) for v in views for f in frames
            if not (out / v / f"{f:04d}.png").is_file()]
    old = json.loads(stamp.read_text()) if stamp.is_file() else None
    kept = ("width", "height", "noise", "version", "filming")
    if old and {k: old.get(k) for k in kept} != {k: meta[k] for k in kept}:
        todo = [(v, f) for v in views for f in frames]
    if todo:
        arm, _ = build_scene(bpy, CMU_WALK, zoom)
        scene = bpy.context.scene
        cams = {v: add_camera(bpy, v, rots[v], distance=distance) for v in views}
        rng = np.random.default_rng(first * 7919 + last)
        for v, f in todo:
            (out / v).mkdir(exist_ok=True)
            scene.camera = cams[v]
            if pans[v]:
                place_camera(cams[v], panned(rots[v], pans[v][frames.index(f)]),
                             STAGE_CENTRE - distance * rots[v][2])
            scene.frame_set(f + 1)  # the importer puts BVH frame 0 on Blender frame 1
            path = out / v / f"{f:04d}.png"
            scene.render.filepath = str(path)
            bpy.ops.render.render(write_still=True)
            rgba = cv2.imread(str(path), cv2.IMREAD_UNCHANGED).astype(np.float32)
            alpha = rgba[..., 3:] / 255
            img = rgba[..., :3] * alpha + backdrop(zoom) * (1 - alpha)
            img += rng.normal(0, NOISE_SIGMA, img.shape)
            cv2.imwrite(str(path), np.clip(img + 0.5, 0, 255).astype(np.uint8))
    stamp.write_text(json.dumps(meta, indent=1))
    truth = read_bvh(CMU_WALK)
    truth.motion = truth.motion[frames]
    truth.frame_time *= step
    write_bvh(truth, out / "truth.bvh")
    cams_json = {v: job_camera(rots[v], zoom, distance, pans[v]) for v in views}
    (out / "cameras.json").write_text(json.dumps(cams_json, indent=1))
    return {"frames": frames, "cameras": cams_json, "rendered": len(todo)}


def tracking_scene(bpy, folder: Path, views: list[str], last_frame: int, images: str = "*.png",
                   joints: dict = JOINTS, distance: float | None = None, pan: float = 0.0):
    """Make the current scene ready to track rendered walk footage in ``folder``: the capture
    (folder/truth.bvh) imported as an armature and posed on frame 1, the bones of ``joints``
    unlocked, a hinge's bone rolled so that its local z is the capture's hinge axis and
    locked to turn about it alone, within its limits (as a user rigs an elbow), envelope
    radii from BLOBS, one camera and view per rendered view (as ``render`` filmed them, the
    first one's pan keyed on every frame), frames 1..last_frame.
    Needs the add-on registered; resetting the scene is the caller's (a factory reset disables
    an installed extension)."""
    load_addon()  # the working tree as the package ``twist_mocap``, if not yet imported
    from twist_mocap.twist_addon import bridge
    bpy.ops.import_anim.bvh(filepath=str(folder / "truth.bvh"), axis_forward="Y", axis_up="Z",
                            frame_start=1)
    arm = bpy.context.view_layer.objects.active
    scene = bpy.context.scene
    scene.frame_set(1)
    arm.animation_data_clear()  # the pose of frame 1 stays: the user's initial pose
    posed = bridge.pose_from_armature(arm, bridge.skeleton_from_armature(arm))
    for pb in arm.pose.bones:
        pb.lock_rotation = (pb.name not in joints,) * 3
    bpy.context.view_layer.objects.active = arm
    bpy.ops.object.mode_set(mode="EDIT")
    for eb in arm.data.edit_bones:
        spec = BLOBS.get(eb.name, {"radius": 0.0})
        r = 0.0 if spec is False else float(np.mean(spec.get("radii", [spec.get("radius")])))
        eb.head_radius = eb.tail_radius = r
    bpy.ops.object.mode_set(mode="OBJECT")
    # the hinges about the capture's axes (its rest axes are the world's), posed as on frame
    # 1 but for the tenth of a degree the capture turns off an axis as given
    bridge.rig_hinges(arm, {name: (np.array(spec["axis"], float),
                                   np.radians(spec.get("limits", [-np.inf, np.inf])))
                            for name, spec in joints.items()
                            if isinstance(spec, dict) and spec["kind"] == "hinge"}, *posed)
    scene.render.resolution_x, scene.render.resolution_y = WIDTH, HEIGHT
    scene.frame_start, scene.frame_end = 1, last_frame
    scene.twist.armature = arm
    rotations = camera_rotations()
    for i, v in enumerate(views):
        cam = add_camera(bpy, v, rotations[v], distance=distance)
        for k in range(last_frame if pan and i == 0 else 0):
            place_camera(cam, panned(rotations[v], pan * k),
                         STAGE_CENTRE - distance * rotations[v][2])
            cam.keyframe_insert("rotation_euler", frame=k + 1)
        view = scene.twist.views.add()
        view.camera, view.images, view.first_frame = cam, str(folder / v / images), 1
    scene.frame_set(1)
    return scene, arm


def write_job(folder: Path, name: str, views: list[str], mode: str, frames: list[int],
              cameras: dict, settings: dict, frame_time: float, joints: dict = JOINTS,
              correct_every: int = 0) -> Path:
    """Write folder/jobs/<name>.json tracking the given rendered frames (capture indices) of
    the given views with the tracked ``joints``; the skeleton comes from folder/truth.bvh
    and the initial pose from its frame of the first of ``frames``. With ``correct_every``
    N, every N-th frame is corrected to the capture's pose there, as a user who keyed it
    would."""
    jobs = folder / "jobs"
    jobs.mkdir(exist_ok=True)
    truth_frames = json.loads((folder / "footage.json").read_text())["frames"]  # truth.bvh
    job = {
        "skeleton": {"bvh": "../truth.bvh", "joints": joints, "blobs": BLOBS},
        "initial": {"bvh": "../truth.bvh", "frame": truth_frames.index(frames[0])},
        "views": [{"images": [f"../{v}/{f:04d}.png" for f in frames], "camera": cameras[v]}
                  for v in views],
        "mode": mode,
        "settings": settings,
        "frame_time": frame_time,
    }
    if correct_every:
        job["corrections"] = [{"image": i, "bvh": "../truth.bvh",
                               "frame": truth_frames.index(frames[i])}
                              for i in range(correct_every, len(frames), correct_every)]
    path = jobs / f"{name}.json"
    path.write_text(json.dumps(job, indent=1))
    return path


def add_footage_arguments(ap) -> None:
    """``--zoom`` (footage that many times the size, the same stage in more pixels) and
    ``--cache`` (where it is rendered); read them back with ``footage_cache``."""
    ap.add_argument("--zoom", type=int, default=1, help=f"footage this many times {WIDTH}x"
                    f"{HEIGHT}")
    ap.add_argument("--cache", "--out", type=Path, help="footage folder (default: "
                    ".cache/walk, or .cache/walk<zoom>x)")


def footage_cache(args) -> Path:
    """The footage folder the arguments of ``add_footage_arguments`` name."""
    return args.cache or ROOT / ".cache" / ("walk" if args.zoom == 1 else f"walk{args.zoom}x")


def add_spine_argument(ap) -> None:
    """``--spine``: track SPINE_JOINTS instead of JOINTS; read it back with
    ``tracked_joints``."""
    ap.add_argument("--spine", action="store_true", help="track the lower back too (22 "
                    "degrees of freedom instead of the paper's 19)")


def tracked_joints(args) -> dict:
    """The joints the argument of ``add_spine_argument`` asks to track."""
    return SPINE_JOINTS if args.spine else JOINTS


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--first", type=int, default=300)
    ap.add_argument("--last", type=int, default=772)
    ap.add_argument("--step", type=int, default=4, help="capture frames per rendered frame")
    ap.add_argument("--views", default="lateral,endon,oblique60")
    add_footage_arguments(ap)
    a = ap.parse_args(argv)
    out = footage_cache(a)
    info = render(out, a.first, a.last, a.step, a.views.split(","), a.zoom)
    print(f"{len(info['frames'])} frames x {len(info['cameras'])} views in {out}"
          f" ({info['rendered']} rendered now)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Views: a camera per view with its footage behind it, added and removed, and the footage's
image for each scene frame.

Operator ids are a public contract: ``twist.add_view``, ``twist.add_plate_view``,
``twist.add_calibrated_views``, ``twist.remove_view``."""

from __future__ import annotations

import glob
from pathlib import Path

import bpy
import cv2

from ..core.calibration import read_calibration
from ..core.errors import InputError
from ..core.image import IMAGE_SUFFIXES
from ..core.lens import Undistorted
from ..core.plate import unconfirmed, write_frames
from ..core.video import VideoFrames, is_video
from .bridge import BridgeError, place_pinhole
from .clip_lens import undistorted
from .properties import first_frame_property


def footage_frames(view_pg, frames: list[int]) -> list:
    """The image (file, or decoded movie frame) of every scene frame in ``frames`` for one
    view; BridgeError names the view and the first frame without an image."""
    cam = view_pg.camera.name if view_pg.camera else "(no camera)"
    if not view_pg.images:
        raise BridgeError(f"the view of '{cam}' has no footage; set its images")
    source = bpy.path.abspath(view_pg.images)
    paths = VideoFrames(source) if is_video(source) else sorted(glob.glob(source))
    if not len(paths):
        raise BridgeError(f"the footage of the view of '{cam}' ({view_pg.images}) matches no "
                          "file")
    indices = []
    for f in frames:
        i = f - view_pg.first_frame
        if not 0 <= i < len(paths):
            raise BridgeError(f"the view of '{cam}' has no image for frame {f} (its "
                              f"{len(paths)} images cover frames {view_pg.first_frame}-"
                              f"{view_pg.first_frame + len(paths) - 1})")
        indices.append(i)
    if isinstance(paths, list):
        return [paths[i] for i in indices]
    return paths.select(indices)


def clean_plate(view_pg):
    """The view's clean plate (its scene without the body) as the tracker reads it: the
    file, read through the lens of the movie clip behind the camera like its footage; None
    when not set. BridgeError when the file is missing."""
    if not view_pg.backdrop:
        return None
    path = Path(bpy.path.abspath(view_pg.backdrop))
    if not path.is_file():
        cam = view_pg.camera.name if view_pg.camera else "(no camera)"
        raise BridgeError(f"{path}: the clean plate of the view of '{cam}' is not found; pick "
                          "the image again, or clear it to paint the backdrop from the first "
                          "frame")
    return undistorted(view_pg, [str(path)])[0][0]


def add_footage_view(context, path: Path, first_frame: int) -> str:
    """Add a view of the footage ``path`` (a movie, or any image of a sequence: its folder's
    images of the same kind, in name order) from ``first_frame``: an orthographic camera
    looking along +y with the footage behind it; the first view sets the scene's frame
    range and resolution, a later one shortens the range to its footage. Returns what was
    done; BridgeError when Blender cannot read the file."""
    movie = is_video(path)
    pattern = str(path) if movie else str(path.parent / f"*{path.suffix}")
    try:
        if movie:
            source = bpy.data.movieclips.load(str(path), check_existing=True)
            count, (img_w, img_h) = source.frame_duration, source.size
            if not count:
                bpy.data.movieclips.remove(source)
                raise RuntimeError("no frames")
        else:
            count = len(glob.glob(pattern))
            source = bpy.data.images.load(str(path), check_existing=True)
            img_w, img_h = source.size  # a sequence reports no size until it is shown
    except RuntimeError:
        raise BridgeError(f"{path.name}: Blender cannot read it as a movie or an image; "
                          "pick a movie file or any image of an image sequence") from None
    scene = context.scene
    n = len(scene.twist.views) + 1
    cam_data = bpy.data.cameras.new(f"View {n}")
    cam_data.type = "ORTHO"
    cam_data.show_background_images = True
    cam = bpy.data.objects.new(f"View {n}", cam_data)
    context.collection.objects.link(cam)
    cam.location = (0.0, -10.0, 1.0)
    cam.rotation_euler = (1.5707963, 0.0, 0.0)  # looking along +y, z up: a side view
    bg = cam_data.background_images.new()
    bg.frame_method = "FIT"
    if movie:
        source.frame_start = first_frame
        bg.source, bg.clip = "MOVIE_CLIP", source
    else:
        source.source = "SEQUENCE" if count > 1 else "FILE"
        bg.image = source
        bg.image_user.frame_start = first_frame
        bg.image_user.frame_duration = count
    if img_w and img_h and n == 1:
        scene.render.resolution_x, scene.render.resolution_y = img_w, img_h
    view = scene.twist.views.add()
    view.camera = cam
    view.images = bpy.path.relpath(pattern) if bpy.data.filepath else pattern
    view.first_frame = first_frame
    scene.twist.active_view = len(scene.twist.views) - 1
    last = first_frame + count - 1
    message = f"added '{cam.name}' with {count} frames"
    if n == 1:  # the scene's range is the footage's
        scene.frame_start, scene.frame_end = first_frame, last
        message += f"; the scene's frames are now {first_frame}-{last}"
    elif scene.frame_end > last:  # every view must have an image for every frame
        scene.frame_end = max(last, scene.frame_start)
        message += f"; the scene now ends at frame {scene.frame_end}, where its footage does"
    return message


class _FromFile:
    """An operator on one file the user picks (``filepath``), beside which it may write:
    ``run(context, path)`` does the work and returns what was done; an error it raises, a
    missing file or a folder that cannot be written is reported instead, nothing done."""

    bl_options = {"REGISTER", "UNDO"}
    kind = "file"  # what the file is, for the message when it is missing

    def invoke(self, context, event):
        context.window_manager.fileselect_add(self)
        return {"RUNNING_MODAL"}

    def execute(self, context):
        path = Path(bpy.path.abspath(self.filepath))
        if not path.is_file():
            self.report({"ERROR"}, f"{self.filepath}: no such {self.kind}")
            return {"CANCELLED"}
        try:
            message = self.run(context, path)
        except InputError as e:
            self.report({"ERROR"}, str(e))
            return {"CANCELLED"}
        except OSError as e:
            self.report({"ERROR"}, f"cannot write beside {path.name} into {path.parent} "
                        f"({e.strerror}): copy it into a folder you can write to")
            return {"CANCELLED"}
        self.report({"INFO"}, message)
        return {"FINISHED"}


class TWIST_OT_add_view(_FromFile, bpy.types.Operator):
    """Add a view: an orthographic camera with the footage behind it, one image per frame"""

    bl_idname = "twist.add_view"
    bl_label = "Add View"
    kind = "image or movie file"

    filepath: bpy.props.StringProperty(
        name="Footage", subtype="FILE_PATH",
        description="A movie, or any image of the footage: its folder's images of the same "
                    "kind are read in name order")
    first_frame: first_frame_property()

    def run(self, context, path: Path) -> str:
        return add_footage_view(context, path, self.first_frame)


class TWIST_OT_add_plate_view(_FromFile, bpy.types.Operator):
    """Add a view from a printed plate: its cells cut out, lined up on the ground line and
    written as an image sequence beside the plate, then added as the view's footage"""

    bl_idname = "twist.add_plate_view"
    bl_label = "Add View from Plate"
    kind = "image file"

    filepath: bpy.props.StringProperty(
        name="Plate", subtype="FILE_PATH",
        description="The plate's image: cells in rows with dark gutters between the rows")
    per_row: bpy.props.IntProperty(
        name="Cells per Row", min=0, default=0,
        description="How many cells each row holds (0: found from the plate; give it where "
                    "the cells touch with no gutter between them)")
    first_frame: first_frame_property()

    def run(self, context, plate: Path) -> str:
        out = plate.parent / f"{plate.stem}_frames"
        try:
            cells, paths = write_frames(plate, out, self.per_row or None)
        except InputError as e:
            raise BridgeError(f"{plate.name}: {e}") from None
        message = add_footage_view(context, paths[0], self.first_frame)
        doubtful = unconfirmed(cells)
        if doubtful:
            self.report({"WARNING"}, f"{plate.name}: {doubtful}")
        return f"{plate.name}: {len(cells)} cells cut into {out.name}/; " + message


def _camera_footage(folder: Path, name: str) -> Path:
    """The footage of the calibration's camera ``name`` beside it: a movie ``name.*``, or
    the first image of a folder ``name/``; BridgeError saying where to put it."""
    movies = sorted(p for p in folder.glob(f"{glob.escape(name)}.*") if is_video(p))
    if movies:
        return movies[0]
    frames = sorted(p for p in (folder / name).glob("*") if p.suffix.lower() in IMAGE_SUFFIXES) \
        if (folder / name).is_dir() else []
    if frames:
        return frames[0]
    raise BridgeError(f"no footage for the camera '{name}': put its movie ({name}.mp4, ...) or "
                      f"its frames (a folder {name}/) beside the calibration, in {folder}")


def _undistorted_footage(path: Path, cam, out: Path) -> Path:
    """The footage ``path`` (a movie, or an image of a sequence) undistorted through the
    camera's lens into ``out`` as PNG frames on the calibration's pixel grid; the first
    frame's path."""
    frames = VideoFrames(path) if is_video(path) else sorted(path.parent.glob(f"*{path.suffix}"))
    lens = Undistorted([], cam.camera.K, cam.dist, cam.size)
    out.mkdir(exist_ok=True)
    for old in out.glob("*.png"):
        old.unlink()
    for i in range(len(frames)):
        img = frames[i] if is_video(path) else cv2.imread(str(frames[i]), cv2.IMREAD_UNCHANGED)
        if img is None:
            raise BridgeError(f"{frames[i]}: cannot read this image")
        cv2.imwrite(str(out / f"{i + 1:04d}.png"), lens.remap(img))
    return out / "0001.png"


def add_calibrated_views(context, calibration: Path, first_frame: int) -> str:
    """One view per camera of a calibration file (``core.calibration``), each a perspective
    camera placed and lensed as calibrated, with its footage found beside the file
    (``_camera_footage``) and, through a distorting lens, undistorted into a folder
    ``<camera>_undistorted`` there first. The scene takes the calibration's resolution and
    the calibrated mode. Everything is checked before anything is added."""
    try:
        cams = read_calibration(calibration)
    except InputError as e:
        raise BridgeError(str(e)) from None
    sizes = {c.size for c in cams}
    if None in sizes or len(sizes) > 1:
        raise BridgeError(f"{calibration.name}: its cameras' image sizes are "
                          f"{', '.join(str(c.size) for c in cams)}; a scene renders every "
                          "camera at one resolution, so one size given for all is needed")
    folder = calibration.parent
    sources = [_camera_footage(folder, c.name) for c in cams]
    scene = context.scene
    for cam, source in zip(cams, sources):
        if cam.dist is not None:
            source = _undistorted_footage(source, cam, folder / f"{cam.name}_undistorted")
        add_footage_view(context, source, first_frame)
        obj = scene.twist.views[-1].camera
        obj.name = obj.data.name = cam.name
        place_pinhole(obj, cam.camera, cam.size)
    scene.render.resolution_x, scene.render.resolution_y = cams[0].size
    scene.render.resolution_percentage = 100
    scene.twist.mode = "CALIBRATED"
    undistorted = sum(c.dist is not None for c in cams)
    return (f"{calibration.name}: {len(cams)} calibrated views ({', '.join(c.name for c in cams)})"
            + (f", {undistorted} with their footage undistorted beside it" if undistorted else "")
            + f"; the scene is {cams[0].size[0]}x{cams[0].size[1]}, Calibrated")


class TWIST_OT_add_calibrated_views(_FromFile, bpy.types.Operator):
    """Add one view per camera of a calibration file (OpenCV, Pose2Sim, Qualisys): perspective
    cameras placed as calibrated, each with its movie or frames folder named after it beside
    the file (undistorted first where the lens distorts)"""

    bl_idname = "twist.add_calibrated_views"
    bl_label = "Add Views from Calibration"
    kind = "calibration file"

    filepath: bpy.props.StringProperty(
        name="Calibration", subtype="FILE_PATH",
        description="OpenCV's .yml/.yaml/.xml/.json, Pose2Sim's .toml or Qualisys' .qca.txt; "
                    "each camera's footage beside it, named after the camera")
    first_frame: first_frame_property()

    def run(self, context, path: Path) -> str:
        return add_calibrated_views(context, path, self.first_frame)


class TWIST_OT_remove_view(bpy.types.Operator):
    """Remove the selected view (its camera stays in the scene)"""

    bl_idname = "twist.remove_view"
    bl_label = "Remove View"
    bl_options = {"REGISTER", "UNDO"}

    @classmethod
    def poll(cls, context):
        return len(context.scene.twist.views) > 0

    def execute(self, context):
        tw = context.scene.twist
        tw.views.remove(tw.active_view)
        tw.active_view = max(0, min(tw.active_view, len(tw.views) - 1))
        return {"FINISHED"}


CLASSES = (TWIST_OT_add_view, TWIST_OT_add_plate_view, TWIST_OT_add_calibrated_views,
           TWIST_OT_remove_view)

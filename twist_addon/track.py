"""A tracking run on the scene: gather the armature, views and footage, step the core tracker
frame by frame, key each tracked frame. The Track operator drives it (all at once from a
script, one frame per timer tick in the UI)."""

from __future__ import annotations

import glob
from dataclasses import dataclass, field

import bpy

from ..core.job import world_root
from ..core.pose import BodyPose
from ..core.tracker import FrameResult, Tracker
from ..core.video import VideoFrames, is_video
from . import keyframes
from .bridge import BridgeError, pose_from_armature, tracked_skeleton, view_from_camera
from .properties import settings_from_properties


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


@dataclass
class TrackSession:
    """Everything one run needs, checked before the first frame is tracked. A frame after the
    first where the user keyed a tracked bone is a correction: its pose (as the scene shows
    it there) is taken as that frame's result and becomes the key frame later frames are held
    against, and the user's keys stay as they are."""

    armature: bpy.types.Object
    frames: list[int]
    tracker: Tracker
    initial: BodyPose
    user_keys: dict[int, frozenset[str]] = field(default_factory=dict)  # frame -> bones
    corrections: dict[int, BodyPose] = field(default_factory=dict)  # by index in ``frames``
    tracked: list[FrameResult] = field(default_factory=list)

    @classmethod
    def from_scene(cls, scene) -> TrackSession:
        tw = scene.twist
        arm = tw.armature
        if arm is None:
            raise BridgeError("no armature is set to track (Twist Mocap > Armature)")
        if not tw.views:
            raise BridgeError("there are no views; add a camera with its footage")
        cur = scene.frame_current
        if tw.direction == "FORWARD":
            frames = list(range(cur, scene.frame_end + 1))
        else:
            frames = list(range(cur, scene.frame_start - 1, -1))
        if len(frames) < 2:
            raise BridgeError(f"nothing to track {tw.direction.lower()} from frame {cur}")
        views, images = [], []
        for v in tw.views:
            if v.camera is None:
                raise BridgeError("a view has no camera; pick its camera or remove the view")
            views.append(view_from_camera(v.camera, scene))
            images.append(footage_frames(v, frames))
        sk = tracked_skeleton(arm)
        R, root = pose_from_armature(arm, sk)
        user_keys = keyframes.user_keys(arm, sk)
        corrections = {}
        for i, f in enumerate(frames[1:], 1):
            if f in user_keys:
                scene.frame_set(f)
                corrections[i] = BodyPose(*pose_from_armature(arm, sk), views)
        if corrections:
            scene.frame_set(cur)
        settings = settings_from_properties(tw.tracker)
        # the tracker indexes frames 0..n-1 in tracking order
        tracker = Tracker(sk, images, tw.mode.lower(), settings)
        return cls(arm, frames, tracker, BodyPose(R, root, views), user_keys, corrections)

    def run(self):
        """Yield after each frame is tracked and keyed."""
        sk = self.tracker.given_skeleton  # the armature's joints, whatever side-on tracks
        steps = self.tracker.iter_track(self.initial, range(len(self.frames)),
                                        self.corrections)
        for res in steps:
            frame = self.frames[res.frame]
            if res.frame and not res.diverged:
                R = res.pose.rotations.copy()
                R[0], root = world_root(self.tracker.mode, self.initial.views[0], res.pose)
                keyframes.write_pose(self.armature, sk, frame, R, root,
                                     self.user_keys.get(frame, frozenset()))
            self.tracked.append(res)
            yield res

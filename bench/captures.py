"""Motion captures of different sources brought to one form, and their body parts by naming.

The benchmark's clips come from three conversions that name and lay out a body differently
(the data's SOURCES.md): CMU 131 as converted with joints named ``LeftHip/LeftKnee/...`` in
metres; CMU as converted for MotionBuilder (``LeftUpLeg/LeftLeg/...``, CMU length units,
frame 0 an added T-pose); and Bandai Namco's (``UpperLeg_L/LowerLeg_L/...``, centimetres,
30 fps, a still ``joint_Root`` above the moving ``Hips`` and position channels on every
joint that repeat its offset). ``normalized`` gives each as one BVH in metres whose root
carries the motion and whose other joints only turn; ``Parts`` names what the benchmark
reads in it (limbs, the joints a user would free) whatever the naming.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from core import se3
from core.bvh import BvhFile, BvhJoint, read_bvh
from core.skeleton import Skeleton

CMU_UNIT = 0.056444  # metres per CMU length unit (the MotionBuilder conversion)
ROOT_CHANNELS = ["Xposition", "Yposition", "Zposition", "Zrotation", "Yrotation", "Xrotation"]
CHANNELS = ["Zrotation", "Yrotation", "Xrotation"]

# role -> its joint in each naming; a role's bone runs from its joint to the joint's child
NAMINGS = {
    "cmu131": {
        "thigh.L": "LeftHip", "thigh.R": "RightHip", "shank.L": "LeftKnee",
        "shank.R": "RightKnee", "foot.L": "LeftAnkle", "foot.R": "RightAnkle",
        "upper_arm.L": "LeftShoulder", "upper_arm.R": "RightShoulder",
        "forearm.L": "LeftElbow", "forearm.R": "RightElbow", "hand.L": "LeftWrist",
        "hand.R": "RightWrist", "neck": "Neck", "head": "Head", "lower_back": "lowerback",
    },
    "cmu_motionbuilder": {
        "thigh.L": "LeftUpLeg", "thigh.R": "RightUpLeg", "shank.L": "LeftLeg",
        "shank.R": "RightLeg", "foot.L": "LeftFoot", "foot.R": "RightFoot",
        "upper_arm.L": "LeftArm", "upper_arm.R": "RightArm", "forearm.L": "LeftForeArm",
        "forearm.R": "RightForeArm", "hand.L": "LeftHand", "hand.R": "RightHand",
        "neck": "Neck", "head": "Head", "lower_back": "LowerBack",
    },
    "bandai_namco": {
        "thigh.L": "UpperLeg_L", "thigh.R": "UpperLeg_R", "shank.L": "LowerLeg_L",
        "shank.R": "LowerLeg_R", "foot.L": "Foot_L", "foot.R": "Foot_R",
        "upper_arm.L": "UpperArm_L", "upper_arm.R": "UpperArm_R", "forearm.L": "LowerArm_L",
        "forearm.R": "LowerArm_R", "hand.L": "Hand_L", "hand.R": "Hand_R", "neck": "Neck",
        "head": "Head", "lower_back": "Spine",
    },
}
# each naming's joints as the CMU 131 walk names their body parts: the rendered body's
# radii (walk_footage.RADII) are given by those names
_SIDES = ("Left", "Right")
AS_CMU131 = {
    "cmu131": {},
    "cmu_motionbuilder": {
        **{f"{s}{a}": f"{s}{b}" for s in _SIDES for a, b in (
            ("UpLeg", "Hip"), ("Leg", "Knee"), ("Foot", "Ankle"), ("ToeBase", "Toe"),
            ("Shoulder", "Collar"), ("Arm", "Shoulder"), ("ForeArm", "Elbow"),
            ("Hand", "Wrist"))},
        "LowerBack": "lowerback", "Spine": "Chest", "Spine1": "Chest2", "Neck": "lowerneck",
        "Neck1": "Neck",
    },
    "bandai_namco": {
        **{f"{a}_{s[0]}": f"{s}{b}" for s in _SIDES for a, b in (
            ("UpperLeg", "Hip"), ("LowerLeg", "Knee"), ("Foot", "Ankle"), ("Toes", "Toe"),
            ("Shoulder", "Collar"), ("UpperArm", "Shoulder"), ("LowerArm", "Elbow"),
            ("Hand", "Wrist"))},
        "Spine": "lowerback",
    },
}
LIMB_ROLES = [  # (label, role at its start, role at its end), the eight limbs first
    ("left thigh", "thigh.L", "shank.L"), ("right thigh", "thigh.R", "shank.R"),
    ("left shank", "shank.L", "foot.L"), ("right shank", "shank.R", "foot.R"),
    ("left upper arm", "upper_arm.L", "forearm.L"),
    ("right upper arm", "upper_arm.R", "forearm.R"),
    ("left forearm", "forearm.L", "hand.L"), ("right forearm", "forearm.R", "hand.R"),
]
BALLS = ("thigh.L", "thigh.R", "upper_arm.L", "upper_arm.R", "neck")
HINGES = ("shank.L", "shank.R", "forearm.L", "forearm.R")


def naming_of(names: list[str]) -> str:
    """Which of ``NAMINGS`` a skeleton's joint names follow (by its left thigh's name)."""
    for naming, roles in NAMINGS.items():
        if roles["thigh.L"] in names:
            return naming
    raise ValueError(f"joint names of no known naming: {', '.join(names[:8])}...")


def normalized(path: Path, first: int = 0, last: int | None = None) -> BvhFile:
    """The capture's frames ``first..last`` (file frames, inclusive; a MotionBuilder file's
    frame 0 is its added T-pose) in metres, with one moving root and only rotations below."""
    bvh = read_bvh(path)
    naming = naming_of(bvh.names)
    unit = {"cmu131": 1.0, "cmu_motionbuilder": CMU_UNIT, "bandai_namco": 0.01}[naming]
    frames = np.arange(first, len(bvh.motion) if last is None else last + 1)
    R, root = bvh.poses(frames)
    keep = list(range(len(bvh.joints)))
    if naming == "bandai_namco":  # the still joint_Root goes; Hips becomes the root
        top = bvh.joints[0]
        if np.abs(R[:, 0] - np.eye(3)).max() > 1e-6 or np.abs(top.offset).max() > 1e-6:
            raise ValueError(f"{path}: its {top.name} moves; expected it still at the origin")
        sl = bvh.channel_slices()[1]
        chans = bvh.joints[1].channels
        root = np.stack([bvh.motion[frames, sl][:, chans.index(c)]
                         for c in ("Xposition", "Yposition", "Zposition")], 1)
        R = R[:, 1:]
        keep = keep[1:]
    joints = []
    for k, j in enumerate(keep):
        src = bvh.joints[j]
        parent = -1 if k == 0 else keep.index(src.parent)
        joints.append(BvhJoint(src.name, parent, np.asarray(src.offset, float) * unit,
                               list(ROOT_CHANNELS if k == 0 else CHANNELS),
                               [np.asarray(e, float) * unit for e in src.end_sites]))
    joints[0].offset = np.zeros(3)
    out = BvhFile(joints, np.zeros((0, 0)), bvh.frame_time)
    return out.with_motion(R, root * unit)


@dataclass
class Parts:
    """What the benchmark reads in one skeleton: its limbs as (label, from, to) joint names,
    the joints a user would free and how."""

    naming: str
    roles: dict[str, str]  # role -> joint name

    @classmethod
    def of(cls, names: list[str]) -> Parts:
        naming = naming_of(names)
        return cls(naming, NAMINGS[naming])

    def radii(self, by_cmu131_name: dict) -> dict:
        """``by_cmu131_name`` (joint name -> radii in the CMU 131 walk's naming) in this
        skeleton's naming."""
        own = {v: k for k, v in AS_CMU131[self.naming].items()}
        return {own.get(k, k): v for k, v in by_cmu131_name.items()}

    def limbs(self) -> list[tuple[str, str, str]]:
        return [(label, self.roles[a], self.roles[b]) for label, a, b in LIMB_ROLES]

    def tracked_joints(self, sk: Skeleton, rotations: np.ndarray, lower_back: bool) -> dict:
        """The job's ``joints``: balls at the hips, shoulders and neck (and the lower back),
        hinges at the knees and elbows about the axis each turns about most over
        ``rotations`` (F, J, 3, 3), as a user refining the skeleton from footage would find
        it, signed so that bending is positive, and limited to -10..165 degrees."""
        out = {self.roles[r]: "ball" for r in BALLS}
        if lower_back:
            out[self.roles["lower_back"]] = "ball"
        for r in HINGES:
            j = sk.index(self.roles[r])
            w = np.array([se3.log_so3(M) for M in rotations[:, j]])
            axis = np.linalg.svd(w, full_matrices=False)[2][0]  # through the rest pose
            if np.mean(w @ axis) < 0:
                axis = -axis
            out[self.roles[r]] = {"kind": "hinge", "axis": axis.round(4).tolist(),
                                  "limits": [-10, 165]}
        return out

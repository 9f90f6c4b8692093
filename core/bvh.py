"""Reading and writing BVH motion files: hierarchy, offsets, channel layout and motion.

Conventions: a joint's rotation channels compose in the order listed, each about the joint's
local axis (``Zrotation Yrotation Xrotation`` means R = Rz @ Ry @ Rx); angles are degrees in
the file and rotation matrices here. The rest pose has every joint frame aligned with the
world, so a joint's rest position is the sum of its ancestors' offsets. Position channels on
the root hold its absolute position; on another joint they are added to its offset.
"""

from __future__ import annotations

import re
import warnings
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from .errors import InputError

_ROT = ("Xrotation", "Yrotation", "Zrotation")
_POS = ("Xposition", "Yposition", "Zposition")


class BvhError(InputError):
    """A BVH file that cannot be read; the message names the file and the line."""


@dataclass
class BvhJoint:
    name: str
    parent: int
    offset: np.ndarray
    channels: list[str]
    end_sites: list[np.ndarray] = field(default_factory=list)

    @property
    def rotation_order(self) -> str:
        """Intrinsic axis order for scipy, e.g. 'ZYX' for Zrotation Yrotation Xrotation."""
        return "".join(c[0] for c in self.channels if c in _ROT)


@dataclass
class BvhFile:
    """A parsed BVH: joints in file order (parents before children) and the motion table."""

    joints: list[BvhJoint]
    motion: np.ndarray  # (frames, channels), file units and degrees
    frame_time: float

    @property
    def names(self) -> list[str]:
        return [j.name for j in self.joints]

    def channel_slices(self) -> list[slice]:
        out, k = [], 0
        for j in self.joints:
            out.append(slice(k, k + len(j.channels)))
            k += len(j.channels)
        return out

    def frame_pose(self, frame: int) -> tuple[np.ndarray, np.ndarray]:
        """Local rotations (J, 3, 3) and root position (3,) of one frame."""
        if not 0 <= frame < len(self.motion):
            raise BvhError(f"frame {frame} is outside the file's 0..{len(self.motion) - 1}")
        R, root = self.poses(np.array([frame]))
        return R[0], root[0]

    def poses(self, frames: np.ndarray | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Local rotations (F, J, 3, 3) and root positions (F, 3) of the given frames."""
        rows = self.motion if frames is None else self.motion[np.asarray(frames)]
        F, J = len(rows), len(self.joints)
        R = np.tile(np.eye(3), (F, J, 1, 1))
        root = np.tile(self.joints[0].offset, (F, 1)).astype(float)
        for j, (joint, sl) in enumerate(zip(self.joints, self.channel_slices())):
            vals = rows[:, sl]
            rot_cols = [i for i, c in enumerate(joint.channels) if c in _ROT]
            if rot_cols:
                R[:, j] = Rotation.from_euler(
                    joint.rotation_order, vals[:, rot_cols], degrees=True
                ).as_matrix()
            if j == 0:
                for i, c in enumerate(joint.channels):
                    if c in _POS:
                        root[:, _POS.index(c)] = vals[:, i]
        return R, root

    def with_motion(self, rotations: np.ndarray, root_positions: np.ndarray) -> BvhFile:
        """A copy with the same hierarchy and channel layout holding the given poses.

        rotations: (F, J, 3, 3) local rotations; root_positions: (F, 3).
        """
        F = len(rotations)
        cols = []
        for j, joint in enumerate(self.joints):
            rot = [c for c in joint.channels if c in _ROT]
            euler = _euler(rotations[:, j], joint.rotation_order) if rot else np.zeros((F, 0))
            k = 0
            for c in joint.channels:
                if c in _ROT:
                    cols.append(euler[:, k])
                    k += 1
                elif j == 0:
                    cols.append(root_positions[:, _POS.index(c)])
                else:
                    cols.append(np.zeros(F))
        motion = np.stack(cols, axis=1) if cols else np.zeros((F, 0))
        return BvhFile(self.joints, motion, self.frame_time)


def read_bvh(path: str | Path) -> BvhFile:
    """Parse a BVH file; errors name the file and line and say what was expected."""
    path = Path(path)
    try:
        text = path.read_text()
    except OSError as e:
        raise BvhError(f"{path}: cannot read the BVH file ({e.strerror})") from e
    lines = text.splitlines()
    tokens: list[tuple[int, str]] = []
    motion_line = None
    for n, line in enumerate(lines, 1):
        if line.strip().upper().startswith("MOTION"):
            motion_line = n
            break
        tokens.extend((n, t) for t in line.split())
    if motion_line is None:
        raise BvhError(f"{path}: no MOTION section; a BVH file needs HIERARCHY then MOTION")

    joints: list[BvhJoint] = []
    pos = 0

    def take(expected: str | None = None) -> tuple[int, str]:
        nonlocal pos
        if pos >= len(tokens):
            raise BvhError(f"{path}: the hierarchy ends early (expected {expected or 'more'})")
        n, t = tokens[pos]
        pos += 1
        if expected is not None and t.upper() != expected.upper():
            raise BvhError(f"{path}, line {n}: expected '{expected}', found '{t}'")
        return n, t

    def floats(k: int) -> np.ndarray:
        vals = []
        for _ in range(k):
            n, t = take()
            try:
                vals.append(float(t))
            except ValueError:
                raise BvhError(f"{path}, line {n}: expected a number, found '{t}'") from None
        return np.array(vals)

    def parse_joint(parent: int) -> None:
        _, name = take()
        take("{")
        take("OFFSET")
        offset = floats(3)
        take("CHANNELS")
        n, count = take()
        if not count.isdigit():
            raise BvhError(f"{path}, line {n}: expected a channel count, found '{count}'")
        channels = [take()[1] for _ in range(int(count))]
        for c in channels:
            if c not in _ROT + _POS:
                raise BvhError(f"{path}, line {n}: unknown channel '{c}' on joint '{name}'")
        joints.append(BvhJoint(name, parent, offset, channels))
        me = len(joints) - 1
        while True:
            n, t = take()
            key = t.upper()
            if key == "}":
                return
            if key == "JOINT":
                parse_joint(me)
            elif key == "END":
                take("Site")
                take("{")
                take("OFFSET")
                joints[me].end_sites.append(floats(3))
                take("}")
            else:
                raise BvhError(f"{path}, line {n}: expected JOINT, End Site or '}}', found '{t}'")

    take("HIERARCHY")
    take("ROOT")
    parse_joint(-1)

    header = lines[motion_line : motion_line + 2]
    m_frames = re.match(r"\s*Frames:\s*(\d+)", header[0] if header else "")
    m_time = re.match(r"\s*Frame Time:\s*([0-9.eE+-]+)", header[1] if len(header) > 1 else "")
    if not (m_frames and m_time):
        raise BvhError(f"{path}, line {motion_line + 1}: expected 'Frames: N' and 'Frame Time: T'")
    n_frames = int(m_frames.group(1))
    n_ch = sum(len(j.channels) for j in joints)
    rows = [ln for ln in lines[motion_line + 2 :] if ln.strip()]
    if len(rows) < n_frames:
        raise BvhError(f"{path}: the header promises {n_frames} frames, the file has {len(rows)}")
    motion = np.zeros((n_frames, n_ch))
    for i, ln in enumerate(rows[:n_frames]):
        vals = ln.split()
        if len(vals) != n_ch:
            raise BvhError(
                f"{path}, line {motion_line + 3 + i}: {len(vals)} values, the hierarchy has"
                f" {n_ch} channels"
            )
        motion[i] = [float(v) for v in vals]
    return BvhFile(joints, motion, float(m_time.group(1)))


def _euler(rotations: np.ndarray, order: str) -> np.ndarray:
    """Angles (F, 3) in degrees, in ``order``, of rotations (F, 3, 3). At gimbal lock (the
    middle angle at +-90 degrees) scipy warns and sets the third angle to zero; the angles
    still compose to the same rotation, so the warning is not passed on."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", "Gimbal lock detected", UserWarning)
        return Rotation.from_matrix(rotations).as_euler(order, degrees=True)


def write_bvh(bvh: BvhFile, path: str | Path) -> None:
    """Write a BvhFile; offsets and values with 6 decimals."""
    out: list[str] = ["HIERARCHY"]
    children: dict[int, list[int]] = {}
    for i, j in enumerate(bvh.joints):
        children.setdefault(j.parent, []).append(i)

    def fmt(v) -> str:
        return " ".join(f"{x:.6f}" for x in v)

    def emit(i: int, depth: int) -> None:
        j = bvh.joints[i]
        pad = "\t" * depth
        out.append(f"{pad}{'ROOT' if j.parent < 0 else 'JOINT'} {j.name}")
        out.append(f"{pad}{{")
        out.append(f"{pad}\tOFFSET {fmt(j.offset)}")
        out.append(f"{pad}\tCHANNELS {len(j.channels)} {' '.join(j.channels)}")
        for c in children.get(i, []):
            emit(c, depth + 1)
        for e in j.end_sites:
            out.extend([f"{pad}\tEnd Site", f"{pad}\t{{", f"{pad}\t\tOFFSET {fmt(e)}",
                        f"{pad}\t}}"])
        out.append(f"{pad}}}")

    emit(0, 0)
    out += ["MOTION", f"Frames: {len(bvh.motion)}", f"Frame Time: {bvh.frame_time:.6f}"]
    out += [fmt(row) for row in bvh.motion]
    Path(path).write_text("\n".join(out) + "\n")

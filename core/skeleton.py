"""The body: a tree of joints, each a hinge, a ball or fixed, with one ellipsoid per segment.

Frames and units. The reference frame is the rest pose, in which every joint frame is aligned
with the world (as in BVH); lengths are in the skeleton's own units (a BVH's). A joint's local
rotation R_j turns its subtree about its rest position p_j, so the motion of segment k is the
product of exponentials of paper eq. 23,

.. math:: g_k = T(x_0) R_0 T(-p_0) \\prod_{j \\in chain(k)} e^{\\hat\\xi_j \\theta_j},
          \\qquad \\xi_j = (-\\omega_j \\times p_j, \\omega_j),

with M_j = g_j T(p_j) the world frame of joint j. A tracked hinge adds one degree of freedom
about a unit axis in the joint's local frame (R_j <- R_j exp(d a)); a ball adds three, about its
local x, y, z axes; a fixed joint keeps its initial rotation.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np

from . import se3
from .bvh import BvhFile

BALL, HINGE, FIXED = "ball", "hinge", "fixed"
# default blobs (``Skeleton.default_blobs``): short radii in parts of a bone's length
# (LENGTH_RADIUS), the rest in parts of the body's height
LENGTH_RADIUS = 0.16
MIN_RADIUS = 0.022  # any bone's least radius
MIN_LENGTH = 0.03  # a shorter bone gets no blob
TRUNK_RADIUS = 0.065  # a trunk bone's least radius: an adult's, as the human template has it
GIRDLE_LENGTH = 0.12  # a bone from the trunk shorter than this is the trunk's
LIMB_REACH = 0.25  # end sites this near a joint all its subtree is near are one limb's


@dataclass
class Ellipsoid:
    """A blob rigidly attached to the segment moved by ``joint``, in the reference frame.

    Points x with |diag(1/radii) Q^T (x - centre)| = 1; Q's columns are the blob's axes.
    """

    joint: int
    name: str
    centre: np.ndarray
    radii: np.ndarray
    Q: np.ndarray


@dataclass
class Skeleton:
    """Joints in topological order (parents first); ``parents[0] == -1`` is the root."""

    names: list[str]
    parents: np.ndarray
    offsets: np.ndarray  # (J, 3) offset from the parent's rest position
    kinds: list[str] = field(default_factory=list)
    axes: np.ndarray | None = None  # (J, 3) hinge axes in the joint's local frame
    end_sites: list[list[np.ndarray]] = field(default_factory=list)
    blobs: list[Ellipsoid] = field(default_factory=list)
    limits: np.ndarray | None = None  # (J, 2) hinge angle range, radians (-inf, inf: free)
    hinge_zero: np.ndarray | None = None  # (J, 3, 3) local rotation where a hinge's angle is 0

    def __post_init__(self):
        J = len(self.names)
        self.parents = np.asarray(self.parents, dtype=int)
        self.offsets = np.asarray(self.offsets, dtype=float).reshape(J, 3)
        if not self.kinds:
            self.kinds = [FIXED] * J
        if self.axes is None:
            self.axes = np.tile([1.0, 0.0, 0.0], (J, 1))
        if self.limits is None:
            self.limits = np.tile([-np.inf, np.inf], (J, 1))
        if self.hinge_zero is None:
            self.hinge_zero = np.tile(np.eye(3), (J, 1, 1))
        if not self.end_sites:
            self.end_sites = [[] for _ in range(J)]
        for j, p in enumerate(self.parents):
            if j == 0 and p != -1 or j > 0 and not 0 <= p < j:
                raise ValueError(f"joint '{self.names[j]}': parents must come before children")
        self.rest_positions = np.zeros((J, 3))
        for j in range(J):
            base = self.rest_positions[self.parents[j]] if j else 0.0
            self.rest_positions[j] = base + self.offsets[j]
        self._moved_by = np.zeros((J, J), dtype=bool)
        for m in range(J):
            self._moved_by[m, self.ancestors(m)] = True
        self._moved_by.setflags(write=False)
        depth = np.zeros(J, dtype=int)
        for j in range(1, J):
            depth[j] = depth[self.parents[j]] + 1
        # the joints below the root by their number of ancestors, with their parents: each
        # generation's frames follow from the one before's at once
        self._generations = [(js, self.parents[js]) for js in
                             (np.flatnonzero(depth == d) for d in range(1, depth.max() + 1))]
        self._dofs = None

    @property
    def n_joints(self) -> int:
        return len(self.names)

    def index(self, name: str) -> int:
        try:
            return self.names.index(name)
        except ValueError:
            raise KeyError(
                f"no joint named '{name}'; the skeleton has: {', '.join(self.names)}"
            ) from None

    def children(self, j: int) -> list[int]:
        return [int(c) for c in np.flatnonzero(self.parents == j)]

    def ancestors(self, j: int) -> list[int]:
        """j and its ancestors up to the root, j first."""
        out = []
        while j >= 0:
            out.append(j)
            j = int(self.parents[j])
        return out

    def height(self) -> float:
        """Largest extent of the rest pose (joints and end sites), a size for default radii."""
        pts = [self.rest_positions]
        for j, ends in enumerate(self.end_sites):
            pts += [self.rest_positions[j] + e for e in ends]
        P = np.vstack(pts)
        return float(np.max(P.max(0) - P.min(0)))

    # --- degrees of freedom -------------------------------------------------------------
    def bone_frame(self, j: int) -> np.ndarray:
        """Rows: unit bone direction (toward the first child or end site that is away from the
        joint, else local x) and two perpendiculars, in the joint's local frame."""
        tips = [self.offsets[c] for c in self.children(j)] + list(self.end_sites[j])
        tips = [t for t in tips if np.linalg.norm(t) > 1e-9]
        return se3.frame_along(tips[0] if tips else np.array([1.0, 0, 0]))

    def dof_joints_and_axes(self) -> tuple[np.ndarray, np.ndarray]:
        """Per degree of freedom: its joint and unit axis in the joint's local frame. A ball's
        three are its twist about the bone, then two swings across it (``bone_frame``).
        Read-only arrays, recomputed only when ``kinds`` or ``axes`` change."""
        key = (tuple(self.kinds), np.asarray(self.axes, dtype=float).tobytes())
        if self._dofs is None or self._dofs[0] != key:
            joints, axes = self._compute_dofs()
            joints.setflags(write=False)
            axes.setflags(write=False)
            self._dofs = (key, (joints, axes))
        return self._dofs[1]

    def _compute_dofs(self) -> tuple[np.ndarray, np.ndarray]:
        joints, axes = [], []
        for j, kind in enumerate(self.kinds):
            if kind == BALL:
                joints += [j, j, j]
                axes += list(self.bone_frame(j))
            elif kind == HINGE:
                a = np.asarray(self.axes[j], dtype=float)
                joints.append(j)
                axes.append(a / np.linalg.norm(a))
        return np.array(joints, dtype=int), np.array(axes, dtype=float).reshape(-1, 3)

    def limit_hinges(self, ranges_deg: dict[str, tuple[float, float]]) -> None:
        """Set the named hinges' ranges (name -> (lowest, highest) angle, degrees)."""
        for name, range_deg in ranges_deg.items():
            self.limits[self.index(name)] = np.radians(range_deg)

    def limited_hinge(self, j: int) -> bool:
        """Whether joint j is a hinge with a finite limit on either side."""
        return self.kinds[j] == HINGE and bool(np.any(np.isfinite(self.limits[j])))

    def hinge_angle(self, j: int, rotation: np.ndarray) -> float:
        """Hinge j's angle in a local rotation: the rotation vector from ``hinge_zero`` (the
        BVH's rest pose, unless side-on made the hinge) along the axis, radians: the
        quantity ``limits`` bound."""
        return float(se3.log_so3(self.hinge_zero[j].T @ rotation) @ self.axes[j])

    def hinge_turns(self, j: int, rotation: np.ndarray) -> tuple[float, float]:
        """The turns (radians, from ``rotation``) that hinge j may make: those that end
        within its limits, or no farther out of them than it already is."""
        theta = self.hinge_angle(j, rotation)
        lo, hi = self.limits[j]
        return min(lo, theta) - theta, max(hi, theta) - theta

    def within_limits(self, j: int, rotation: np.ndarray) -> bool:
        """Whether hinge j's angle in local ``rotation`` lies within its limits."""
        lo, hi = self.limits[j]
        return bool(lo <= self.hinge_angle(j, rotation) <= hi)

    def outside_limits(self, rotations: np.ndarray) -> list[str]:
        """The limited hinges that ``rotations`` (J, 3, 3) bend outside their limits."""
        return [self.names[j] for j in range(self.n_joints)
                if self.limited_hinge(j) and not self.within_limits(j, rotations[j])]

    def untwisted(self, rotations: np.ndarray) -> np.ndarray:
        """``rotations`` (J, 3, 3), a copy, with each limited hinge that is bent outside its
        limits under a parent ball twisted over a quarter turn about the bone between them
        turned back: the parent turned half a turn about that bone and the hinge bent the
        other way. A thigh twisted half a turn over a knee bent forward puts every joint and
        blob where the untwisted thigh over the knee bent backward does (clicks cannot tell
        them apart), but only the second is within the knee's limits, and a tracked hinge
        outside its limits can only straighten. Kept only where the hinge ends within its
        limits and every joint, end site and blob stays where it was."""
        out = np.array(rotations, float)
        for j in range(self.n_joints):
            p = int(self.parents[j])
            if not self.limited_hinge(j) or p < 0 or self.kinds[p] != BALL:
                continue
            if self.within_limits(j, out[j]):
                continue
            bone = self.offsets[j] / max(float(np.linalg.norm(self.offsets[j])), 1e-12)
            if abs(twist_about(out[p], bone)) <= np.pi / 2:
                continue  # turning it half a turn would twist the parent more, not less
            half = se3.exp_so3(np.pi * bone)  # half a turn about the bone, in p's frame
            cand = out.copy()
            cand[p] = out[p] @ half
            cand[j] = half.T @ out[j] @ half
            for c in self.children(j):
                cand[c] = half.T @ out[c]
            if self.within_limits(j, cand[j]) and self.same_body(out, cand):
                out = cand
        return out

    def same_body(self, a: np.ndarray, b: np.ndarray, tol: float = 1e-9) -> bool:
        """Whether local rotations ``a`` and ``b`` (J, 3, 3) put every joint, end site and
        blob (its centre and its shape) in the same place, to ``tol`` of the body's height."""
        places = []
        for R in (a, b):
            M = self.joint_frames(R, np.zeros(3))
            g = self.segment_motions(M)
            ends = [M[j, :3, :3] @ e + M[j, :3, 3] for j, es in enumerate(self.end_sites)
                    for e in es]
            # each blob's centre, and its quadric's matrix scaled by its least radius squared
            blobs = [np.concatenate([g[b.joint, :3, :3] @ b.centre + g[b.joint, :3, 3], (
                g[b.joint, :3, :3] @ b.Q @ np.diag((b.radii.min() / b.radii) ** 2) @ b.Q.T
                @ g[b.joint, :3, :3].T).ravel()]) for b in self.blobs]
            places.append(np.concatenate([M[:, :3, 3].ravel(), np.ravel(ends)] + blobs))
        return bool(np.allclose(places[0], places[1], rtol=0, atol=tol * self.height()))

    def tracked_joint_names(self) -> list[str]:
        """Names of the joints that turn (ball or hinge), parents first."""
        return [n for n, kind in zip(self.names, self.kinds) if kind in (BALL, HINGE)]

    def dof_names(self) -> list[str]:
        names = []
        for j, kind in enumerate(self.kinds):
            if kind == BALL:
                names += [f"{self.names[j]}.{c}" for c in ("twist", "swing1", "swing2")]
            elif kind == HINGE:
                names.append(self.names[j])
        return names

    def moved_by(self) -> np.ndarray:
        """Boolean (J, J), read-only: ``[m, j]`` is True when joint j's rotation moves joint
        m's segment."""
        return self._moved_by

    # --- forward kinematics --------------------------------------------------------------
    def joint_frames(self, rotations: np.ndarray, root_position: np.ndarray,
                     offsets: np.ndarray | None = None) -> np.ndarray:
        """World frames M_j (J, 4, 4) of every joint for local rotations (J, 3, 3); with
        ``offsets`` (J, 3), of the same hierarchy with those bone offsets instead."""
        offsets = self.offsets if offsets is None else offsets
        # rotations and positions apart, gathered with take: a third of the time of indexing
        # the (J, 4, 4) stack
        R, p = np.empty((self.n_joints, 3, 3)), np.empty((self.n_joints, 3))
        R[0], p[0] = rotations[0], root_position
        for js, ps in self._generations:
            turn = R.take(ps, 0)
            R[js] = turn @ rotations.take(js, 0)
            p[js] = (turn @ offsets.take(js, 0)[:, :, None])[..., 0] + p.take(ps, 0)
        M = np.zeros((self.n_joints, 4, 4))
        M[:, :3, :3], M[:, :3, 3], M[:, 3, 3] = R, p, 1.0
        return M

    def segment_motions(self, frames: np.ndarray) -> np.ndarray:
        """g_j = M_j T(-p_j) (J, 4, 4): reference-frame points of segment j to the world."""
        g = frames.copy()
        g[:, :3, 3] -= np.einsum("jab,jb->ja", frames[:, :3, :3], self.rest_positions)
        return g

    def world_positions(self, rotations: np.ndarray, root_position: np.ndarray,
                        offsets: np.ndarray | None = None) -> np.ndarray:
        """World positions of every joint (J, 3) (``joint_frames``)."""
        return self.joint_frames(rotations, root_position, offsets)[:, :3, 3]

    # --- blobs ------------------------------------------------------------------------
    def default_blobs(self) -> list[Ellipsoid]:
        """One ellipsoid per bone (joint to child or end site) long enough to see: long radius
        half the bone, short radii ``blob_radii``'s; bones shorter than ``MIN_LENGTH`` of
        the height get none."""
        H = self.height()
        tips = [[self.offsets[c] for c in self.children(j)] + list(self.end_sites[j])
                for j in range(self.n_joints)]
        bones = [(j, k, d) for j, ds in enumerate(tips) for k, d in enumerate(ds)
                 if np.linalg.norm(d) >= MIN_LENGTH * H]
        radii = self.blob_radii([(j, d) for j, _, d in bones])
        return [bone_blob(j, self.names[j] if len(tips[j]) == 1 else f"{self.names[j]}.{k}",
                          self.rest_positions[j], d, r)
                for (j, k, d), r in zip(bones, radii)]

    def blob_radii(self, bones: list[tuple[int, np.ndarray]]) -> np.ndarray:
        """The default short radius of each bone (joint j, the vector d from it to the bone's
        tip): ``LENGTH_RADIUS`` of its length, ``MIN_RADIUS`` of the body's height at
        least. The trunk is the body's widest part, but a capture cuts it into short bones
        (a spine of three or four, a pelvis and a shoulder girdle of a bone a side), which
        that rule makes rods, and foreground the rods leave uncovered lures the arms onto
        the trunk: a trunk bone, of a joint three or more limbs hang from
        (``limbs_below``) or a short one (under ``GIRDLE_LENGTH`` of the height) from such
        a joint to a limb (a pelvis's or shoulder girdle's half, the neck's base), is
        ``TRUNK_RADIUS`` of the height at least."""
        H, limbs = self.height(), self.limbs_below()
        out = np.empty(len(bones))
        for i, (j, d) in enumerate(bones):
            L, p = float(np.linalg.norm(d)), self.parents[j]
            trunk = limbs[j] >= 3 or (p >= 0 and limbs[p] >= 3 and L < GIRDLE_LENGTH * H)
            out[i] = max(LENGTH_RADIUS * L, (TRUNK_RADIUS if trunk else MIN_RADIUS) * H)
        return out

    def limbs_below(self) -> np.ndarray:
        """Per joint, how many limbs hang from it: the end sites of its subtree grouped, one
        group for every end site reached within ``LIMB_REACH`` of the height of a joint all
        of whose subtree is that near (a hand's fingers, a foot's toe and heel are one)."""
        near = LIMB_REACH * self.height()
        J = self.n_joints
        reach, limbs = np.zeros(J), np.zeros(J, int)
        for j in reversed(range(J)):  # children after their parents: the deepest first
            kids = self.children(j)
            ends = [float(np.linalg.norm(e)) for e in self.end_sites[j]]
            reach[j] = max([reach[c] + float(np.linalg.norm(self.offsets[c])) for c in kids]
                           + ends, default=0.0)
            limbs[j] = 1 if reach[j] <= near else sum(limbs[c] for c in kids) + len(ends)
        return limbs


def bone_blob(joint: int, name: str, head: np.ndarray, direction: np.ndarray, r) -> Ellipsoid:
    """Ellipsoid along a bone from head to head + direction with short radii r (or (r1, r2))."""
    L = float(np.linalg.norm(direction))
    r1, r2 = np.broadcast_to(np.asarray(r, dtype=float), (2,))
    return Ellipsoid(
        joint, name, head + direction / 2, np.array([L / 2, r1, r2]), se3.frame_along(direction).T
    )


def skeleton_from_bvh(bvh: BvhFile) -> Skeleton:
    """Hierarchy, offsets and end sites of a BVH file; every joint fixed, no blobs yet."""
    return Skeleton(
        names=bvh.names,
        parents=[j.parent for j in bvh.joints],
        offsets=np.array([j.offset for j in bvh.joints]),
        end_sites=[list(j.end_sites) for j in bvh.joints],
    )


def twist_about(R: np.ndarray, axis: np.ndarray) -> float:
    """The angle (radians, in [-pi, pi]) of rotation R's twist about the unit ``axis``: R is
    a swing that moves the axis after that twist (the swing-twist split)."""
    r = se3.log_so3(R)  # angle times unit axis: the quaternion (cos(a/2), sin(a/2) n)
    angle = float(np.linalg.norm(r))
    along = float(r @ axis) / angle if angle > 1e-12 else 0.0
    return float(2 * np.arctan2(np.sin(angle / 2) * along, np.cos(angle / 2)))


MIN_BEND = 10.0  # degrees a bone must be bent from its rest direction to show its hinge


def bend_hinge(direction: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, float]:
    """The hinge that bends a bone as its joint's rotation ``R`` does: the unit axis normal
    to the bone's rest ``direction`` and its turned one ``R @ direction`` (so across the
    bone), and the angle (radians, in (0, pi)) about that axis from the one to the other; a
    twist about the bone, which a hinge cannot hold, is left out. For a limb straight at
    rest it is the normal of the plane the limb bends in. ValueError where the bone is
    turned less than ``MIN_BEND`` degrees from its rest direction (or right round): no
    plane shows the axis."""
    d = np.asarray(direction, float) / np.linalg.norm(direction)
    turned = R @ d
    normal = np.cross(d, turned)
    angle = float(np.arctan2(np.linalg.norm(normal), d @ turned))
    if not np.radians(MIN_BEND) <= angle <= np.pi - np.radians(MIN_BEND):
        raise ValueError(f"bent {np.degrees(angle):.0f} degrees from its rest direction, "
                         f"under {MIN_BEND:g}: no bend shows its axis")
    return normal / np.linalg.norm(normal), angle


# --- templates -------------------------------------------------------------------------
def _build(spec, end_sites=None, limits=None) -> Skeleton:
    """A template from its joints (name, parent, offset, kind[, axis]), end sites and hinge
    ``limits`` (name -> (lowest, highest) angle in degrees)."""
    names = [s[0] for s in spec]
    parents = [names.index(s[1]) if s[1] else -1 for s in spec]
    sk = Skeleton(
        names=names,
        parents=parents,
        offsets=[s[2] for s in spec],
        kinds=[s[3] for s in spec],
        axes=np.array([s[4] if len(s) > 4 else (1, 0, 0) for s in spec], dtype=float),
        end_sites=[[np.asarray(e, float)] if e is not None else [] for e in end_sites]
        if end_sites
        else None,
    )
    sk.limit_hinges(limits or {})
    sk.blobs = sk.default_blobs()
    return sk


def human_template(lower_back: bool = False) -> Skeleton:
    """The paper's 19-DOF human, metres, y up, facing +z: 3-DOF hips, shoulders and neck,
    1-DOF knees and elbows (flexion about local x), each limited to bend one way as anatomy
    has it (knees 0 to 160 degrees, elbows -160 to 0). With ``lower_back`` the spine is a
    ball too (22 DOF), so that the pelvis may turn against the chest as a walker's does."""
    spec = [
        ("Hips", None, (0, 0.95, 0), FIXED),
        ("Spine", "Hips", (0, 0.1, 0), BALL if lower_back else FIXED),
        ("Chest", "Spine", (0, 0.3, 0), FIXED),
        ("Neck", "Chest", (0, 0.15, 0), BALL),
        ("LeftShoulder", "Chest", (0.18, 0.1, 0), BALL),
        ("LeftElbow", "LeftShoulder", (0, -0.28, 0), HINGE, (1, 0, 0)),
        ("RightShoulder", "Chest", (-0.18, 0.1, 0), BALL),
        ("RightElbow", "RightShoulder", (0, -0.28, 0), HINGE, (1, 0, 0)),
        ("LeftHip", "Hips", (0.09, -0.05, 0), BALL),
        ("LeftKnee", "LeftHip", (0, -0.42, 0), HINGE, (1, 0, 0)),
        ("RightHip", "Hips", (-0.09, -0.05, 0), BALL),
        ("RightKnee", "RightHip", (0, -0.42, 0), HINGE, (1, 0, 0)),
    ]
    ends = [None, None, None, (0, 0.25, 0), None, (0, -0.27, 0), None, (0, -0.27, 0), None,
            (0, -0.43, 0), None, (0, -0.43, 0)]
    # a knee turning +x swings its shank backward, an elbow turning -x its forearm forward
    bends = {"LeftKnee": (0, 160), "RightKnee": (0, 160), "LeftElbow": (-160, 0),
             "RightElbow": (-160, 0)}
    sk = _build(spec, ends, bends)
    # an adult's widths (metres), in place of the length-based defaults
    radius = {"Hips": 0.13, "Spine": 0.13, "Chest": 0.11, "Neck": 0.09, "LeftShoulder": 0.045,
              "RightShoulder": 0.045, "LeftElbow": 0.04, "RightElbow": 0.04, "LeftHip": 0.08,
              "RightHip": 0.08, "LeftKnee": 0.055, "RightKnee": 0.055}
    for b in sk.blobs:
        b.radii[1:] = radius[sk.names[b.joint]]
    return sk


def walker_template() -> Skeleton:
    """A 6-DOF frontoparallel walker seen from its side (+x is forward, y up, z toward the
    camera): hinges at hips, knees and ankles, all about z; the knees bend backward only
    (-160 to 0 degrees: turning +z swings a shank forward)."""
    z = (0, 0, 1)
    spec = [
        ("Hips", None, (0, 0.95, 0), FIXED),
        ("Torso", "Hips", (0, 0.05, 0), FIXED),
        ("LeftHip", "Hips", (0, -0.05, 0.09), HINGE, z),
        ("LeftKnee", "LeftHip", (0, -0.42, 0), HINGE, z),
        ("LeftAnkle", "LeftKnee", (0, -0.43, 0), HINGE, z),
        ("RightHip", "Hips", (0, -0.05, -0.09), HINGE, z),
        ("RightKnee", "RightHip", (0, -0.42, 0), HINGE, z),
        ("RightAnkle", "RightKnee", (0, -0.43, 0), HINGE, z),
    ]
    ends = [None, (0, 0.6, 0), None, None, (0.2, -0.05, 0), None, None, (0.2, -0.05, 0)]
    return _build(spec, ends, {"LeftKnee": (-160, 0), "RightKnee": (-160, 0)})


def planar_chain_template(lengths=(0.5, 0.4, 0.3), axis=(0, 0, 1)) -> Skeleton:
    """A chain along +x whose hinges all turn about ``axis`` (the view direction), for a limb
    or an animal seen from the side."""
    spec = [("Base", None, (0, 0, 0), FIXED)]
    for i in range(len(lengths)):
        parent = spec[-1][0]
        offset = (lengths[i - 1], 0, 0) if i else (0, 0, 0)
        spec.append((f"Link{i + 1}", parent, offset, HINGE, axis))
    ends = [None] * len(lengths) + [(lengths[-1], 0, 0)]
    return _build(spec, ends)


# degrees a planar quadruped's joints turn either way from the pose they stand in (the
# template's, or one posed over a first frame): a head and neck nod, a leg's bones swing
# through a gallop's stride; none folds up onto the trunk or turns the head over
QUADRUPED_REACH = {"Neck": 45.0, "Head": 45.0, "Upper": 75.0, "Lower": 75.0}


def quadruped_limits(names: Sequence[str]) -> dict[str, tuple[float, float]]:
    """Hinge ranges (degrees, name -> (lowest, highest)) of ``QUADRUPED_REACH`` for those of
    ``names`` that end in its keys: a planar quadruped's neck, head and legs."""
    return {n: (-r, r) for n in names for k, r in QUADRUPED_REACH.items() if n.endswith(k)}


def planar_quadruped_template() -> Skeleton:
    """A horse-like body seen from its side (+x forward, y up, z toward the camera): a rigid
    trunk from rump to chest (its joint at the rump) carrying neck and head and four
    two-segment legs, every joint a hinge about z within ``quadruped_limits`` of this
    standing pose."""
    z = (0, 0, 1)
    spec = [
        ("Trunk", None, (-0.8, 1.3, 0), FIXED),
        ("Neck", "Trunk", (1.6, 0.1, 0), HINGE, z),
        ("Head", "Neck", (0.45, 0.45, 0), HINGE, z),
    ]
    ends = [None, None, (0.35, -0.35, 0)]
    for side, dz in (("Left", 0.15), ("Right", -0.15)):
        for end, x in (("Fore", 1.5), ("Hind", 0.1)):
            top, low = f"{side}{end}Upper", f"{side}{end}Lower"
            spec += [(top, "Trunk", (x, -0.15, dz), HINGE, z),
                     (low, top, (0, -0.55, 0), HINGE, z)]
            ends += [None, (0, -0.55, 0)]
    sk = _build(spec, ends, quadruped_limits([s[0] for s in spec]))
    sk.blobs = [bone_blob(0, "Trunk", sk.rest_positions[0] - (0.05, 0, 0),
                          sk.offsets[1] + (0.1, 0, 0), (0.33, 0.25))]
    sk.blobs += [b for b in sk.default_blobs() if b.joint != 0]
    return sk


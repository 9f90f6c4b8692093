"""How far a tracked armature's legs are from the rendered walk's capture."""

from pathlib import Path

import numpy as np

LEGS = [("LeftHip", "LeftKnee"), ("RightHip", "RightKnee"), ("LeftKnee", "LeftAnkle"),
        ("RightKnee", "RightAnkle")]


def leg_errors(scene, bridge, arm, folder: Path, frames) -> np.ndarray:
    """(frames, 4): degrees between the keyed and the captured (folder/truth.bvh) thighs and
    shanks on each scene frame of ``frames`` (scene frame f shows capture frame f - 1)."""
    from core import se3
    from core.bvh import read_bvh
    from core.skeleton import skeleton_from_bvh

    sk = bridge.skeleton_from_armature(arm)
    truth = read_bvh(folder / "truth.bvh")
    truth_sk = skeleton_from_bvh(truth)
    R_true, p_true = truth.poses()
    out = []
    for f in frames:
        scene.frame_set(f)
        got = sk.world_positions(*bridge.pose_from_armature(arm, sk))
        want = dict(zip(truth.names, truth_sk.world_positions(R_true[f - 1], p_true[f - 1])))
        out.append([np.degrees(se3.angle_between_vectors(
            got[sk.index(b)] - got[sk.index(a)], want[b] - want[a])) for a, b in LEGS])
    return np.array(out)

"""A template human walking on the spot and forward, keyed the way Track keys (GENERATED
keys on the tracked channels): material for the cycle and body tests."""

import numpy as np

PERIOD = 24.5  # frames per gait cycle


def walking_template(bpy, registered, frames=70):
    from core import se3

    bpy.ops.twist.add_template_armature(template="HUMAN")
    scene = bpy.context.scene
    arm = scene.twist.armature
    tw = registered.twist_addon
    sk = tw.bridge.skeleton_from_armature(arm)
    R0, root0 = tw.bridge.pose_from_armature(arm, sk)
    for f in range(1, frames + 1):
        phase = 2 * np.pi * f / PERIOD
        R = R0.copy()
        for name, sign in (("LeftHip", 1), ("RightHip", -1)):  # swing and sideways sway
            R[sk.index(name)] = se3.exp_so3(np.array([0.5 * sign * np.sin(phase),
                                                      0.1 * np.cos(phase), 0]))
        for name, shift in (("LeftKnee", 0.0), ("RightKnee", np.pi)):
            j = sk.index(name)
            R[j] = se3.exp_so3(sk.axes[j] * (0.6 + 0.5 * np.sin(phase + shift)))
        # walks toward -y (world axes, z up), bobbing and swaying
        root = root0 + np.array([0.02 * np.sin(phase), -0.05 * f, 0.03 * np.sin(2 * phase)])
        tw.keyframes.write_pose(arm, sk, f, R, root)
    scene.frame_start, scene.frame_end = 1, frames
    return scene, arm

"""Named example poses (SMPL joint order) for renders, tests and the simulator.

Angles are local joint rotations in degrees in SMPL's canonical axes (x: the person's
left, y: up, z: forward), where at rest every joint frame is aligned with them:
a hip rotation of −90° about x lifts the thigh forward, +x at the knee bends it,
+x at a spine joint leans forward, −z at the left shoulder lowers the left arm.
``pose_aa`` returns (72,) axis-angle with the global orientation that puts the
canonical body into the carpet frame (Z up): +90° about x for upright poses.
"""

from __future__ import annotations

import numpy as np

from edge.body.model import SMPL_JOINT_NAMES
from edge.body.rotations import euler_xyz_deg_to_axis_angle

_UPRIGHT = (90.0, 0.0, 0.0)  # canonical Y-up → carpet Z-up, facing −y

# name → (global orientation in degrees about x (applied after upright), {joint: (x,y,z) degrees})
POSES: dict[str, tuple[tuple[float, float, float], dict[str, tuple[float, float, float]]]] = {
    "t_pose": (_UPRIGHT, {}),
    "deep_squat": (
        (110.0, 0.0, 0.0),  # pelvis tipped 20° forward
        {
            "left_hip": (-115.0, 0.0, -10.0), "right_hip": (-115.0, 0.0, 10.0),
            "left_knee": (140.0, 0.0, 0.0), "right_knee": (140.0, 0.0, 0.0),
            "left_ankle": (-45.0, 0.0, 0.0), "right_ankle": (-45.0, 0.0, 0.0),
            "spine1": (10.0, 0.0, 0.0), "spine2": (5.0, 0.0, 0.0),
            "left_shoulder": (0.0, -75.0, 0.0), "right_shoulder": (0.0, 75.0, 0.0),
            "neck": (-15.0, 0.0, 0.0),
        },
    ),
    "lunge": (
        _UPRIGHT,
        {
            "left_hip": (-85.0, 0.0, 0.0), "left_knee": (85.0, 0.0, 0.0),
            "right_hip": (25.0, 0.0, 0.0), "right_knee": (75.0, 0.0, 0.0), "right_ankle": (-10.0, 0.0, 0.0),
            "left_shoulder": (0.0, 0.0, -75.0), "right_shoulder": (0.0, 0.0, 75.0),
            "left_elbow": (0.0, -20.0, 0.0), "right_elbow": (0.0, 20.0, 0.0),
        },
    ),
    "sitting_on_floor": (
        _UPRIGHT,
        {
            "left_hip": (-90.0, 0.0, -5.0), "right_hip": (-90.0, 0.0, 5.0),
            "spine1": (5.0, 0.0, 0.0),
            "left_shoulder": (0.0, -20.0, -50.0), "right_shoulder": (0.0, 20.0, 50.0),
        },
    ),
    "push_up_plank": (
        (156.0, 0.0, 0.0),  # face down, head toward −y and 24° up (feet on the floor)
        {
            "left_shoulder": (24.0, -90.0, 0.0), "right_shoulder": (24.0, 90.0, 0.0),  # arms vertical
            "left_ankle": (-10.0, 0.0, 0.0), "right_ankle": (-10.0, 0.0, 0.0),
            "neck": (-20.0, 0.0, 0.0),
        },
    ),
    "arms_raised": (
        _UPRIGHT,
        {
            "left_collar": (0.0, 0.0, 15.0), "right_collar": (0.0, 0.0, -15.0),
            "left_shoulder": (0.0, 0.0, 65.0), "right_shoulder": (0.0, 0.0, -65.0),
        },
    ),
}


def pose_aa(name: str) -> np.ndarray:
    """The named pose as (72,) axis-angle in radians, global orientation included."""
    if name not in POSES:
        raise ValueError(f"unknown pose {name!r}; known: {', '.join(POSES)}")
    orient, joints = POSES[name]
    out = np.zeros((len(SMPL_JOINT_NAMES), 3))
    out[0] = euler_xyz_deg_to_axis_angle(np.asarray(orient))
    for joint, deg in joints.items():
        out[SMPL_JOINT_NAMES.index(joint)] = euler_xyz_deg_to_axis_angle(np.asarray(deg))
    return out.reshape(-1)

"""Grounded example bodies for the contact tests, renders and benchmark.

The named poses of ``edge.body.poses`` plus a variant that puts the intended
supports on the floor (the named poses are drawing examples, not balanced stances):

* ``push_up_flat_hands``: the plank with the wrists extended 90° (palms flat) and the
  body pitched so that palms and toes touch the floor together (the named plank rests
  on its fingertips).

The named ``lunge`` has no static balance: its rear foot hovers ~6 cm up and, even
with the rear foot put down, its COM lies outside the narrow diagonal support of a
wide-stance lunge; the contact model reports it (``balanced=False``).
"""

from __future__ import annotations

import numpy as np

from edge.body.poses import POSES, pose_aa
from edge.body.rotations import euler_xyz_deg_to_axis_angle

VARIANTS = ("push_up_flat_hands",)
SCENE_POSES = tuple(POSES) + VARIANTS


def _joint(model, name):
    return list(model.joint_names).index(name)


def _bisect(gap, lo, hi, iters=30):
    g_lo = gap(lo)
    for _ in range(iters):
        mid = 0.5 * (lo + hi)
        g = gap(mid)
        if (g > 0) == (g_lo > 0):
            lo, g_lo = mid, g
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _part(model, joints):
    return np.asarray(model.arrays.weights)[:, [_joint(model, j) for j in joints]].sum(1) > 0.5


def scene_pose(model, name: str) -> np.ndarray:
    """(72,) axis-angle of a named pose or variant (see module doc)."""
    if name in POSES:
        return pose_aa(name)
    if name == "push_up_flat_hands":
        hands = _part(model, ["left_wrist", "right_wrist", "left_hand", "right_hand"])

        def make(theta):
            p = pose_aa("push_up_plank").reshape(-1, 3).copy()
            p[0] = euler_xyz_deg_to_axis_angle((theta, 0.0, 0.0))
            p[_joint(model, "left_wrist")] = euler_xyz_deg_to_axis_angle((0.0, 0.0, 90.0))
            p[_joint(model, "right_wrist")] = euler_xyz_deg_to_axis_angle((0.0, 0.0, -90.0))
            return p.reshape(-1)

        def gap(theta):
            v = model.forward(make(theta), None, np.zeros(3), vertices=True)["vertices"][0]
            return float(v[hands, 2].min() - v[~hands, 2].min())

        return make(_bisect(gap, 150.0, 180.0))
    raise ValueError(f"unknown scene pose {name!r}; known: {', '.join(SCENE_POSES)}")


def grounded_vertices(model, pose, betas=None, xy_m=(0.9, 0.9), yaw_deg: float = 0.0, sink_m: float = 0.0):
    """Vertices (V,3) float64 of ``pose`` turned by yaw about the vertical, moved so the
    pelvis is over xy_m and the lowest vertex at z = −sink_m."""
    from edge.body.rotations import axis_angle_to_matrix, matrix_to_axis_angle

    p = np.asarray(pose, dtype=np.float64).reshape(-1).copy()
    if yaw_deg:
        r = axis_angle_to_matrix(np.array([0.0, 0.0, np.radians(yaw_deg)])) @ axis_angle_to_matrix(p[:3])
        p[:3] = matrix_to_axis_angle(r)
    b = None if betas is None else np.asarray(betas, dtype=np.float64).reshape(1, -1)
    v = model.forward(p, b, np.zeros(3), vertices=True)["vertices"][0].astype(np.float64)
    return v + np.array([xy_m[0], xy_m[1], -v[:, 2].min() - sink_m])

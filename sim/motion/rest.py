"""A body coming to rest on the floor: where a lying or sitting pose ends up when its muscles let go.

    q = settle(SUPINE, model, betas)       # (24,3) Euler degrees, SMPL canonical axes, as sim.motion.keys poses

Two steps, both lowering the centre of mass (the segment mass model of sim.contact) above the
body's lowest point, which is the floor:

1. Rigid rest: the whole pose tilted by up to 45° about both horizontal axes (a 5° grid, then 1°).
   A rigid body settles where its centre of mass lies lowest, on three or more supports around it.
2. Limp relaxation: the spine, neck, hips, knees, shoulders and elbows give way by up to 30° each
   (knees and elbows only bend further), each degree of freedom resisted by a joint stiffness
   (``STIFFNESS_M_PER_RAD2``: a turn of θ radians costs as much as raising the centre of mass by
   k·θ² metres), minimised by Powell's method from the rigid rest. The trunk then lies on the floor
   instead of bridging between a shoulder and a knee, as a body lying still does.

The result is cached per pose, shape and body model (hundreds to a few thousand forward passes, 0.2–2 s).
"""

from __future__ import annotations

import numpy as np
from scipy.optimize import minimize
from scipy.spatial.transform import Rotation

from edge.body.rotations import euler_xyz_deg_to_matrix, matrix_to_axis_angle
from sim.motion.generate import body_model
from sim.motion.rig import UPRIGHT, J, axis_rotation, rot_x

TILT_DEG = 45.0  # how far from the scripted posture a body may roll or tip as it comes to rest
TURN_M_PER_DEG = 0.0004  # a rigid turn costs ~1 cm of height per 25°: no turn for nothing
GIVE_DEG = 30.0  # how far a joint gives way
STIFFNESS_M_PER_RAD2 = 0.1  # 15° of give costs 7 mm of height, 30° costs 27 mm
# (joint, Euler axis, sign it may move: 0 either way, +1/-1 only that way from where it is — a hinge that
# only bends further)
LIMP = (("spine1", 0, 0), ("spine1", 2, 0), ("spine2", 0, 0), ("spine2", 2, 0), ("spine3", 0, 0), ("spine3", 2, 0),
        ("neck", 0, 0), ("neck", 2, 0), ("left_hip", 0, 0), ("left_hip", 2, 0), ("right_hip", 0, 0), ("right_hip", 2, 0),
        ("left_knee", 0, 1), ("right_knee", 0, 1), ("left_shoulder", 1, 0), ("left_shoulder", 2, 0),
        ("right_shoulder", 1, 0), ("right_shoulder", 2, 0), ("left_elbow", 1, -1), ("right_elbow", 1, 1))

_SETTLED: dict[bytes, np.ndarray] = {}


def _tilt_matrix(tilt_deg: np.ndarray) -> np.ndarray:
    """(N,2) tilts about the world x then y axis, degrees → (N,3,3) = Ry·Rx."""
    t = np.radians(tilt_deg)
    return axis_rotation(np.array([0.0, 1.0, 0.0]), t[:, 1]) @ rot_x(t[:, 0])


def _tilted(p: np.ndarray, tilt_deg) -> np.ndarray:
    """The pose p with its root turned by a world tilt (about x, about y)."""
    out = p.copy()
    root = UPRIGHT.T @ _tilt_matrix(np.asarray(tilt_deg, float).reshape(1, 2))[0] @ UPRIGHT @ euler_xyz_deg_to_matrix(p[0])
    out[0] = Rotation.from_matrix(root).as_euler("XYZ", degrees=True)  # intrinsic: R = Rx·Ry·Rz
    return out


class _Heights:
    """The centre of mass above the lowest vertex for poses of one shape."""

    def __init__(self, body, betas):
        from sim.contact.segments import SegmentMassModel

        self.body, self.betas = body, betas
        self.mass = SegmentMassModel(body, betas)

    def posed(self, poses: np.ndarray):
        """(N,24,3) Euler degrees → vertices (N,V,3) and centres of mass (N,3), the pelvis at the origin."""
        local = euler_xyz_deg_to_matrix(poses)
        local[:, 0] = UPRIGHT @ local[:, 0]
        aa = matrix_to_axis_angle(local).reshape(len(poses), 72)
        v = self.body.forward(aa, self.betas, None, vertices=True)["vertices"]
        return v, self.mass.com_m(aa, np.zeros((len(poses), 3)))

    def __call__(self, poses: np.ndarray) -> np.ndarray:
        v, com = self.posed(poses)
        return com[:, 2] - v[:, :, 2].min(axis=1)


def _rigid_rest(p: np.ndarray, heights: _Heights) -> np.ndarray:
    v, com = heights.posed(p[None])
    v, com = v[0], com[0]

    def cost(tilt):  # the height after a tilt is the tilt's third row times a point
        up = _tilt_matrix(tilt)[:, 2]
        return up @ com - (v @ up.T).min(axis=0) + TURN_M_PER_DEG * np.abs(tilt).sum(axis=1)

    best = np.zeros(2)
    for step, half in ((5.0, TILT_DEG), (1.0, 5.0)):
        d = np.arange(-half, half + 1e-9, step)
        cand = np.stack(np.meshgrid(d + best[0], d + best[1], indexing="ij"), -1).reshape(-1, 2)
        cand = cand[np.abs(cand).max(axis=1) <= TILT_DEG]
        best = cand[int(np.argmin(cost(cand)))]
    return _tilted(p, best)


def _limp(p: np.ndarray, heights: _Heights) -> np.ndarray:
    rows = np.array([J[name] for name, _, _ in LIMP])
    cols = np.array([axis for _, axis, _ in LIMP])
    bounds = [(-GIVE_DEG if s <= 0 else 0.0, GIVE_DEG if s >= 0 else 0.0) for _, _, s in LIMP]
    k_per_deg2 = STIFFNESS_M_PER_RAD2 * np.radians(1.0) ** 2

    def pose_of(x):
        q = p.copy()
        q[rows, cols] += x  # every (joint, axis) of LIMP once
        return q

    def cost(x):
        return float(heights(pose_of(x)[None])[0] + k_per_deg2 * np.sum(np.square(x)))

    res = minimize(cost, np.zeros(len(LIMP)), method="Powell", bounds=bounds, options={"xtol": 0.5, "ftol": 1e-5, "maxfev": 4000})
    return pose_of(res.x)


def settle(p: np.ndarray, model=None, betas=None) -> np.ndarray:
    """The pose p (24,3) Euler degrees as it comes to rest on the floor (module doc); betas: the shape
    (default the mean shape)."""
    body = body_model(model)
    b = np.zeros(10) if betas is None else np.asarray(betas, np.float64).reshape(-1)
    key = p.tobytes() + b.tobytes() + str(id(body)).encode()
    if key not in _SETTLED:
        heights = _Heights(body, b)
        q = _limp(_rigid_rest(np.asarray(p, np.float64), heights), heights)
        _SETTLED[key] = _rigid_rest(q, heights)  # the limp body may rest on other supports: let it tip once more
    return _SETTLED[key].copy()

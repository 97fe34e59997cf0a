"""Rotations, forward kinematics, skinning and two-bone IK for one body shape.

Everything here is batched over frames (leading axis T) and float64. A ``Rig`` is the
body model evaluated for one shape (betas): its rest joints with the pelvis at the
origin, the vertex sets of the contact parts, FK, vertex heights and limb IK. The solver
that puts a posed sequence on the floor is ``sim.motion.ground.ground``.
"""

from __future__ import annotations

import numpy as np

from edge.body import SMPL_PARENTS, BodyModel, lbs
from edge.body.rotations import skew
from sim.motion.balance import foot_geometry

J = {name: i for i, name in enumerate((
    "pelvis", "left_hip", "right_hip", "spine1", "left_knee", "right_knee", "spine2",
    "left_ankle", "right_ankle", "spine3", "left_foot", "right_foot", "neck",
    "left_collar", "right_collar", "head", "left_shoulder", "right_shoulder",
    "left_elbow", "right_elbow", "left_wrist", "right_wrist", "left_hand", "right_hand",
))}

# Contact parts (columns of a contact schedule) and the joints whose vertices form them.
CONTACT_PARTS = ("left_foot", "right_foot", "left_hand", "right_hand", "buttocks", "back")
LF, RF, LH, RH, BUTT, BACK = range(6)
SETTLE = 6  # anchor code: the pelvis moves between resting on the feet and on the buttocks (both feet locked)
_PART_JOINTS = (
    (J["left_ankle"], J["left_foot"]),
    (J["right_ankle"], J["right_foot"]),
    (J["left_wrist"], J["left_hand"]),
    (J["right_wrist"], J["right_hand"]),
    (J["pelvis"], J["left_hip"], J["right_hip"]),
    (J["spine1"], J["spine2"], J["spine3"], J["left_collar"], J["right_collar"]),
)
# Lock point of each part (a joint): feet lock the ball of the foot, hands the wrist.
LOCK_JOINT = (J["left_foot"], J["right_foot"], J["left_wrist"], J["right_wrist"], J["pelvis"], J["spine2"])
# Limb chains for two-bone IK: (root, hinge, end, hinge axis in the hinge's local frame).
CHAINS = {
    LF: (J["left_hip"], J["left_knee"], J["left_ankle"], np.array([1.0, 0, 0])),
    RF: (J["right_hip"], J["right_knee"], J["right_ankle"], np.array([1.0, 0, 0])),
    LH: (J["left_shoulder"], J["left_elbow"], J["left_wrist"], np.array([0, -1.0, 0])),
    RH: (J["right_shoulder"], J["right_elbow"], J["right_wrist"], np.array([0, 1.0, 0])),
}
UPRIGHT = np.array([[1.0, 0, 0], [0, 0, -1.0], [0, 1.0, 0]])  # +90° about x: canonical Y-up → Z-up


# ----------------------------------------------------------------------------- rotations

def rot_z(angle_rad: np.ndarray) -> np.ndarray:
    a = np.asarray(angle_rad, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    r = np.zeros(a.shape + (3, 3))
    r[..., 0, 0], r[..., 0, 1], r[..., 1, 0], r[..., 1, 1], r[..., 2, 2] = c, -s, s, c, 1.0
    return r


def rot_x(angle_rad: np.ndarray) -> np.ndarray:
    a = np.asarray(angle_rad, dtype=np.float64)
    c, s = np.cos(a), np.sin(a)
    r = np.zeros(a.shape + (3, 3))
    r[..., 0, 0], r[..., 1, 1], r[..., 1, 2], r[..., 2, 1], r[..., 2, 2] = 1.0, c, -s, s, c
    return r


def min_rotation(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking direction a to direction b, (N,3) → (N,3,3)."""
    a = a / np.linalg.norm(a, axis=-1, keepdims=True)
    b = b / np.linalg.norm(b, axis=-1, keepdims=True)
    v = np.cross(a, b)
    c = np.sum(a * b, -1)
    k = skew(v)
    return np.eye(3) + k + (k @ k) / np.maximum(1.0 + c, 1e-9)[..., None, None]


def axis_rotation(axis: np.ndarray, angle: np.ndarray) -> np.ndarray:
    """Rotation about one fixed unit axis (3,) by angles (N,) → (N,3,3)."""
    k = skew(np.broadcast_to(axis, angle.shape + (3,)))
    s, c = np.sin(angle)[..., None, None], np.cos(angle)[..., None, None]
    return np.eye(3) + s * k + (1 - c) * (k @ k)


# ----------------------------------------------------------------------------- the rig

class Rig:
    """One body shape: FK, vertex heights and positions, two-bone IK."""

    def __init__(self, model: BodyModel, betas: np.ndarray):
        self.model = model
        self.betas = np.asarray(betas, dtype=np.float64).reshape(-1)
        self.parents = np.asarray(SMPL_PARENTS)
        self.levels = lbs.kinematic_levels(self.parents)
        _, b, _ = model.prepare_inputs(np.zeros(72), self.betas, None)
        raw_joints = lbs.shape_joints(model._j_template, model._j_shapedirs, b)[0]
        self.rest = raw_joints - raw_joints[0]  # (24,3) rest joints, pelvis at the origin (canonical frame)
        a = model.arrays
        shaped = a.v_template + (a.shapedirs.reshape(-1, a.shapedirs.shape[-1]) @ b[0]).reshape(-1, 3)
        self.rest_vertices = shaped - raw_joints[0]  # (V,3) float64, pelvis at the origin
        self._vh = np.concatenate([self.rest_vertices, np.ones((len(shaped), 1))], 1)  # homogeneous
        self._weights = np.asarray(a.weights, np.float64)
        self._posedirs = None if a.posedirs is None else a.posedirs.reshape(-1, a.posedirs.shape[2]).T  # (207, 3V)
        # Skinning as one product: vertex v's coordinate r = Σ_jk W[v,j]·vh[v,k]·A[t,j,r,k].
        # float32: the products are ~10× below a millimetre off and twice as fast.
        self._wvh = (self._weights[:, :, None] * self._vh[:, None, :]).reshape(len(shaped), -1).T.astype(np.float32)  # (J·4, V)
        dominant = np.argmax(a.weights, axis=1)
        self.part_vertices = [np.flatnonzero(np.isin(dominant, joints)) for joints in _PART_JOINTS]
        self.pelvis_vertices = np.flatnonzero(dominant == J["pelvis"])  # sacrum and buttocks, not the thighs
        # A flat foot (canonical orientation upright): height of the ball joint above the sole.
        up = np.tile(np.eye(3), (1, 24, 1, 1))
        up[0, 0] = UPRIGHT
        g_rot, g_t = self.fk(up)
        z = self.vertex_z(up)[0]
        self.ball_height = {p: float(g_t[0, LOCK_JOINT[p], 2] - z[self.part_vertices[p]].min()) for p in (LF, RF)}
        self.stand_height = float(-z.min())  # pelvis height standing in the rest pose
        self.foot_vec = {p: self.rest[LOCK_JOINT[p]] - self.rest[CHAINS[p][2]] for p in (LF, RF)}  # ankle → ball, canonical
        from sim.contact.segments import SegmentMassModel
        self.mass_model = SegmentMassModel(model, self.betas)
        self.com_height = self.stand_height + float(self.mass_model.rest_com_m[1])  # standing COM above the floor
        self.foot_geometry = {p: foot_geometry(self.rest_vertices, self.part_vertices[p], self.rest[CHAINS[p][2]],
                                               self.rest[LOCK_JOINT[p]]) for p in (LF, RF)}
        self.reach = {q: float(np.linalg.norm(self.rest[CHAINS[q][1]] - self.rest[CHAINS[q][0]])
                               + np.linalg.norm(self.rest[CHAINS[q][2]] - self.rest[CHAINS[q][1]])) for q in CHAINS}

    # FK on local rotation matrices (T,24,3,3), joint 0 already the world orientation.
    def fk(self, local: np.ndarray):
        rest = np.broadcast_to(self.rest, (local.shape[0],) + self.rest.shape)
        return lbs.forward_kinematics(local, rest, self.levels)

    def _skin_rows(self, local, g_rot, g_t, rows, vertices=None):
        """Rows (coordinates) of the skinned vertices, pelvis at the origin: (T,V,len(rows))
        (vertices: an optional index array, V of them)."""
        if g_rot is None:
            g_rot, g_t = self.fk(local)
        t = g_t - (g_rot @ self.rest[None, :, :, None])[..., 0]
        a = np.concatenate([g_rot[:, :, rows, :], t[:, :, rows, None]], -1)  # (T,J,R,4)
        if self._posedirs is None:
            n, nj, nr = a.shape[:3]
            flat = np.ascontiguousarray(a.transpose(0, 2, 1, 3), dtype=np.float32).reshape(n * nr, nj * 4)
            wvh = self._wvh if vertices is None else self._wvh_columns(vertices)
            return (flat @ wvh).astype(np.float64).reshape(n, nr, -1).transpose(0, 2, 1)
        per = np.einsum("vj,tjrk->tvrk", self._weights, a, optimize=True)
        feat = (local[:, 1:] - np.eye(3)).reshape(len(local), -1)
        v = self.rest_vertices[None] + (feat @ self._posedirs).reshape(len(local), -1, 3)
        out = np.einsum("tvrk,tvk->tvr", per[..., :3], v) + per[..., 3]
        return out if vertices is None else out[:, vertices]

    def _wvh_columns(self, vertices) -> np.ndarray:
        """The skinning matrix's columns of these vertices (cached by their bytes)."""
        vertices = np.asarray(vertices)
        key = vertices.tobytes()
        cache = self.__dict__.setdefault("_wvh_cache", {})
        if key not in cache:
            cache[key] = np.ascontiguousarray(self._wvh[:, vertices])
        return cache[key]

    def vertex_z(self, local: np.ndarray, g=None, vertices=None) -> np.ndarray:
        """Height of every vertex (or of ``vertices``, an index array) above the pelvis (T,V)."""
        g_rot, g_t = (None, None) if g is None else g
        return self._skin_rows(local, g_rot, g_t, [2], vertices)[..., 0]

    def skinned(self, local: np.ndarray, g) -> np.ndarray:
        """Every vertex (T,V,3), pelvis at the origin; g the FK (g_rot, g_t) of ``local``."""
        return self._skin_rows(local, g[0], g[1], [0, 1, 2])

    def vertices(self, local: np.ndarray, transl: np.ndarray | None = None) -> np.ndarray:
        v = self._skin_rows(local, None, None, [0, 1, 2])
        return v if transl is None else v + transl[:, None]

    # ------------------------------------------------------------------ IK
    def two_bone_ik(self, local: np.ndarray, part: int, frames: np.ndarray, target: np.ndarray, g=None) -> None:
        """Move the end joint of a limb (ankle or wrist) onto target (N,3) (pelvis-relative world)
        in the given frames, in place: hinge angle from the distance, then the smallest swing at
        the root joint (hip or shoulder). g: optional FK (g_rot, g_t) of ``local[frames]``
        (only the root's parent chain is used, which this does not change)."""
        if len(frames) == 0:
            return
        a, b, c, k = CHAINS[part]
        g_rot, g_t = self.fk(local[frames]) if g is None else g
        u = self.rest[b] - self.rest[a]
        v = self.rest[c] - self.rest[b]
        lu, lv = np.linalg.norm(u), np.linalg.norm(v)
        d = target - g_t[:, a]
        dist = np.clip(np.linalg.norm(d, axis=1), abs(lu - lv) + 1e-3, (lu + lv) * 0.9995)
        uk, vk = u @ k, v @ k
        aa = u @ v - uk * vk
        bb = u @ np.cross(k, v)
        cc = 0.5 * (dist**2 - lu**2 - lv**2) - uk * vk
        rho = np.hypot(aa, bb)
        theta = np.arctan2(bb, aa) + np.arccos(np.clip(cc / rho, -1.0, 1.0))
        r_hinge = axis_rotation(k, theta)
        local[frames, b] = r_hinge
        w = u + (r_hinge @ v)  # (N,3) end relative to root, in the root's own frame
        g_parent = g_rot[:, self.parents[a]]
        want = np.einsum("nji,nj->ni", g_parent, d)  # G_parent^T d
        have = np.einsum("nij,nj->ni", local[frames, a], w)
        local[frames, a] = min_rotation(have, want) @ local[frames, a]

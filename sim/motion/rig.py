"""Rotations, forward kinematics, two-bone IK and ground contact for one body shape.

Everything here is batched over frames (leading axis T) and float64. A ``Rig`` is the
body model evaluated for one shape (betas): its rest joints with the pelvis at the
origin, the vertex sets of the contact parts, and ``ground`` — the solver that turns
local joint rotations plus a contact schedule into world ``pose_aa`` and ``transl_m``
(see ``Rig.ground``).
"""

from __future__ import annotations

import numpy as np
from scipy.signal import savgol_filter
from scipy.spatial.transform import Rotation

from edge.body import SMPL_PARENTS, BodyModel, lbs
from edge.body.rotations import euler_xyz_deg_to_matrix as euler_deg_to_matrix  # noqa: F401  (sim.motion uses these names)
from edge.body.rotations import matrix_to_axis_angle as matrix_to_rotvec  # noqa: F401
from edge.body.rotations import skew
from sim.contact.track import ACC_WINDOW
from sim.motion.balance import foot_geometry, left_weight, support_point, zmp_com
from sim.motion.spans import (
    bridge_gaps,
    envelope,
    hold_at_span_start,
    min_jerk,
    near_contact_weight,
    slerp_mats,
    span_start_index,
)
from sim.motion.swing import swing_ankle_path, swing_spans

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
_CHAINS = {
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
    """One body shape: FK, vertex heights, IK and the ground-contact solve."""

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
        self.foot_vec = {p: self.rest[LOCK_JOINT[p]] - self.rest[_CHAINS[p][2]] for p in (LF, RF)}  # ankle → ball, canonical
        from sim.contact.segments import SegmentMassModel
        self.mass_model = SegmentMassModel(model, self.betas)
        self.com_height = self.stand_height + float(self.mass_model.rest_com_m[1])  # standing COM above the floor
        self.foot_geometry = {p: foot_geometry(self.rest_vertices, self.part_vertices[p], self.rest[_CHAINS[p][2]],
                                               self.rest[LOCK_JOINT[p]]) for p in (LF, RF)}
        self.reach = {q: float(np.linalg.norm(self.rest[_CHAINS[q][1]] - self.rest[_CHAINS[q][0]])
                               + np.linalg.norm(self.rest[_CHAINS[q][2]] - self.rest[_CHAINS[q][1]])) for q in _CHAINS}

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
        a, b, c, k = _CHAINS[part]
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

    # ------------------------------------------------------------------ ground contact
    def ground(self, local: np.ndarray, contact: np.ndarray, anchor: np.ndarray, heel_deg: np.ndarray,
               foot_yaw: np.ndarray, hand_rot: np.ndarray | None = None, start_xy=(0.0, 0.0),
               iterations: int = 3, balance: np.ndarray | None = None, rate_hz: float = 14.0,
               seated: np.ndarray | None = None, swing: np.ndarray | None = None) -> np.ndarray:
        """Place a posed sequence on the floor; returns transl (T,3) (the pelvis).

        local: (T,24,3,3) local rotations, joint 0 the world orientation (modified in place:
        ankles, feet, wrists and limb chains get contact corrections);
        contact: (T,6) bool schedule over ``CONTACT_PARTS``; anchor: (T,) the part that
        carries the root (a contact part in that frame, or SETTLE); heel_deg: (T,2) heel
        raise of each foot while in contact (0 flat, ~70 on the toes); foot_yaw: (T,2) world
        yaw of each foot (rad) used when it touches down; hand_rot: optional (T,2,3,3) world
        orientation of the wrists while the hands touch; balance, seated, swing: optional (T,)
        bool masks of the frames where the COM is balanced over the feet (``_balance``), a
        floor sitter's trunk is put over the buttocks, and a foot between two contacts
        follows a planned swing path (``sim.motion.swing``: walking).

        1. Lock points: a foot's ball (flat at its touch-down yaw, heel raised by heel_deg),
           a hand's wrist (and its orientation), the buttocks'/back's pelvis/spine joint.
           The anchor part carries the root: transl is the locked point minus its
           pelvis-relative position; a limb touching down is locked where the posed body
           puts it, at floor height. Jumps of transl where the anchor changes are spread
           over a few frames.
        2. Repeat: lower the pelvis (smoothly) where a locked limb cannot reach its lock;
           put every locked limb (the anchor's too) on its lock by two-bone IK; raise the
           body where any vertex is below the floor.
        """
        n = len(local)
        contact = np.asarray(contact, bool)
        anchor = np.asarray(anchor)
        heel = np.radians(heel_deg)
        # Foot orientation: in contact flat (or on the toes) at the yaw of touch-down; in the air
        # blended from the last lock to the next one, so a foot never snaps on lift-off.
        foot_rot = {}
        for p in (LF, RF):
            yaw = hold_at_span_start(contact[:, p], foot_yaw[:, p])
            yaw, hl = bridge_gaps(contact[:, p], yaw), bridge_gaps(contact[:, p], heel[:, p].copy())
            foot_rot[p] = rot_z(yaw) @ UPRIGHT @ rot_x(hl)
        toe_rot = {p: rot_x(-0.8 * np.maximum(heel[:, p], 0.0)) for p in (LF, RF)}
        wrist_rot = {}
        if hand_rot is not None:
            for p in (LH, RH):
                if contact[:, p].any():
                    wrist_rot[p] = hand_rot[span_start_index(contact[:, p]), p - LH]
        blend = {p: near_contact_weight(contact[:, p], 4) for p in (LH, RH)}
        feet_used = [p for p in (LF, RF) if contact[:, p].any()]

        def orient_ends(frames, g_rot):
            """Feet and wrists to their world orientations in `frames` (index array); g_rot the FK of local[frames]."""
            for p in feet_used:
                ankle = _CHAINS[p][2]
                local[frames, ankle] = np.swapaxes(g_rot[:, self.parents[ankle]], -1, -2) @ foot_rot[p][frames]
                local[frames, LOCK_JOINT[p]] = toe_rot[p][frames]  # toes stay on the floor
            for p in wrist_rot:
                sel = blend[p][frames] > 0
                if not sel.any():
                    continue
                f = frames[sel]
                wrist = _CHAINS[p][2]
                want = np.swapaxes(g_rot[sel, self.parents[wrist]], -1, -2) @ wrist_rot[p][f]
                local[f, wrist] = slerp_mats(local[f, wrist], want, blend[p][f])

        all_frames = np.arange(n)
        g = self.fk(local)
        orient_ends(all_frames, g[0])
        self._rest_on_back(local, contact)
        g = self.fk(local)
        z = self.vertex_z(local, g)
        part_low = np.stack([z[:, idx].min(1) for idx in self.part_vertices], 1)  # (T,6)
        # height of each ankle above its foot's lowest point (set by the foot's orientation alone)
        ankle_drop = {q: g[1][:, _CHAINS[q][2], 2] - part_low[:, q] for q in (LF, RF)}
        lock_local = g[1][:, list(LOCK_JOINT)]  # (T,6,3)

        # ---- 1. the anchor chain
        transl = np.zeros((n, 3))
        limbs = (LF, RF, LH, RH)
        span_of = {q: span_start_index(contact[:, q]) for q in limbs}
        touch = {q: np.flatnonzero(contact[:, q] & ~np.r_[False, contact[:-1, q]]) for q in limbs}

        def floor_z(q, t0):
            if q in (LF, RF) and heel[t0, q] == 0:
                return self.ball_height[q]
            return lock_local[t0, q, 2] - part_low[t0, q]

        starts = np.flatnonzero(np.r_[True, anchor[1:] != anchor[:-1]])
        ends = np.r_[starts[1:], n]
        w_prev = None
        locks = {}  # (limb, first frame of its contact span) → locked world point
        for s, e in zip(starts, ends):
            p = int(anchor[s])
            settle = p == SETTLE
            if settle:  # xy follow the left foot's lock; z blends between feet and buttocks
                p = LF
            if w_prev is None:
                w = np.array([start_xy[0], start_xy[1], 0.0]) + lock_local[s, p] * [1, 1, 0]  # pelvis over start_xy
            else:
                q, wq = w_prev
                w = wq - lock_local[s, q] + lock_local[s, p]  # continuity of transl at the switch
            if p in span_of and contact[s, p]:
                key = (p, int(span_of[p][s]))
                if key in locks:  # already locked as a non-anchor limb: keep that lock
                    w = locks[key].copy()
                else:
                    w[2] = floor_z(p, s)
                    locks[key] = w
            seg = slice(s, e)
            transl[seg] = w - lock_local[seg, p]
            if p in (BUTT, BACK):
                transl[seg, 2] = -part_low[seg, p]
            elif p in (LF, RF):  # rolling on the heel (toes up): the heel, not the locked ball, is on the floor
                rock = np.flatnonzero(contact[seg, p] & (heel[seg, p] < 0)) + s
                transl[rock, 2] = -part_low[rock, p]
            if settle:
                down = w_prev is None or w_prev[0] in limbs
                ramp = min_jerk((np.arange(e - s) + 1.0) / (e - s))
                ramp = ramp if down else 1.0 - ramp
                transl[seg, 2] = (1 - ramp) * transl[seg, 2] + ramp * (-part_low[seg, BUTT])
            if s >= 2:  # spread a jump at the switch over the next frames
                jump = transl[s] - (2 * transl[s - 1] - transl[s - 2])
                k = min(_SMOOTH, e - s)
                fade = 1.0 - min_jerk((np.arange(k) + 1.0) / (_SMOOTH + 1.0))
                transl[s:s + k] -= fade[:, None] * jump
            w_prev = (p, w)
            # Limbs touching down during this span get their locks from this placement.
            for q in limbs:
                if q == p:
                    continue
                t0s = touch[q][(touch[q] > s) & (touch[q] < e)]
                if contact[s, q]:
                    t0s = np.r_[span_of[q][s], t0s]
                for t0 in t0s:
                    t0 = int(t0)
                    if (q, t0) not in locks:
                        wq = transl[t0] + lock_local[t0, q]
                        wq[2] = floor_z(q, t0)
                        locks[(q, t0)] = wq

        # Per limb: frames to solve, weights (1 in contact; hands ramp in/out) and lock targets.
        t_idx = np.arange(n)
        solve = {}
        for q in limbs:
            c = contact[:, q]
            if not c.any():
                continue
            weight = blend[q] if q in blend else c.astype(float)
            frames = np.flatnonzero(weight > 0)
            prev_c = np.maximum.accumulate(np.where(c, t_idx, -1))
            next_c = np.minimum.accumulate(np.where(c, t_idx, n)[::-1])[::-1]
            f = frames
            near = np.where(c[f], f, np.where((f - prev_c[f] <= next_c[f] - f) & (prev_c[f] >= 0), prev_c[f], next_c[f]))
            near = np.clip(near, 0, n - 1)
            span0 = span_of[q][near]
            keys, inv = np.unique(span0, return_inverse=True)
            table = np.stack([locks[(q, int(k0))] if (q, int(k0)) in locks else transl[k0] + lock_local[k0, q] for k0 in keys])
            target = table[inv]
            if q in (LF, RF):  # the ball's height follows the heel raise (sole or toes on the floor)
                on = c[frames]
                zf = np.where(heel[frames, q] != 0, lock_local[frames, q, 2] - part_low[frames, q], self.ball_height[q])
                # One ball height per contact span, the middle of what the heel raise asks for: the
                # ball stays put while the toes or the sole stay within a few mm of the floor.
                rock = on & (heel[frames, q] < 0)  # heel strike (toes up): the foot rolls on its heel,
                sole = on & ~rock                  # the ball comes down frame by frame
                sid = np.unique(span0[sole], return_inverse=True)[1]
                lo, hi = np.full(sid.max() + 1 if len(sid) else 0, np.inf), np.full(sid.max() + 1 if len(sid) else 0, -np.inf)
                np.minimum.at(lo, sid, zf[sole])
                np.maximum.at(hi, sid, zf[sole])
                target[sole, 2] = 0.5 * (lo + hi)[sid]
                target[rock, 2] = zf[rock]
                target = target - np.einsum("nij,j->ni", foot_rot[q][frames], self.foot_vec[q])
            solve[q] = (frames, weight[frames], target, c[frames])
        swing_ik = {}  # foot → (frames, ankle targets) of its planned swings
        for q in (LF, RF) if swing is not None else ():
            if q not in solve:
                continue
            spans = swing_spans(contact[:, q], swing, int(round(_MAX_SWING_S * rate_hz)))
            if spans:
                ankle = np.zeros((n, 3))
                ankle[solve[q][0]] = solve[q][2]
                ends = np.array(spans)
                swing_ik[q] = swing_ankle_path(spans, ankle[ends[:, 0]], ankle[ends[:, 1]], ankle_drop[q])

        def put_limbs(g_rot, g_t):
            """Every locked limb onto its lock (hands ramp toward it before and after contact)."""
            for q, (frames, wgt, target, on) in solve.items():
                end = target
                if (wgt < 1).any():
                    native = transl[frames] + g_t[frames, _CHAINS[q][2]]
                    end = native + wgt[:, None] * (target - native)
                self.two_bone_ik(local, q, frames, end - transl[frames], (g_rot[frames], g_t[frames]))
            for q, (frames, path) in swing_ik.items():
                self.two_bone_ik(local, q, frames, path - transl[frames], (g_rot[frames], g_t[frames]))
            g_rot, g_t = self.fk(local)
            orient_ends(all_frames, g_rot)

        # ---- 1b. balance: the pelvis carries the COM along the path whose ZMP stays on the feet
        if seated is not None:  # after the feet are on their locks: the lever to them is known
            put_limbs(*self.fk(local))
            self._sit_over_buttocks(local, contact, anchor, np.asarray(seated, bool))
        com_path = None
        if balance is not None:
            put_limbs(*self.fk(local))
            com_path = self._balance(local, transl, contact, anchor, heel, foot_rot, np.asarray(balance, bool), rate_hz,
                                     put_limbs)

        # ---- 2. reach, IK, rest, lift
        moved_body = 0.0
        for it in range(iterations):
            g_rot, g_t = self.fk(local)
            if com_path is not None:  # lowering the pelvis bent the knees forward: keep the COM on its path
                self._follow_com(transl, com_path, g_rot, g_t)
            need = np.zeros(n)
            for q, (frames, wgt, target, on) in solve.items():
                f = frames[on]
                v = target[on] - (transl[f] + g_t[f, _CHAINS[q][0]])
                r = 0.997 * self.reach[q]
                h = np.hypot(v[:, 0], v[:, 1])
                d = np.where(h < 0.98 * r, -v[:, 2] - np.sqrt(np.maximum(r * r - h * h, 0.0)), 0.0)  # lowering can't help a far lock
                need[f] = np.maximum(need[f], d)
            if need.max() > 1e-5:
                transl[:, 2] -= envelope(np.maximum(need, 0.0), _SMOOTH)
            put_limbs(g_rot, g_t)
            g = self.fk(local)
            z = self.vertex_z(local, g) + transl[:, 2:3]
            # A free (swinging) foot or hand that dips below the floor is raised by IK, not the body.
            moved = np.zeros(n, bool)
            for q in limbs:
                free = ~contact[:, q]
                pen = np.maximum(0.0, -z[:, self.part_vertices[q]].min(1)) * free
                f = np.flatnonzero(pen > 1e-4)
                if len(f):
                    end = g[1][f, _CHAINS[q][2]] + np.outer(pen[f] + 0.002, [0.0, 0.0, 1.0])
                    self.two_bone_ik(local, q, f, end, (g[0][f], g[1][f]))
                    moved[f] = True
            if moved.any():  # only the frames whose limbs moved need new vertex heights
                f = np.flatnonzero(moved)
                z[f] = self.vertex_z(local[f]) + transl[f, 2:3]
            # A body resting on the buttocks or the back stays on them after the IK moved the thighs.
            # The change fades out over a few frames around those spans (no jump of the pelvis).
            rest = np.isin(anchor, (BUTT, BACK))
            if rest.any():
                adj = np.zeros(n)
                for p in (BUTT, BACK):
                    rows = np.flatnonzero(anchor == p)
                    if len(rows):
                        adj[rows] = z[np.ix_(rows, self.part_vertices[p])].min(1)
                t_idx = np.arange(n)
                prev_r = np.maximum.accumulate(np.where(rest, t_idx, -1))
                next_r = np.minimum.accumulate(np.where(rest, t_idx, n)[::-1])[::-1]
                nearest = np.where((prev_r >= 0) & ((t_idx - prev_r <= next_r - t_idx) | (next_r >= n)), prev_r, next_r)
                adj = adj[np.clip(nearest, 0, n - 1)] * near_contact_weight(rest, _SMOOTH)
                moved_body = max(moved_body, float(np.abs(adj).max()))
                transl[:, 2] -= adj
                z -= adj[:, None]
            # A locked foot or hand may press up to _SINK into the floor (skinning at a sharply bent
            # ankle or wrist) without lifting the whole body off its other contacts.
            for q in limbs:
                rows = np.flatnonzero(contact[:, q])
                if len(rows):
                    z[np.ix_(rows, self.part_vertices[q])] += _SINK
            low = z.min(1)
            lift = np.maximum(0.0, -low)
            transl[:, 2] += lift
            moved_body = max(moved_body, float(lift.max()), float(need.max()))
            if moved_body < 1e-4:
                break
            if it < iterations - 1:
                moved_body = 0.0
        if moved_body >= 1e-4:  # the body moved after the last IK: put the limbs back on their locks
            put_limbs(*self.fk(local))
        if com_path is not None:
            # The path again for the body's own COM height and vertical acceleration (the ZMP is
            # com − z·ẍ/(g + z̈); a 1 cm COM error at a step's sway swings it ~4 cm), followed closely.
            g_rot, g_t = self.fk(local)
            z = transl[:, 2] + self.mass_model.com_from_fk(g_rot, g_t)[:, 2]
            acc_z = savgol_filter(z, ACC_WINDOW, 3, deriv=2, delta=1.0 / rate_hz) if n >= ACC_WINDOW else np.zeros(n)
            p, wgt, _ = com_path
            com_path = (p, wgt, zmp_com(p, rate_hz, z / (1.0 + acc_z / 9.81)))
            for _ in range(_COM_ROUNDS):
                self._follow_com(transl, com_path, g_rot, g_t)
                put_limbs(g_rot, g_t)
                g_rot, g_t = self.fk(local)
        return transl

    def _follow_com(self, transl, com_path, g_rot, g_t) -> None:
        """Shift the pelvis (in place) by the COM's distance from its path (com_path: support point
        (T,2), weight (T,), desired COM (T,2))."""
        _, wgt, desired = com_path
        com = transl[:, :2] + self.mass_model.com_from_fk(g_rot, g_t)[:, :2]
        transl[:, :2] += wgt[:, None] * (desired - com)

    def _balance(self, local, transl, contact, anchor, heel, foot_rot, balance, rate_hz, put_limbs, rounds: int = 3):
        """Shift the pelvis (in place) where the body stands on its feet alone so that the COM
        follows the path whose zero-moment point is the feet's support point; faded in and
        out over a few frames around those spans. The locked feet are put back by IK.
        Returns (support point (T,2), weight (T,), desired COM (T,2)) for the later passes, or None."""
        feet = contact[:, [LF, RF]]
        feet_only = feet.any(1) & ~contact[:, [LH, RH, BUTT, BACK]].any(1) & np.isin(anchor, (LF, RF)) & balance
        if not feet_only.any():
            return None
        wgt = near_contact_weight(feet_only, _SMOOTH + 1)
        desired = None
        for _ in range(rounds):
            g_rot, g_t = self.fk(local)
            com = transl[:, :2] + self.mass_model.com_from_fk(g_rot, g_t)[:, :2]
            if desired is None:
                p = com.copy()
                pts = {q: support_point(transl + g_t[:, LOCK_JOINT[q]], foot_rot[q], self.foot_geometry[q],
                                        heel[:, q]) for q in (LF, RF)}
                w = left_weight(feet[:, 0], feet[:, 1], rate_hz)[:, None]
                p[feet_only] = (w * pts[LF] + (1.0 - w) * pts[RF])[feet_only]
                desired = zmp_com(p, rate_hz, self.com_height)
            transl[:, :2] += wgt[:, None] * (desired - com)
            put_limbs(g_rot, g_t)
        return p, wgt, desired

    def _sit_over_buttocks(self, local, contact, anchor, seated, rounds: int = 3) -> None:
        """Sitting on the floor without the hands: flex (or extend) the lower spine so that the
        COM lies over the seat, SIT_COM_FRAC of the way from the buttocks toward the feet (the
        buttocks then carry most of the weight, as a seated body's own mass distribution says)."""
        sit = (anchor == BUTT) & contact[:, BUTT] & ~contact[:, [BACK, LH, RH]].any(1) & seated
        if not sit.any():
            return
        wgt = near_contact_weight(sit, _SMOOTH + 1)
        f = np.flatnonzero(wgt > 0)
        for _ in range(rounds):
            g_rot, g_t = self.fk(local[f])
            com = self.mass_model.com_from_fk(g_rot, g_t)
            pv = self._skin_rows(local[f], g_rot, g_t, [0, 1, 2])[:, self.pelvis_vertices]
            seat = pv[np.arange(len(f)), pv[:, :, 2].argmin(1)]
            feet = 0.25 * sum(g_t[:, J[n]] for n in ("left_ankle", "right_ankle", "left_foot", "right_foot"))
            d = feet[:, :2] - seat[:, :2]
            u = d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-6)
            e = np.sum((com[:, :2] - seat[:, :2] - SIT_COM_FRAC * d) * u, 1)  # > 0: COM too far toward the feet
            angle = np.clip(-e / _UPPER_LEVER_M, -0.5, 0.5) * wgt[f]
            local[f, J["spine1"]] = local[f, J["spine1"]] @ rot_x(angle)

    def _rest_on_back(self, local: np.ndarray, contact: np.ndarray) -> None:
        """Where the back and the buttocks are both scheduled on the floor, pitch the root so
        that the back and the pelvis (sacrum, buttocks; not the backs of the thighs, which a
        flexed hip lowers) are equally low, the pelvis _SACRUM_DROP lower. The frames around a
        lying span take the nearest lying frame's correction, fading over _LIE_FADE frames (most
        of a curl): refitted to a back already rising, or faded faster than the curl lifts the
        trunk, it pitched the trunk back down toward the template's and up again."""
        lying = contact[:, BACK] & contact[:, BUTT]
        f = np.flatnonzero(lying)
        if len(f) == 0:
            return
        total = Rotation.identity(len(f))
        for _ in range(4):
            g = self.fk(local[f])
            z = self.vertex_z(local[f], g)
            dz = z[:, self.part_vertices[BACK]].min(1) - z[:, self.pelvis_vertices].min(1) - _SACRUM_DROP
            d = g[1][:, LOCK_JOINT[BACK]] - g[1][:, LOCK_JOINT[BUTT]]
            d[:, 2] = 0.0
            length = np.maximum(np.linalg.norm(d, axis=1), 0.05)
            axis = np.cross(np.array([0.0, 0.0, 1.0]), d / length[:, None])
            axis /= np.maximum(np.linalg.norm(axis, axis=1, keepdims=True), 1e-9)
            rot = Rotation.from_rotvec(axis * np.arctan2(dz, length)[:, None])
            local[f, 0] = rot.as_matrix() @ local[f, 0]
            total = rot * total
        wgt = near_contact_weight(lying, _LIE_FADE)
        ramp = np.flatnonzero((wgt > 0) & ~lying)
        if len(ramp):
            t_idx = np.arange(len(lying))
            prev_l = np.maximum.accumulate(np.where(lying, t_idx, -len(lying)))
            next_l = np.minimum.accumulate(np.where(lying, t_idx, 2 * len(lying))[::-1])[::-1]
            nearest = np.where(ramp - prev_l[ramp] <= next_l[ramp] - ramp, prev_l[ramp], next_l[ramp])
            rv = total.as_rotvec()[np.searchsorted(f, nearest)] * wgt[ramp, None]
            local[ramp, 0] = Rotation.from_rotvec(rv).as_matrix() @ local[ramp, 0]


_SMOOTH = 4  # frames over which transl corrections are spread
_MAX_SWING_S = 1.2  # a foot off the floor longer than this is not a walking step's swing
_COM_ROUNDS = 3  # final passes that put the COM back on its balanced path after the reach and floor passes
SIT_COM_FRAC = 0.08  # seated COM this far from the lowest point of the buttocks toward the feet (~84 % on the buttocks)
_UPPER_LEVER_M = 0.17  # COM shift per radian of lower-spine flexion (upper-body mass share × its lever)
_LIE_FADE = 12  # frames over which the lying correction fades out into a curl (and in before lying down)
_SACRUM_DROP = 0.03  # m the pelvis lies lower than the back when supine: the sacrum and buttocks carry the heavy pelvis
_SINK = 0.008  # m a locked foot/hand may press into the floor before the body is lifted

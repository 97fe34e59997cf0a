"""The ground solve: a posed sequence with a contact schedule → the pelvis translation that
puts it on the floor (``ground``), locked limbs on their locks by two-bone IK.

Steps, in order (each a function here, in ``sim.motion.locks`` or ``sim.motion.posture``):

1. Lock points (``locks``): a foot's ball (flat at its touch-down yaw, heel raised by
   heel_deg), a hand's wrist (and its orientation), the buttocks'/back's pelvis/spine joint.
   A lying body is first pitched so that back and buttocks both rest (``rest_on_back``). The
   anchor part carries the root (``anchor_chain``); a limb touching down is locked where the
   posed body puts it, at floor height.
2. Balance: a floor sitter's trunk over the buttocks (``sit_over_buttocks``); standing on
   the feet alone, the COM along the path whose ZMP stays on the feet (``balance_com``).
3. Up to ``iterations`` floor passes (``_floor_pass``): lower the pelvis (smoothly) where a
   locked limb cannot reach its lock; put every locked limb (the anchor's too) on its lock
   by IK; raise a free limb that dips below the floor; keep a resting body on its
   buttocks/back; lift the body where any vertex is still below the floor.
4. The COM path refitted to the body's own COM height and followed again (``_refit_com``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import savgol_filter

from sim.contact.track import ACC_WINDOW
from sim.motion.balance import zmp_com
from sim.motion.locks import LIMBS, EndRotations, LimbLock, Posed, Schedule, anchor_chain, limb_locks, swing_targets
from sim.motion.posture import ComPath, balance_com, follow_com, rest_on_back, sit_over_buttocks
from sim.motion.rig import BACK, BUTT, CHAINS, Rig
from sim.motion.spans import SMOOTH_FRAMES, envelope, near_contact_weight

_COM_ROUNDS = 3  # final passes that put the COM back on its balanced path after the reach and floor passes
_SINK_M = 0.008  # m a locked foot/hand may press into the floor before the body is lifted


def ground(rig: Rig, local: np.ndarray, contact: np.ndarray, anchor: np.ndarray, heel_deg: np.ndarray,
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
    bool masks of the frames where the COM is balanced over the feet (``balance_com``), a
    floor sitter's trunk is put over the buttocks, and a foot between two contacts
    follows a planned swing path (``sim.motion.swing``: walking).
    """
    sched = Schedule.of(contact, anchor, heel_deg)
    ends = EndRotations.of(sched, foot_yaw, hand_rot)
    ends.apply(rig, local, np.arange(len(local)), rig.fk(local)[0])
    rest_on_back(rig, local, sched.contact)
    posed = Posed.of(rig, local)
    transl, locks = anchor_chain(rig, sched, posed, start_xy)
    solve = limb_locks(rig, sched, posed, ends, transl, locks)
    limbs = LimbPlacer(rig, local, transl, solve, swing_targets(sched, swing, rate_hz, solve, posed), ends)

    if seated is not None:  # after the feet are on their locks: the lever to them is known
        limbs.put(*rig.fk(local))
        sit_over_buttocks(rig, local, sched.contact, sched.anchor, np.asarray(seated, bool))
    com_path = None
    if balance is not None:
        limbs.put(*rig.fk(local))
        com_path = balance_com(rig, local, transl, sched.contact, sched.anchor, sched.heel, ends.foot,
                               np.asarray(balance, bool), rate_hz, limbs.put)

    moved_m = 0.0
    for _ in range(iterations):
        moved_m = _floor_pass(limbs, sched, com_path)
        if moved_m < 1e-4:
            break
    if moved_m >= 1e-4:  # the body moved after the last IK: put the limbs back on their locks
        limbs.put(*rig.fk(local))
    if com_path is not None:
        _refit_com(limbs, com_path, rate_hz)
        _lift_after_refit(limbs, sched)
    return transl


def _lift_after_refit(limbs: LimbPlacer, sched: Schedule, passes: int = 3) -> None:
    """Moving the pelvis onto the COM path can bend a deep crouch's knee into the floor (getting
    up from a push-up): raise the body there, the locked limbs re-solved onto their locks."""
    rig, local, transl = limbs.rig, limbs.local, limbs.transl
    for _ in range(passes):
        g = rig.fk(local)
        if _lift_above_floor(rig, transl, sched.contact, rig.vertex_z(local, g) + transl[:, 2:3]) < 1e-4:
            return
        limbs.put(*g)  # the lift moved transl only: the FK of local still holds


@dataclass(frozen=True)
class LimbPlacer:
    """A sequence being grounded: its local rotations (T,24,3,3) and transl (T,3), both
    changed in place, with every limb's locks, planned swings and end orientations."""

    rig: Rig
    local: np.ndarray
    transl: np.ndarray
    solve: dict[int, LimbLock]
    swings: dict[int, tuple[np.ndarray, np.ndarray]]
    ends: EndRotations

    def put(self, g_rot: np.ndarray, g_t: np.ndarray) -> None:
        """Every locked limb onto its lock (hands ramp toward it before and after contact),
        swinging feet onto their paths, then the feet and wrists to their orientations.
        g_rot, g_t: the FK of ``local`` before."""
        rig, local, transl = self.rig, self.local, self.transl
        for q, (frames, wgt, target, _) in self.solve.items():
            end = target
            if (wgt < 1).any():
                native = transl[frames] + g_t[frames, CHAINS[q][2]]
                end = native + wgt[:, None] * (target - native)
            rig.two_bone_ik(local, q, frames, end - transl[frames], (g_rot[frames], g_t[frames]))
        for q, (frames, path) in self.swings.items():
            rig.two_bone_ik(local, q, frames, path - transl[frames], (g_rot[frames], g_t[frames]))
        g_rot, g_t = rig.fk(local)
        self.ends.apply(rig, local, np.arange(len(local)), g_rot)


def _floor_pass(limbs: LimbPlacer, sched: Schedule, com_path: ComPath | None) -> float:
    """One pass of reach, IK, rest and lift; returns how far (m) it moved the body."""
    rig, local, transl = limbs.rig, limbs.local, limbs.transl
    g_rot, g_t = rig.fk(local)
    if com_path is not None:  # lowering the pelvis bent the knees forward: keep the COM on its path
        follow_com(rig, transl, com_path, g_rot, g_t)
    need = _reach_need(rig, transl, limbs.solve, g_t)
    if need.max() > 1e-5:
        transl[:, 2] -= envelope(np.maximum(need, 0.0), SMOOTH_FRAMES)
    limbs.put(g_rot, g_t)
    z = _raise_free_limbs(rig, local, transl, sched.contact)
    rest_m = _keep_resting(rig, transl, sched.anchor, z)
    lift_m = _lift_above_floor(rig, transl, sched.contact, z)
    return max(rest_m, lift_m, float(need.max()))


def _reach_need(rig: Rig, transl: np.ndarray, solve: dict[int, LimbLock], g_t: np.ndarray) -> np.ndarray:
    """(T,) how far the pelvis must come down for every locked limb to reach its lock."""
    need = np.zeros(len(transl))
    for q, (frames, _, target, on) in solve.items():
        f = frames[on]
        v = target[on] - (transl[f] + g_t[f, CHAINS[q][0]])
        r = 0.997 * rig.reach[q]
        h = np.hypot(v[:, 0], v[:, 1])
        d = np.where(h < 0.98 * r, -v[:, 2] - np.sqrt(np.maximum(r * r - h * h, 0.0)), 0.0)  # lowering can't help a far lock
        need[f] = np.maximum(need[f], d)
    return need


def _raise_free_limbs(rig: Rig, local: np.ndarray, transl: np.ndarray, contact: np.ndarray) -> np.ndarray:
    """A free (swinging) foot or hand that dips below the floor is raised by IK, not the body
    (local in place). Returns every vertex's height above the floor afterwards (T,V)."""
    n = len(local)
    g = rig.fk(local)
    z = rig.vertex_z(local, g) + transl[:, 2:3]
    moved = np.zeros(n, bool)
    for q in LIMBS:
        free = ~contact[:, q]
        pen = np.maximum(0.0, -z[:, rig.part_vertices[q]].min(1)) * free
        f = np.flatnonzero(pen > 1e-4)
        if len(f):
            end = g[1][f, CHAINS[q][2]] + np.outer(pen[f] + 0.002, [0.0, 0.0, 1.0])
            rig.two_bone_ik(local, q, f, end, (g[0][f], g[1][f]))
            moved[f] = True
    if moved.any():  # only the frames whose limbs moved need new vertex heights
        f = np.flatnonzero(moved)
        z[f] = rig.vertex_z(local[f]) + transl[f, 2:3]
    return z


def _keep_resting(rig: Rig, transl: np.ndarray, anchor: np.ndarray, z: np.ndarray) -> float:
    """A body resting on the buttocks or the back stays on them after the IK moved the thighs
    (transl and the heights z (T,V) in place). The change fades out over a few frames around
    those spans (no jump of the pelvis). Returns the largest change (m)."""
    n = len(transl)
    rest = np.isin(anchor, (BUTT, BACK))
    if not rest.any():
        return 0.0
    adj = np.zeros(n)
    for p in (BUTT, BACK):
        rows = np.flatnonzero(anchor == p)
        if len(rows):
            adj[rows] = z[np.ix_(rows, rig.part_vertices[p])].min(1)
    t_idx = np.arange(n)
    prev_r = np.maximum.accumulate(np.where(rest, t_idx, -1))
    next_r = np.minimum.accumulate(np.where(rest, t_idx, n)[::-1])[::-1]
    nearest = np.where((prev_r >= 0) & ((t_idx - prev_r <= next_r - t_idx) | (next_r >= n)), prev_r, next_r)
    adj = adj[np.clip(nearest, 0, n - 1)] * near_contact_weight(rest, SMOOTH_FRAMES)
    transl[:, 2] -= adj
    z -= adj[:, None]
    return float(np.abs(adj).max())


def _lift_above_floor(rig: Rig, transl: np.ndarray, contact: np.ndarray, z: np.ndarray) -> float:
    """Lift the body (transl in place) where a vertex is below the floor; a locked foot or hand
    may press up to _SINK_M into it (skinning at a sharply bent ankle or wrist) without lifting
    the whole body off its other contacts. z (T,V) is changed. Returns the largest lift (m)."""
    for q in LIMBS:
        rows = np.flatnonzero(contact[:, q])
        if len(rows):
            z[np.ix_(rows, rig.part_vertices[q])] += _SINK_M
    lift = np.maximum(0.0, -z.min(1))
    transl[:, 2] += lift
    return float(lift.max())


def _refit_com(limbs: LimbPlacer, com_path: ComPath, rate_hz: float) -> None:
    """The COM path again for the body's own COM height and vertical acceleration (the ZMP is
    com − z·ẍ/(g + z̈); a 1 cm COM error at a step's sway swings it ~4 cm), followed closely."""
    rig, local, transl = limbs.rig, limbs.local, limbs.transl
    n = len(transl)
    g_rot, g_t = rig.fk(local)
    z = transl[:, 2] + rig.mass_model.com_from_fk(g_rot, g_t)[:, 2]
    acc_z = savgol_filter(z, ACC_WINDOW, 3, deriv=2, delta=1.0 / rate_hz) if n >= ACC_WINDOW else np.zeros(n)
    path = ComPath(com_path.support, com_path.weight, zmp_com(com_path.support, rate_hz, z / (1.0 + acc_z / 9.81)))
    for _ in range(_COM_ROUNDS):
        follow_com(rig, transl, path, g_rot, g_t)
        limbs.put(g_rot, g_t)
        g_rot, g_t = rig.fk(local)

"""Where each contact part is locked on the floor: the first half of the ground solve
(``sim.motion.ground``).

- ``EndRotations``: the world orientation of each foot (flat at its touch-down yaw, or on
  the toes) and each wrist (palm flat) while they touch, blended in the air.
- ``Posed``: the posed body measured once, pelvis at the origin (lock points, lowest point
  of each part).
- ``anchor_chain``: the pelvis placed from the lock of the part that carries it (the
  anchor), span by span; every limb touching down gets its lock from that placement.
- ``limb_locks``: per limb, the frames to solve by IK, their weights and lock targets (a
  foot's ball at one height per contact span); ``swing_targets``: the planned swing paths.

Arrays are over frames (leading axis T); part indices are ``sim.motion.rig``'s LF … BACK.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import NamedTuple

import numpy as np

from sim.motion.rig import BACK, BUTT, CHAINS, LF, LH, LOCK_JOINT, RF, RH, SETTLE, UPRIGHT, Rig, rot_x, rot_z
from sim.motion.spans import (
    SMOOTH_FRAMES,
    bridge_gaps,
    hold_at_span_start,
    min_jerk,
    near_contact_weight,
    slerp_mats,
    span_start_index,
)
from sim.motion.swing import swing_ankle_path, swing_spans

LIMBS = (LF, RF, LH, RH)
_MAX_SWING_S = 1.2  # a foot off the floor longer than this is not a walking step's swing

Lock = tuple[int, int]  # (limb, first frame of its contact span)


@dataclass(frozen=True)
class Schedule:
    """The contact schedule: contact (T,6) bool over CONTACT_PARTS; anchor (T,) the part
    carrying the root (or SETTLE); heel (T,2) each foot's heel raise (rad); per limb the
    first frame of the contact span each frame belongs to (span_of) and its touch-downs."""

    contact: np.ndarray
    anchor: np.ndarray
    heel: np.ndarray
    span_of: dict[int, np.ndarray]
    touch: dict[int, np.ndarray]

    @classmethod
    def of(cls, contact: np.ndarray, anchor: np.ndarray, heel_deg: np.ndarray) -> "Schedule":
        contact = np.asarray(contact, bool)
        span_of = {q: span_start_index(contact[:, q]) for q in LIMBS}
        touch = {q: np.flatnonzero(contact[:, q] & ~np.r_[False, contact[:-1, q]]) for q in LIMBS}
        return cls(contact, np.asarray(anchor), np.radians(heel_deg), span_of, touch)


@dataclass(frozen=True)
class EndRotations:
    """World orientations of the feet (T,3,3) and the toes' local rotation (T,3,3) per foot
    in use; of the wrists (T,3,3) per hand that touches; per hand the weight (T,) of its
    lock, ramping in and out over 4 frames around contact."""

    foot: dict[int, np.ndarray]
    toe: dict[int, np.ndarray]
    wrist: dict[int, np.ndarray]
    blend: dict[int, np.ndarray]
    feet_used: tuple[int, ...]

    @classmethod
    def of(cls, sched: Schedule, foot_yaw: np.ndarray, hand_rot: np.ndarray | None) -> "EndRotations":
        """foot_yaw: (T,2) world yaw of each foot (rad) used when it touches down; hand_rot:
        optional (T,2,3,3) world orientation of the wrists while the hands touch."""
        contact, heel = sched.contact, sched.heel
        # In contact flat (or on the toes) at the yaw of touch-down; in the air blended from the
        # last lock to the next one, so a foot never snaps on lift-off.
        foot = {}
        for p in (LF, RF):
            yaw = hold_at_span_start(contact[:, p], foot_yaw[:, p])
            yaw, hl = bridge_gaps(contact[:, p], yaw), bridge_gaps(contact[:, p], heel[:, p].copy())
            foot[p] = rot_z(yaw) @ UPRIGHT @ rot_x(hl)
        toe = {p: rot_x(-0.8 * np.maximum(heel[:, p], 0.0)) for p in (LF, RF)}
        wrist = {}
        if hand_rot is not None:
            for p in (LH, RH):
                if contact[:, p].any():
                    wrist[p] = hand_rot[span_start_index(contact[:, p]), p - LH]
        blend = {p: near_contact_weight(contact[:, p], 4) for p in (LH, RH)}
        feet_used = tuple(p for p in (LF, RF) if contact[:, p].any())
        return cls(foot, toe, wrist, blend, feet_used)

    def apply(self, rig: Rig, local: np.ndarray, frames: np.ndarray, g_rot: np.ndarray) -> None:
        """Feet and wrists of ``local`` (in place) to their world orientations in ``frames``
        (index array); g_rot the FK of local[frames]."""
        for p in self.feet_used:
            ankle = CHAINS[p][2]
            local[frames, ankle] = np.swapaxes(g_rot[:, rig.parents[ankle]], -1, -2) @ self.foot[p][frames]
            local[frames, LOCK_JOINT[p]] = self.toe[p][frames]  # toes stay on the floor
        for p in self.wrist:
            sel = self.blend[p][frames] > 0
            if not sel.any():
                continue
            f = frames[sel]
            wrist = CHAINS[p][2]
            want = np.swapaxes(g_rot[sel, rig.parents[wrist]], -1, -2) @ self.wrist[p][f]
            local[f, wrist] = slerp_mats(local[f, wrist], want, self.blend[p][f])


@dataclass(frozen=True)
class Posed:
    """The posed body, pelvis at the origin: lock points (T,6,3), lowest vertex of each part
    (T,6) and each ankle's height above its foot's lowest point (T,) (the foot's orientation
    sets it)."""

    lock_local: np.ndarray
    part_low: np.ndarray
    ankle_drop: dict[int, np.ndarray]

    @classmethod
    def of(cls, rig: Rig, local: np.ndarray) -> "Posed":
        g = rig.fk(local)
        z = rig.vertex_z(local, g)
        part_low = np.stack([z[:, idx].min(1) for idx in rig.part_vertices], 1)
        ankle_drop = {q: g[1][:, CHAINS[q][2], 2] - part_low[:, q] for q in (LF, RF)}
        return cls(g[1][:, list(LOCK_JOINT)], part_low, ankle_drop)

    def floor_z(self, rig: Rig, heel: np.ndarray, q: int, t0: int) -> float:
        """Height of limb q's lock point when it rests on the floor at frame t0."""
        if q in (LF, RF) and heel[t0, q] == 0:
            return rig.ball_height[q]
        return self.lock_local[t0, q, 2] - self.part_low[t0, q]


def anchor_chain(rig: Rig, sched: Schedule, posed: Posed, start_xy) -> tuple[np.ndarray, dict[Lock, np.ndarray]]:
    """Place the pelvis span by span of the anchor: transl (T,3) is the anchor's locked point
    minus its pelvis-relative position, continuous where the anchor changes (a jump spread
    over SMOOTH_FRAMES). Returns transl and the locks (world points) of every limb span."""
    anchor = sched.anchor
    n = len(anchor)
    transl = np.zeros((n, 3))
    starts = np.flatnonzero(np.r_[True, anchor[1:] != anchor[:-1]])
    ends = np.r_[starts[1:], n]
    w_prev: tuple[int, np.ndarray] | None = None
    locks: dict[Lock, np.ndarray] = {}
    for s, e in zip(starts, ends):
        p = int(anchor[s])
        settle = p == SETTLE
        if settle:  # xy follow the left foot's lock; z blends between feet and buttocks
            p = LF
        w = _anchor_point(rig, sched, posed, locks, int(s), p, w_prev, start_xy)
        down = w_prev is None or w_prev[0] in LIMBS
        _place_span(sched, posed, transl, int(s), int(e), p, w, settle, down)
        w_prev = (p, w)
        _lock_touchdowns(rig, sched, posed, transl, locks, int(s), int(e), p)
    return transl, locks


def _anchor_point(rig: Rig, sched: Schedule, posed: Posed, locks: dict[Lock, np.ndarray], s: int, p: int,
                  w_prev: tuple[int, np.ndarray] | None, start_xy) -> np.ndarray:
    """The world point of anchor part p from frame s on: over start_xy at the start,
    continuing the previous anchor's placement after a switch, a limb's lock when it is one."""
    lock_local = posed.lock_local
    if w_prev is None:
        w = np.array([start_xy[0], start_xy[1], 0.0]) + lock_local[s, p] * [1, 1, 0]  # pelvis over start_xy
    else:
        q, wq = w_prev
        # continuity of transl at the switch; from one foot to the other (a step) as the body is
        # on the frame before, where the landing foot touches: by s the push-off has begun
        f = s - 1 if s > 0 and p in (LF, RF) and q in (LF, RF) else s
        w = wq - lock_local[f, q] + lock_local[f, p]
    if p in sched.span_of and sched.contact[s, p]:
        key = (p, int(sched.span_of[p][s]))
        if key in locks:  # already locked as a non-anchor limb: keep that lock
            w = locks[key].copy()
        else:
            w[2] = posed.floor_z(rig, sched.heel, p, s)
            locks[key] = w
    return w


def _place_span(sched: Schedule, posed: Posed, transl: np.ndarray, s: int, e: int, p: int, w: np.ndarray,
                settle: bool, down: bool) -> None:
    """transl (in place) over frames s:e from anchor p at world point w. Resting parts keep
    their lowest point on the floor; a settle blends from the feet down to the buttocks
    (down) or back up."""
    lock_local, part_low, contact, heel = posed.lock_local, posed.part_low, sched.contact, sched.heel
    seg = slice(s, e)
    transl[seg] = w - lock_local[seg, p]
    if p in (BUTT, BACK):
        transl[seg, 2] = -part_low[seg, p]
    elif p in (LF, RF):  # rolling on the heel (toes up): the heel, not the locked ball, is on the floor
        rock = np.flatnonzero(contact[seg, p] & (heel[seg, p] < 0)) + s
        transl[rock, 2] = -part_low[rock, p]
    if settle:
        ramp = min_jerk((np.arange(e - s) + 1.0) / (e - s))
        ramp = ramp if down else 1.0 - ramp
        transl[seg, 2] = (1 - ramp) * transl[seg, 2] + ramp * (-part_low[seg, BUTT])
    if s >= 2:  # spread a jump at the switch over the next frames
        jump = transl[s] - (2 * transl[s - 1] - transl[s - 2])
        k = min(SMOOTH_FRAMES, e - s)
        fade = 1.0 - min_jerk((np.arange(k) + 1.0) / (SMOOTH_FRAMES + 1.0))
        transl[s:s + k] -= fade[:, None] * jump


def _lock_touchdowns(rig: Rig, sched: Schedule, posed: Posed, transl: np.ndarray, locks: dict[Lock, np.ndarray],
                     s: int, e: int, p: int) -> None:
    """Limbs other than the anchor p touching down in frames s:e (or touching at s) are
    locked where this placement puts them, at floor height (first lock of a span wins)."""
    for q in LIMBS:
        if q == p:
            continue
        touch = sched.touch[q]
        t0s = touch[(touch > s) & (touch < e)]
        if sched.contact[s, q]:
            t0s = np.r_[sched.span_of[q][s], t0s]
        for t0 in t0s:
            t0 = int(t0)
            if (q, t0) not in locks:
                wq = transl[t0] + posed.lock_local[t0, q]
                wq[2] = posed.floor_z(rig, sched.heel, q, t0)
                locks[(q, t0)] = wq


class LimbLock(NamedTuple):
    """One limb's IK work: frames (N,), weight (N,) of the lock (1 in contact; hands ramp in
    and out), target (N,3) world point of the chain's end (ankle or wrist), on (N,) bool in contact."""

    frames: np.ndarray
    weight: np.ndarray
    target: np.ndarray
    on: np.ndarray


def limb_locks(rig: Rig, sched: Schedule, posed: Posed, ends: EndRotations, transl: np.ndarray,
               locks: dict[Lock, np.ndarray]) -> dict[int, LimbLock]:
    """Per limb in contact somewhere: the frames to solve, weights and end targets (a frame
    out of contact takes the lock of its nearest contact span)."""
    contact = sched.contact
    n = len(contact)
    t_idx = np.arange(n)
    solve = {}
    for q in LIMBS:
        c = contact[:, q]
        if not c.any():
            continue
        weight = ends.blend[q] if q in ends.blend else c.astype(float)
        frames = np.flatnonzero(weight > 0)
        prev_c = np.maximum.accumulate(np.where(c, t_idx, -1))
        next_c = np.minimum.accumulate(np.where(c, t_idx, n)[::-1])[::-1]
        f = frames
        near = np.where(c[f], f, np.where((f - prev_c[f] <= next_c[f] - f) & (prev_c[f] >= 0), prev_c[f], next_c[f]))
        near = np.clip(near, 0, n - 1)
        span0 = sched.span_of[q][near]
        keys, inv = np.unique(span0, return_inverse=True)
        table = np.stack([locks[(q, int(k0))] if (q, int(k0)) in locks else transl[k0] + posed.lock_local[k0, q]
                          for k0 in keys])
        target = table[inv]
        if q in (LF, RF):
            target = _ankle_targets(rig, sched, posed, ends, q, frames, span0, target)
        solve[q] = LimbLock(frames, weight[frames], target, c[frames])
    return solve


def _ankle_targets(rig: Rig, sched: Schedule, posed: Posed, ends: EndRotations, q: int, frames: np.ndarray,
                   span0: np.ndarray, target: np.ndarray) -> np.ndarray:
    """Foot q's ball targets (N,3) → its ankle targets: the ball's height follows the heel
    raise (sole or toes on the floor), one height per contact span."""
    heel, c = sched.heel, sched.contact[:, q]
    on = c[frames]
    zf = np.where(heel[frames, q] != 0, posed.lock_local[frames, q, 2] - posed.part_low[frames, q], rig.ball_height[q])
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
    return target - np.einsum("nij,j->ni", ends.foot[q][frames], rig.foot_vec[q])


def swing_targets(sched: Schedule, swing: np.ndarray | None, rate_hz: float, solve: dict[int, LimbLock],
                  posed: Posed) -> dict[int, tuple[np.ndarray, np.ndarray]]:
    """Per foot, (frames (N,), ankle targets (N,3)) of its planned swings (``sim.motion.swing``)
    in the frames of ``swing`` (T,) bool; none without it."""
    swing_ik = {}
    n = len(sched.contact)
    for q in (LF, RF) if swing is not None else ():
        if q not in solve:
            continue
        spans = swing_spans(sched.contact[:, q], swing, int(round(_MAX_SWING_S * rate_hz)))
        if spans:
            ankle = np.zeros((n, 3))
            ankle[solve[q].frames] = solve[q].target
            ends = np.array(spans)
            swing_ik[q] = swing_ankle_path(spans, ankle[ends[:, 0]], ankle[ends[:, 1]], posed.ankle_drop[q])
    return swing_ik

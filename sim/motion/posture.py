"""Whole-body corrections of the ground solve (``sim.motion.ground``): the COM carried along
its balanced path over the feet, a floor sitter's trunk over the buttocks, a lying body's
back and pelvis both on the floor.

Each works in place on a sequence's local rotations (T,24,3,3) (joint 0 the world
orientation) or its pelvis translation (T,3), for one ``Rig``; faded in and out over a few
frames around the spans it applies to, so that no correction makes a jump.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import NamedTuple

import numpy as np
from scipy.spatial.transform import Rotation

from sim.motion.balance import left_weight, support_point, zmp_com
from sim.motion.rig import BACK, BUTT, LF, LH, LOCK_JOINT, RF, RH, J, Rig, rot_x
from sim.motion.spans import SMOOTH_FRAMES, near_contact_weight

SIT_COM_FRAC = 0.08  # seated COM this far from the lowest point of the buttocks toward the feet (~84 % on the buttocks)
_UPPER_LEVER_M = 0.17  # COM shift per radian of lower-spine flexion (upper-body mass share × its lever)
_LIE_FADE = 12  # frames over which the lying correction fades out into a curl (and in before lying down)
SACRUM_DROP_M = 0.03  # m the pelvis lies lower than the back when supine: the sacrum and buttocks carry the heavy pelvis

# Puts the locked limbs back on their locks after the pelvis moved, given the FK (g_rot, g_t).
PutLimbs = Callable[[np.ndarray, np.ndarray], None]


class ComPath(NamedTuple):
    """The balanced path of the COM: support point (T,2) (the ZMP wanted), weight (T,) of the
    correction (1 standing on the feet alone, fading to 0 around those spans), COM (T,2)."""

    support: np.ndarray
    weight: np.ndarray
    desired: np.ndarray


def follow_com(rig: Rig, transl: np.ndarray, path: ComPath, g_rot: np.ndarray, g_t: np.ndarray) -> None:
    """Shift the pelvis (in place) by the COM's distance from its path; g_rot, g_t the FK."""
    com = transl[:, :2] + rig.mass_model.com_from_fk(g_rot, g_t)[:, :2]
    transl[:, :2] += path.weight[:, None] * (path.desired - com)


def balance_com(rig: Rig, local: np.ndarray, transl: np.ndarray, contact: np.ndarray, anchor: np.ndarray,
                heel: np.ndarray, foot_rot: dict[int, np.ndarray], balance: np.ndarray, rate_hz: float,
                put_limbs: PutLimbs, rounds: int = 3) -> ComPath | None:
    """Shift the pelvis (in place) where the body stands on its feet alone so that the COM
    follows the path whose zero-moment point is the feet's support point; faded in and out
    over a few frames around those spans. ``put_limbs`` puts the locked feet back by IK.

    contact: (T,6) bool; anchor: (T,); heel: (T,2) heel raise (rad); foot_rot: each foot's
    world orientation (T,3,3); balance: (T,) bool, the frames this applies to.
    Returns the path for the later passes, or None where nobody stands on the feet alone."""
    feet = contact[:, [LF, RF]]
    feet_only = feet.any(1) & ~contact[:, [LH, RH, BUTT, BACK]].any(1) & np.isin(anchor, (LF, RF)) & balance
    if not feet_only.any():
        return None
    wgt = near_contact_weight(feet_only, SMOOTH_FRAMES + 1)
    desired = None
    for _ in range(rounds):
        g_rot, g_t = rig.fk(local)
        com = transl[:, :2] + rig.mass_model.com_from_fk(g_rot, g_t)[:, :2]
        if desired is None:
            p = com.copy()
            pts = {q: support_point(transl + g_t[:, LOCK_JOINT[q]], foot_rot[q], rig.foot_geometry[q],
                                    heel[:, q]) for q in (LF, RF)}
            w = left_weight(feet[:, 0], feet[:, 1], rate_hz)[:, None]
            p[feet_only] = (w * pts[LF] + (1.0 - w) * pts[RF])[feet_only]
            desired = zmp_com(p, rate_hz, rig.com_height)
        transl[:, :2] += wgt[:, None] * (desired - com)
        put_limbs(g_rot, g_t)
    return ComPath(p, wgt, desired)


def sit_over_buttocks(rig: Rig, local: np.ndarray, contact: np.ndarray, anchor: np.ndarray, seated: np.ndarray,
                      rounds: int = 3) -> None:
    """Sitting on the floor without the hands: flex (or extend) the lower spine so that the
    COM lies over the seat, SIT_COM_FRAC of the way from the buttocks toward the feet (the
    buttocks then carry most of the weight, as a seated body's own mass distribution says).
    seated: (T,) bool, the frames of a floor sitter."""
    sit = (anchor == BUTT) & contact[:, BUTT] & ~contact[:, [BACK, LH, RH]].any(1) & seated
    if not sit.any():
        return
    wgt = near_contact_weight(sit, SMOOTH_FRAMES + 1)
    f = np.flatnonzero(wgt > 0)
    for _ in range(rounds):
        g_rot, g_t = rig.fk(local[f])
        com = rig.mass_model.com_from_fk(g_rot, g_t)
        pv = rig.skinned(local[f], (g_rot, g_t))[:, rig.pelvis_vertices]
        seat = pv[np.arange(len(f)), pv[:, :, 2].argmin(1)]
        feet = 0.25 * sum(g_t[:, J[n]] for n in ("left_ankle", "right_ankle", "left_foot", "right_foot"))
        d = feet[:, :2] - seat[:, :2]
        u = d / np.maximum(np.linalg.norm(d, axis=1, keepdims=True), 1e-6)
        e = np.sum((com[:, :2] - seat[:, :2] - SIT_COM_FRAC * d) * u, 1)  # > 0: COM too far toward the feet
        angle = np.clip(-e / _UPPER_LEVER_M, -0.5, 0.5) * wgt[f]
        local[f, J["spine1"]] = local[f, J["spine1"]] @ rot_x(angle)


def rest_on_back(rig: Rig, local: np.ndarray, contact: np.ndarray) -> None:
    """Where the back and the buttocks are both scheduled on the floor, pitch the root so
    that the back and the pelvis (sacrum, buttocks; not the backs of the thighs, which a
    flexed hip lowers) are equally low, the pelvis SACRUM_DROP_M lower. The frames around a
    lying span take the nearest lying frame's correction, fading over _LIE_FADE frames (most
    of a curl): refitted to a back already rising, or faded faster than the curl lifts the
    trunk, it pitched the trunk back down toward the template's and up again."""
    lying = contact[:, BACK] & contact[:, BUTT]
    f = np.flatnonzero(lying)
    if len(f) == 0:
        return
    total = Rotation.identity(len(f))
    for _ in range(4):
        g = rig.fk(local[f])
        z = rig.vertex_z(local[f], g)
        dz = z[:, rig.part_vertices[BACK]].min(1) - z[:, rig.pelvis_vertices].min(1) - SACRUM_DROP_M
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

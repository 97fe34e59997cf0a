"""Pacing: how long a key must last so that the centre of mass moves up or down no faster
than a controlled movement does.

A key moves the body between two poses with minimum-jerk timing (joint angles
θ(τ) = θ₀ + (θ₁ − θ₀)·s(τ), τ = t/T); the COM height h follows, and its vertical
acceleration is h''(τ)/T² — at least 10/√3·Δh/T² (a height linear in the angles), more
where the height changes fastest late in a deep flexion. People squat, bend, sit down and do push-ups and sit-ups under control: the
floor force stays within about 0.9–1.1 × body weight (issue 13), so the COM's vertical
acceleration stays under about 0.1 g. A key that would exceed ``limit_m_s2`` is lengthened
to the shortest duration that keeps it:

    T_min = √(max_τ |h''(τ)| / a_max)

The COM height of a key pose is measured above the lowest of the parts that carry the
body during the key (its contact schedule; a key that settles onto the buttocks counts
them too), with the subject's own segment mass model (``sim.contact.segments``), so
heavier and taller bodies and deeper templates are paced by their own geometry.

    pacer = Pacer(rig, limit_m_s2=0.8)
    tl = Timeline(pace=pacer)          # Timeline.add lengthens keys that move too fast
"""

from __future__ import annotations

import math

import numpy as np

from edge.body.rotations import euler_xyz_deg_to_matrix
from sim.motion.rig import BUTT, CONTACT_PARTS, SETTLE, UPRIGHT
from sim.motion.spans import min_jerk

MIN_JERK_PEAK_ACC = 10.0 / math.sqrt(3.0)  # max |s''| of s(τ) = 10τ³ − 15τ⁴ + 6τ⁵ on [0, 1]
_TAU = np.linspace(0.0, 1.0, 17)  # where a key's height is followed


class Pacer:
    """Minimum key durations for one body (``rig``: a sim.motion.rig.Rig)."""

    def __init__(self, rig, limit_m_s2: float):
        if limit_m_s2 <= 0:
            raise ValueError(f"limit_m_s2 must be positive, got {limit_m_s2}")
        self.rig = rig
        self.limit_m_s2 = float(limit_m_s2)
        self._cache: dict = {}

    def com_height_m(self, pose_deg: np.ndarray, contact: np.ndarray) -> np.ndarray:
        """COM height above the lowest contact part of poses (N,24,3) (or one (24,3)) in Euler
        degrees, root tilt relative to upright; contact (6,) over CONTACT_PARTS (none: the
        lowest vertex). Returns (N,) (or a float)."""
        pose_deg = np.asarray(pose_deg, float)
        one = pose_deg.ndim == 2
        poses = pose_deg[None] if one else pose_deg
        local = euler_xyz_deg_to_matrix(poses)
        local[:, 0] = UPRIGHT @ local[:, 0]
        g_rot, g_t = self.rig.fk(local)
        com_z = self.rig.mass_model.com_from_fk(g_rot, g_t)[:, 2]
        parts = np.flatnonzero(np.asarray(contact, bool)[:len(CONTACT_PARTS)])
        idx = np.concatenate([self.rig.part_vertices[p] for p in parts]) if len(parts) else None
        h = com_z - self.rig.vertex_z(local, (g_rot, g_t), idx).min(1)
        return float(h[0]) if one else h

    def min_duration_s(self, pose_from: np.ndarray, pose_to: np.ndarray, contact: np.ndarray, anchor: int) -> float:
        """Shortest duration of a key from pose_from to pose_to under this contact schedule: the
        height is followed along the key's minimum-jerk path (it changes fastest where the
        joints are most flexed), so T_min = √(max |d²h/dτ²| / a_max) over τ in [0, 1]."""
        a, b = np.asarray(pose_from, float), np.asarray(pose_to, float)
        if np.array_equal(a, b):
            return 0.0
        c = np.asarray(contact, bool).copy()
        if anchor == SETTLE:  # sitting down or getting up: the buttocks meet the floor
            c[BUTT] = True
        key = (a.tobytes(), b.tobytes(), c.tobytes())
        if key not in self._cache:
            s = min_jerk(_TAU)
            h = self.com_height_m(a[None] + (b - a)[None] * s[:, None, None], c)
            acc = np.abs(np.diff(h, 2)) / (_TAU[1] - _TAU[0]) ** 2
            self._cache[key] = math.sqrt(float(acc.max()) / self.limit_m_s2)
        return self._cache[key]

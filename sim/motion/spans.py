"""Frame masks and ramps for contact spans: where a span starts, values held over it or
bridged between spans, weights that ramp in and out around it, and the minimum-jerk warp
they ramp with. Pure array functions over a (T,) time axis.

    w = near_contact_weight(contact[:, part], 4)   # (T,) 1 in contact, 0 four frames away
"""

from __future__ import annotations

import numpy as np
from scipy.spatial.transform import Rotation

SMOOTH_FRAMES = 4  # frames over which the ground solve spreads a correction of the pelvis (sim.motion.ground)


def min_jerk(s: np.ndarray) -> np.ndarray:
    """Minimum-jerk time warp of s in [0, 1] (zero velocity and acceleration at the ends)."""
    s = np.clip(s, 0.0, 1.0)
    return s * s * s * (10.0 - 15.0 * s + 6.0 * s * s)


def envelope(x: np.ndarray, k: int) -> np.ndarray:
    """A smooth curve ≥ x: a running max over ±k frames, then twice a running mean over ±k/2
    (piecewise quadratic: no corners, so no spikes of acceleration)."""
    from scipy.ndimage import maximum_filter1d, uniform_filter1d
    h = max(k // 2, 1)
    m = maximum_filter1d(x, 4 * h + 1, mode="nearest")
    return uniform_filter1d(uniform_filter1d(m, 2 * h + 1, mode="nearest"), 2 * h + 1, mode="nearest")


def span_start_index(mask: np.ndarray) -> np.ndarray:
    """For each frame, the first frame of the run of equal values it belongs to."""
    n = len(mask)
    change = np.r_[True, mask[1:] != mask[:-1]]
    idx = np.where(change, np.arange(n), 0)
    return np.maximum.accumulate(idx)


def hold_at_span_start(mask: np.ndarray, values: np.ndarray) -> np.ndarray:
    """values frozen at the start of each contact span (free outside contact)."""
    out = values.copy()
    start = span_start_index(mask)
    out[mask] = values[start[mask]]
    return out


def bridge_gaps(mask: np.ndarray, values: np.ndarray) -> np.ndarray:
    """Outside the mask, interpolate (min-jerk) between the last value before and the next after."""
    out = values.astype(np.float64).copy()
    n = len(mask)
    idx = np.flatnonzero(mask)
    if len(idx) == 0:
        return out
    gaps = np.flatnonzero(~mask)
    if len(gaps) == 0:
        return out
    prev_i = np.maximum.accumulate(np.where(mask, np.arange(n), -1))
    next_i = np.minimum.accumulate(np.where(mask, np.arange(n), n)[::-1])[::-1]
    g = gaps
    a, b = prev_i[g], next_i[g]
    va = np.where(a >= 0, out[np.clip(a, 0, n - 1)], out[np.clip(b, 0, n - 1)])
    vb = np.where(b < n, out[np.clip(b, 0, n - 1)], va)
    s = np.where((a >= 0) & (b < n), (g - a) / np.maximum(b - a, 1), 0.0)
    out[g] = va + (vb - va) * min_jerk(s)
    return out


def near_contact_weight(mask: np.ndarray, k: int) -> np.ndarray:
    """1 in contact, ramping to 0 over k frames before and after each contact span."""
    n = len(mask)
    idx = np.flatnonzero(mask)
    if len(idx) == 0:
        return np.zeros(n)
    t = np.arange(n)
    prev_i = np.maximum.accumulate(np.where(mask, t, -10**9))
    next_i = np.minimum.accumulate(np.where(mask, t, 10**9)[::-1])[::-1]
    dist = np.minimum(t - prev_i, next_i - t).astype(float)
    return min_jerk(np.clip(1.0 - dist / (k + 1), 0.0, 1.0))


def slerp_mats(r0: np.ndarray, r1: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Rotation from r0 toward r1 by fraction w, (N,3,3) each."""
    if len(r0) == 0:
        return r0
    rel = Rotation.from_matrix(np.swapaxes(r0, -1, -2) @ r1).as_rotvec() * w[:, None]
    return r0 @ Rotation.from_rotvec(rel).as_matrix()

"""The swinging foot of a walking step: a planned path from lift-off to touch-down.

A foot that leaves the floor in a walking step goes from where it left (on its toes) to
where it will land (on its heel, toes up) along a path of its own, not wherever the swing
pose of the hip and knee happens to carry it: with the keyframed swing the foot skimmed
the floor (1–3 mm up through mid-swing, loaded by the contact physics whenever the plane
tilted) and touched down a few frames early, sliding on its heel. Here the ankle moves
from its lift-off lock to its touch-down lock (min-jerk along the floor, the way a swing
foot speeds up and slows down), and the foot's lowest point keeps a clearance that rises
from the floor and comes back to it:

    lowest point above the floor = CLEARANCE_M · sin(π·u),  u = (t − t_off)/(t_on − t_off)

(mid-swing toe clearance in gait studies is 1–2 cm; the heel and the toes around it rise
more). The leg follows by two-bone IK (``Rig.two_bone_ik``); the foot's orientation stays
the rig's blend from the lift-off orientation to the touch-down one.

    spans = swing_spans(contact[:, LF], planned, max_frames=20)   # [(t_off, t_on), ...]
    ankle = swing_ankle_path(spans, start, end, drop, n)          # (frames, (N,3) targets)
"""

from __future__ import annotations

import numpy as np

CLEARANCE_M = 0.035  # the foot's lowest point at mid-swing


def swing_spans(on_floor: np.ndarray, planned: np.ndarray, max_frames: int) -> list[tuple[int, int]]:
    """(last frame on the floor, next frame on the floor) of each gap in on_floor (T,) bool
    that lies inside planned (T,) bool, is bounded by contact on both sides and lasts at most
    max_frames frames."""
    on_floor, planned = np.asarray(on_floor, bool), np.asarray(planned, bool)
    d = np.diff(np.r_[0, (~on_floor).astype(np.int8), 0])
    out = []
    for s, e in zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)):
        if s == 0 or e == len(on_floor) or e - s > max_frames or not planned[s:e].all():
            continue
        out.append((int(s - 1), int(e)))
    return out


def swing_ankle_path(spans, ankle_off: np.ndarray, ankle_on: np.ndarray, drop_m: np.ndarray,
                     clearance_m: float = CLEARANCE_M) -> tuple[np.ndarray, np.ndarray]:
    """Ankle targets of the swing frames: spans [(t_off, t_on)]; ankle_off, ankle_on (S,3) the
    ankle's world position at lift-off and at touch-down of each span; drop_m (T,) the ankle's
    height above the foot's lowest point in each frame (the foot's orientation sets it).
    Returns (frames (N,), targets (N,3)): along the floor min-jerk from lift-off to touch-down;
    up, the lowest point at clearance_m·sin(π·u) above the floor (plus whatever the two
    locks' heights differ from a foot resting on the floor, blended linearly)."""
    frames, targets = [], []
    for k, (a, b) in enumerate(spans):
        f = np.arange(a + 1, b)
        u = (f - a) / float(b - a)
        s = u * u * u * (10.0 - 15.0 * u + 6.0 * u * u)
        xy = ankle_off[k, :2] + (ankle_on[k, :2] - ankle_off[k, :2]) * s[:, None]
        rest_a, rest_b = ankle_off[k, 2] - drop_m[a], ankle_on[k, 2] - drop_m[b]
        z = rest_a + (rest_b - rest_a) * u + drop_m[f] + clearance_m * np.sin(np.pi * u)
        frames.append(f)
        targets.append(np.column_stack([xy, z]))
    if not frames:
        return np.zeros(0, int), np.zeros((0, 3))
    return np.concatenate(frames), np.concatenate(targets)

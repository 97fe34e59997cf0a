"""How a body came onto the floor: judged from the stances before it (docs/falls.md, "Arrival").

    secs = arrival(feet, start_t, body, landed_length_m, config, standing=False)   # None: no fall-like arrival
    supported(feet, start_t, touch_m, body)                                       # a descent under control

``feet`` holds the detector's readings of bodies on their feet, oldest first: (t_s, centre (2,), load N).
A *stance* is a stretch of them without a gap longer than RUN_GAP_S. Pure functions: the detector keeps
the readings and the episodes, these only read them.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from edge.scene.falls_config import FallConfig
from edge.scene.falls_features import BodyFeatures

RUN_GAP_S = 0.25  # on-the-feet readings further apart than this are two stances ...
STANCE_JUMP_M = 0.4  # ... and so are two whose centres lie further apart than this (walking, kneeling, sitting
# move it ≤ 0.38 m between frames; a falling body's buttocks, read compact as they land, 0.6 m from its feet)
SEATED_STILL_M = 0.05  # a seated person's feet stay within this of where they rest ...
SEATED_STEADY = 0.25  # ... and their load within this fraction of its usual
STANCE_S = 0.5  # where a stance stood: the median centre over its last this many seconds ...
TIPPING_S = 1.0  # ... and over the second before those (a body toppling pivots on its feet: the centre of pressure
# runs 0.2-0.3 m toward the fall while the feet still carry the load)
# A supported descent is no fall (a push-up from a crouch, lying back from sitting on the floor): from the last reading
# on the feet to the first on the floor the centre of pressure slid at most SUPPORTED_JUMP_M (a falling body's trunk
# lands ≥ 0.24 m from its feet on the tuning falls; push-ups and sit-ups 0.00–0.15 m) while that reading still carried
# at least SUPPORTED_LOAD of the load then lying (a falling body unloads its feet first: ≤ 0.49 on the tuning falls;
# push-ups ≈ 1, the sit-ups that alarmed 0.64–0.92).
SUPPORTED_JUMP_M = 0.15
SUPPORTED_LOAD = 0.55
# ... and that reading ended a stance of at least SUPPORTED_STANCE_S (a crouch, sitting on the floor): a falling body
# that lands compact can read as feet for one frame just before it reads as lying (held-out fall_forward-s6: one
# frame, 0.28 s after the last real reading on the feet), which is no support.
SUPPORTED_STANCE_S = 0.5

Reading = tuple  # (t_s, centre (2,), load N)


def arrival(feet: Sequence[Reading], start_t: float, b: BodyFeatures, landed_length_m: float, c: FallConfig,
            standing: bool) -> float | None:
    """Seconds from the last stance nearby to landing at start_t, judged from where the landed body ``b``
    lies (see the module doc of edge.scene.falls); None: no fall-like arrival. ``standing``: one of the body's
    tracks has stood on its feet for a while (someone beside a dropped bag or a pet lying down)."""
    runs = stances(feet, start_t, b.centre_m, c)
    landed = landed_length_m if np.isfinite(landed_length_m) else b.length_m
    for run in runs:
        end_t = run[0][0]
        if end_t - run[-1][0] < SUPPORTED_STANCE_S and run is runs[0] and len(runs) > 1:
            continue  # under SUPPORTED_STANCE_S on the "feet" just before landing: the landing body itself, read
            # compact (a frame or two; buttocks sliding off a chair, 0.36 s) — nobody stands that briefly
        down = start_t - end_t
        if b.force_n <= c.max_load_ratio * float(np.median([r[2] for r in run])):  # stood here: did the load
            moved = shift_m(run, b.centre_m) >= c.min_shift_m  # did the load move by a body's height?
            return down if moved or collapsed(start_t, run, landed, b, c, standing) else None
        if seated(run, b, c):  # feet under a chair: the whole weight came down onto the floor
            return down
        if collapsed(start_t, run, landed, b, c, standing):  # stood, then went down through a light kneel
            return down
        # lighter than the body now lying and not seated: the body in the air, a hand: look further back
    return None


def shift_m(run: Sequence[Reading], centre_m: np.ndarray) -> float:
    """How far ``centre_m`` lies from where the stance ``run`` (newest first) stood: over its last STANCE_S, or over the
    TIPPING_S before that (before a fall began to topple it), whichever is further."""
    end_t = run[0][0]
    out = 0.0
    for lo, hi in ((end_t - STANCE_S, end_t), (end_t - STANCE_S - TIPPING_S, end_t - STANCE_S)):
        pts = [r[1] for r in run if lo <= r[0] <= hi]
        if pts:
            out = max(out, float(np.linalg.norm(np.median(pts, axis=0) - centre_m)))
    return out


def stances(feet: Sequence[Reading], start_t: float, centre_m: np.ndarray, c: FallConfig) -> list[list]:
    """The stances before start_t within fall_radius_m of centre_m, newest first, each newest first: stretches of
    on-the-feet readings without a gap longer than RUN_GAP_S or a jump of the centre longer than STANCE_JUMP_M."""
    runs: list[list] = []
    for r in reversed(feet):
        if r[0] >= start_t or np.linalg.norm(r[1] - centre_m) > c.fall_radius_m:
            continue
        if not runs or runs[-1][-1][0] - r[0] > RUN_GAP_S or np.linalg.norm(runs[-1][-1][1] - r[1]) > STANCE_JUMP_M:
            runs.append([])
        runs[-1].append(r)
    return runs


def supported(feet: Sequence[Reading], start_t: float, touch_m: np.ndarray, b: BodyFeatures, c: FallConfig) -> bool:
    """A descent under control (a push-up from a crouch, lying back from sitting): the last reading on the feet
    came just before the first touch (within RUN_GAP_S) at the end of a stance of SUPPORTED_STANCE_S, the centre
    of pressure slid from it to where the body first touched (``touch_m``, at most SUPPORTED_JUMP_M) and it still
    carried at least SUPPORTED_LOAD of the load ``b`` now lying. A falling body unloads its feet and lands its
    trunk away from them."""
    runs = stances(feet, start_t, b.centre_m, c)
    if not runs or start_t - runs[0][0][0] > RUN_GAP_S:
        return False
    last = runs[0][0]
    return (last[0] - runs[0][-1][0] >= SUPPORTED_STANCE_S and float(np.linalg.norm(touch_m - last[1])) <= SUPPORTED_JUMP_M
            and last[2] >= SUPPORTED_LOAD * b.force_n)


def collapsed(start_t: float, run: Sequence[Reading], landed_length_m: float, b: BodyFeatures, c: FallConfig,
              standing: bool) -> bool:
    """Someone who crumpled where they stood (knees giving way, then over to the side): the stance ``run``
    (newest first) ended at most collapse_window_s before the landing at start_t and carried a standing
    load (at least 1/max_load_ratio of the body ``b`` now lying) at most collapse_s before it (kneeling
    reads light; a deliberate lie-down stays low for longer); the body landed at full length and stayed
    so (``landed_length_m``, its shortest since landing, median-filtered, at least collapse_min_length_m: a
    push-up gets down onto hands and feet first, then stretches into the plank) or lies crumpled over at
    least collapse_min_area_m2 (trunk, hips and legs down together), and none of its tracks is
    still ``standing`` (the feet of someone beside a dropped bag or a pet lying down)."""
    if start_t - run[0][0] > c.collapse_window_s or standing:
        return False
    if landed_length_m < c.collapse_min_length_m and b.area_m2 < c.collapse_min_area_m2:
        return False
    return any(r[0] >= start_t - c.collapse_s and b.force_n <= c.max_load_ratio * r[2] for r in run)


def seated(run: Sequence[Reading], b: BodyFeatures, c: FallConfig) -> bool:
    """Someone seated on a chair beside the carpet: a footprint held still and steady (within SEATED_STILL_M of
    where it mostly was, its load within SEATED_STEADY of its usual) for seated_s without a break, carrying at
    most 1/seated_load_ratio of the load now lying on the floor. A squat or a hand going down keeps moving."""
    where = np.median([r[1] for r in run], axis=0)
    near = [np.linalg.norm(r[1] - where) <= SEATED_STILL_M for r in run]
    if not any(near):
        return False
    usual = float(np.median([r[2] for r, n in zip(run, near) if n]))
    best, first = 0.0, None  # the longest unbroken still, steady stretch (run is newest first)
    for r, n in zip(run, near):
        if n and abs(r[2] - usual) <= SEATED_STEADY * usual:
            first = r[0] if first is None else first
            best = max(best, first - r[0])
        else:
            first = None
    return best >= c.seated_s and b.force_n >= c.seated_load_ratio * usual


__all__ = ["RUN_GAP_S", "SUPPORTED_LOAD", "arrival", "collapsed", "seated", "stances", "supported"]

"""Step 4 (optional), auto-range: set the front-end gain potentiometer so that at most
1 % of the active sensels sit at the rail while someone stands on the carpet.

Pure logic plus a callback: ``capture(step) -> (N, H, W) counts`` reads a few frames at
a potentiometer step (live: through the board; sim: a model). Binary search over the
steps of a :class:`edge.peripherals.GainControl` for the highest gain whose rail
fraction is ≤ 1 % (more gain = more resolution at light loads).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from calibration.result import StepResult

MAX_RAIL_FRACTION = 0.01


def rail_fraction(frames: np.ndarray, baseline: np.ndarray, noise: np.ndarray, sign: int, full_scale: int,
                  usable: np.ndarray) -> float:
    """Fraction of active sensels (> 6σ from baseline) that read the rail code."""
    rail = full_scale if sign > 0 else 0
    d = sign * (frames - baseline[None])
    active = (d > 6.0 * noise[None]) & usable[None]
    at = active & (frames == rail)
    return float(at.sum() / max(active.sum(), 1))


def auto_range(gain_control, capture: Callable[[int], np.ndarray], baseline: np.ndarray, noise: np.ndarray,
               sign: int, full_scale: int, usable: np.ndarray) -> StepResult:
    res = StepResult("autorange")
    lo, hi = 0, gain_control.step_count - 1
    tried: dict[int, float] = {}
    while lo < hi:
        mid = (lo + hi + 1) // 2
        gain_control.set_step(mid)
        frac = rail_fraction(capture(mid), baseline, noise, sign, full_scale, usable)
        tried[mid] = frac
        if frac <= MAX_RAIL_FRACTION:
            lo = mid
        else:
            hi = mid - 1
    gain_control.set_step(lo)
    frac = tried.get(lo)
    if frac is None:
        frac = rail_fraction(capture(lo), baseline, noise, sign, full_scale, usable)
    res.numbers.update(step=lo, rail_fraction=round(frac, 4), tried={int(k): round(v, 4) for k, v in tried.items()})
    res.say(f"gain step {lo} of {gain_control.step_count - 1}: {frac:.1%} of active sensels at the rail "
            f"(limit {MAX_RAIL_FRACTION:.0%})")
    if frac > MAX_RAIL_FRACTION:
        return res.refuse("even the lowest gain leaves more than 1 % of active sensels at the rail", retry=False)
    res.say("the analogue gain changed: the empty capture is taken again at this setting")
    return res

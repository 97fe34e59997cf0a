"""Step 8: assemble the calibration from the steps' results, validate it, save it.

Validation figures: usable sensels, faulty lines, the noise floor in kPa (the
pressure a median sensel needs to clear its 3σ gate), and the total-force error on a
held-out stance: A·(Σ uncensored P + φ · n_censored · P_sat) against m·g (φ from the
stance step). Target ≤ 15 % (10 % is good).
"""

from __future__ import annotations

from typing import Any

import numpy as np

from calibration.apply import Applier
from calibration.capture import Capture, frame_validity
from calibration.file import FAULT, UNUSABLE, Calibration, Curve
from calibration.result import StepResult

G_M_S2 = 9.81
FORCE_TARGET = 0.15


def assemble(device: dict[str, Any], pitch_m: float, empty: StepResult, walk: StepResult | None,
             board: StepResult | None, stance: StepResult | None, mask: np.ndarray | None = None,
             crosstalk_r_norm: float = 0.0, temperature_c: float | None = None) -> Calibration:
    """A Calibration from the step results (missing steps: gain 1, the note's typical curve)."""
    fault = empty.arrays["fault"].copy()
    if walk is not None:
        fault |= walk.arrays["fault"]
    if mask is not None:
        fault[~mask.astype(bool)] |= FAULT["outside"]
    gain = np.ones(fault.shape, np.float32)
    if board is not None:
        gain = board.arrays["gain"].copy()
        raw = board.arrays["raw_gain"]
        too_weak = ((fault & FAULT["weak"]) > 0) & (raw < 0.5)
        fault[too_weak] |= FAULT["dead"]  # half-dead beyond what a gain can correct
    base = empty.arrays["baseline_counts"]
    if stance is not None:
        ph, n, span, psat = (float(v) for v in stance.arrays["curve"])
        curve = Curve(ph, n, span, psat)
    else:
        from calibration.board import default_curve
        curve = default_curve(base, int(device["sign"]), (1 << int(device["adc_bits"])) - 1, (fault & UNUSABLE) == 0)
    line_faults = list(empty.numbers.get("line_faults", [])) + (list(walk.numbers.get("line_faults", [])) if walk else [])
    steps = {r.step: {k: v for k, v in r.numbers.items() if k != "line_faults"}
             for r in (empty, walk, board, stance) if r is not None}
    gain[(fault & UNUSABLE) > 0] = 1.0
    return Calibration(baseline_counts=base, noise_counts=empty.arrays["noise_counts"], gain=gain, fault=fault,
                       device=dict(device), pitch_m=pitch_m, curve=curve, crosstalk_r_norm=crosstalk_r_norm,
                       temperature_c=temperature_c, line_faults=line_faults, steps=steps)


def force_estimate_n(applied, pitch_m: float, fill_ratio: float, saturation_kpa: float) -> tuple[float, float]:
    """(lower bound, estimate) of the total force in N of one applied frame."""
    a = pitch_m**2 * 1e3
    p = applied.pressure_kpa
    unc = float(p[~applied.saturated].sum()) * a
    n_c = int(applied.saturated.sum())
    return unc + n_c * saturation_kpa * a, unc + n_c * saturation_kpa * fill_ratio * a


def validation(cal: Calibration, holdout: Capture | None, mass_kg: float | None, fill_ratio: float = 1.0) -> StepResult:
    res = StepResult("validation")
    usable = cal.usable
    n_use, n_all = int(usable.sum()), int(((cal.fault & FAULT["outside"]) == 0).sum())
    span = cal.curve.span_counts
    r_gate = 3.0 * np.median(cal.noise_counts[usable]) / (np.median(cal.gain[usable]) * span) if n_use else np.nan
    floor_kpa = float(cal.curve.inverse(np.array(r_gate)))
    kinds: dict[str, int] = {}
    for lf in cal.line_faults:
        kinds[lf["kind"]] = kinds.get(lf["kind"], 0) + 1
    res.numbers.update(usable_sensels=n_use, sensels=n_all, usable_fraction=round(n_use / max(n_all, 1), 4),
                       faulty_lines=kinds, noise_floor_kpa=round(floor_kpa, 3),
                       noise_median_counts=round(float(np.median(cal.noise_counts[usable])), 3) if n_use else None)
    res.say(f"{n_use} of {n_all} sensels usable ({n_use / max(n_all, 1):.1%}); faults: "
            + (", ".join(f"{v} {k}" for k, v in kinds.items()) or "none"))
    res.say(f"noise floor {floor_kpa * 1000:.0f} Pa (3σ of a typical sensel)")
    if holdout is None or not mass_kg:
        res.say("no held-out stance: force accuracy not validated")
        return res
    ok, _ = frame_validity(holdout.frames, holdout.full_scale)
    ap = Applier(cal, crosstalk=cal.crosstalk_r_norm > 0)
    lows, ests = [], []
    weight = mass_kg * G_M_S2
    for fr in holdout.frames[ok]:
        out = ap.apply(np.clip(fr, 0, holdout.full_scale).astype(np.uint16))
        lo, est = force_estimate_n(out, cal.pitch_m, fill_ratio, cal.curve.saturation_kpa)
        if est > 0.3 * weight:  # someone standing (not stepping on/off)
            lows.append(lo)
            ests.append(est)
    if not ests:
        return res.refuse("nobody stood on the carpet in the held-out stance capture")
    err = float(np.median(ests) / weight - 1.0)
    res.numbers.update(holdout_frames=len(ests), force_error=round(err, 4),
                       force_lower_bound_ratio=round(float(np.median(lows) / weight), 4), force_target=FORCE_TARGET)
    res.say(f"held-out stance: force {np.median(ests):.0f} N for {weight:.0f} N ({err:+.1%}); "
            f"lower bound from censored sensels {np.median(lows) / weight:.0%} of the weight")
    if abs(err) > FORCE_TARGET:
        return res.refuse(f"the force error {err:+.1%} exceeds ±{FORCE_TARGET:.0%}: redo the board and stance steps "
                          "(check the mass entered and that the person stood still on both feet)")
    return res

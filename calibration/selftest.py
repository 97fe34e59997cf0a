"""Step 2, self-test: is the board streaming whole, sane frames at the rate it claims?

Checks: frame shape against the INFO packet, the measured rate against the nominal
(± 10 %), gaps in device time (lost frames) and the source's own counters (missed,
torn, CRC), garbage frames (NaN/∞, out of range, constant, duplicated). Refuses when
the shape is wrong, the rate is off by more than 10 %, or more than 5 % of frames are
lost or garbage.
"""

from __future__ import annotations

import numpy as np

from calibration.capture import Capture, frame_validity
from calibration.result import StepResult

MAX_BAD_FRACTION = 0.05
RATE_TOLERANCE = 0.10


def self_test(cap: Capture) -> StepResult:
    res = StepResult("self_test")
    n = cap.frames.shape[0]
    rows, cols = cap.device["rows"], cap.device["cols"]
    res.numbers.update(frames=n, rows=rows, cols=cols, adc_bits=cap.device["adc_bits"], sign=cap.sign)
    if cap.shape != (rows, cols):
        return res.refuse(f"frames are {cap.shape[0]}×{cap.shape[1]} but the board says {rows}×{cols}: "
                          "check the wiring map / firmware configuration", retry=False)
    if n < 10:
        return res.refuse(f"only {n} frames arrived; is the board streaming?")
    ok, reasons = frame_validity(cap.frames, cap.full_scale)
    bad = int((~ok).sum())
    dt = np.diff(cap.t_s)
    dt = dt[dt > 0]
    period = float(np.median(dt)) if dt.size else 1.0 / cap.rate_hz
    rate = 1.0 / period
    gaps = int(np.sum(np.maximum(np.rint(dt / period) - 1, 0))) if dt.size else 0
    fr = cap.stats.get("frames", {})
    counted = {k: int(fr.get(k, 0)) for k in ("missed_frames", "torn_dropped", "torn_flagged", "crc_mismatch",
                                              "duplicate_frames", "bad_rows") if fr.get(k)}
    lost = max(gaps, counted.get("missed_frames", 0))
    res.numbers.update(rate_hz=round(rate, 3), nominal_rate_hz=cap.rate_hz, lost_frames=lost,
                       garbage_frames=bad, garbage_reasons=reasons, source_counters=counted)
    res.say(f"{n} frames of {rows}×{cols} at {rate:.2f} Hz (nominal {cap.rate_hz:g} Hz), "
            f"{cap.device['adc_bits']}-bit, sign {cap.sign:+d}")
    if reasons:
        res.say("garbage frames dropped: " + ", ".join(f"{v} {k.replace('_', ' ')}" for k, v in reasons.items()))
    if lost:
        res.say(f"{lost} frames lost in transit (gaps in the device clock or counter)")
    if counted:
        res.say("source counters: " + ", ".join(f"{k}={v}" for k, v in counted.items()))
    if abs(rate - cap.rate_hz) > RATE_TOLERANCE * cap.rate_hz:
        return res.refuse(f"the rate is {rate:.2f} Hz, not {cap.rate_hz:g} Hz: check the link speed and the board's rate setting")
    if (bad + lost) > MAX_BAD_FRACTION * (n + lost):
        return res.refuse(f"{bad + lost} of {n + lost} frames lost or garbage (> {MAX_BAD_FRACTION:.0%}): "
                          "check the cable, the USB hub and the power supply, then run the self-test again")
    res.say("self-test passed")
    return res

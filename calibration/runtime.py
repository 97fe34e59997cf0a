"""Runtime calibration: raw counts → kPa, frame after frame, for hours.

Per frame (:meth:`CalibratedFrames.process`)::

    validate counts (shape, NaN/∞, out of range, constant, time) ─ reject with a reason, counted
    accumulate the frame for the baseline tracker                 one add
    Applier.apply with the TRACKED baseline and the board's last STATUS temperature
    every ``update_interval_s`` (1 s): BaselineTracker.update → LineWatch → DriftMonitor

Baseline tracking (:class:`~calibration.baseline.BaselineTracker`, its settings
:class:`~calibration.baseline.BaselineConfig`) lives in :mod:`calibration.baseline`; both
are re-exported here.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime, timezone
from typing import Any, Callable, Iterator

import numpy as np

from calibration.apply import Applier
from calibration.baseline import BaselineConfig, BaselineTracker, BaselineUpdate
from calibration.drift import Advice, DriftConfig, DriftMonitor, LineWatch
from calibration.file import Calibration


@dataclass
class Processed:
    """One processed frame. Unpacks as ``pressure_kpa, saturated, masked, advice``.

    pressure_kpa (H, W) float32 kPa (None when the frame was rejected); saturated, masked
    (H, W) bool; advice: new :class:`~calibration.drift.Advice` raised at this frame (usually
    empty); rejected: the reason a frame was refused, else None.
    """

    pressure_kpa: np.ndarray | None
    saturated: np.ndarray | None
    masked: np.ndarray | None
    advice: list[Advice]
    rejected: str | None = None

    @property
    def valid(self) -> bool:
        return self.rejected is None

    def __iter__(self) -> Iterator[Any]:
        return iter((self.pressure_kpa, self.saturated, self.masked, self.advice))


REJECT_REASONS = ("not_an_array", "shape_mismatch", "bad_time", "time_not_increasing", "non_finite", "out_of_range",
                  "constant")


def status_temperature_c(status: Any) -> float | None:
    """Board temperature in °C from a STATUS packet (``temperature_cdeg``; −32768 = no sensor)."""
    v = getattr(status, "temperature_cdeg", -32768)
    return None if v is None or v == -32768 else v / 100.0


class CalibratedFrames:
    """The runtime calibration step: counts in, kPa out, baseline tracked, drift watched.

        step = CalibratedFrames(Calibration.load(path), info)     # refuses another carpet
        pressure_kpa, saturated, masked, advice = step.process(counts, t_s, temperature_c)
        for a in advice: log.warning(a.reason)                     # rare; each said once

    ``masked`` is shared between frames (until a line fails at run time): do not modify it.

    ``temperature_c``: the board's STATUS temperature when it arrives (it is kept for the
    next frames; ``None`` = no new reading). ``clock``: wall-clock time (UTC) for the
    calibration-age rule. ``max_nonfinite_fraction``: up to this fraction of NaN/∞
    sensels are masked for the frame; more rejects it.
    """

    def __init__(self, cal: Calibration, info: Any = None, *, baseline: BaselineConfig | None = None,
                 drift: DriftConfig | None = None, crosstalk: bool = True, noise_gate: float = 3.0,
                 max_nonfinite_fraction: float = 0.01, clock: Callable[[], datetime] | None = None,
                 drift_check_s: float = 10.0) -> None:
        if info is not None:
            cal.check_device(info)
        self.cal = cal
        self.applier = Applier(cal, noise_gate=noise_gate, crosstalk=crosstalk)
        self.tracker = BaselineTracker(cal, baseline)
        self.applier.baseline = self.tracker.baseline_counts  # shared, updated in place
        self.monitor = DriftMonitor(cal, drift)
        self.lines = LineWatch(cal, self.monitor.config)
        self.full_scale = float(cal.full_scale)
        self.max_nonfinite_fraction = max_nonfinite_fraction
        self.clock = clock or (lambda: datetime.now(timezone.utc))
        self.drift_check_s = drift_check_s
        self.temperature_c: float | None = None
        self._last_t: float | None = None
        self._last_drift_check: float | None = None
        self.counters: dict[str, int] = {"frames": 0, "valid": 0, "saturated_frames": 0, "advice": 0,
                                         "masked_at_runtime": 0, "bad_temperature": 0, "baseline_updates": 0,
                                         "baseline_steps": 0,
                                         **{f"rejected_{r}": 0 for r in REJECT_REASONS}}
        self._pending: list[Advice] = self._note(self.monitor.check_age(0.0, self.clock()))  # said with the first frame

    # ------------------------------------------------------------------ inputs

    def set_temperature(self, temperature_c: float | None, t_s: float | None = None) -> list[Advice]:
        """A STATUS temperature (°C); implausible values are counted and ignored."""
        if temperature_c is None:
            return []
        try:
            t = float(temperature_c)
        except (TypeError, ValueError):
            t = math.nan
        if not (math.isfinite(t) and -40.0 <= t <= 125.0):
            self.counters["bad_temperature"] += 1
            return []
        self.temperature_c = t
        when = self._last_t if t_s is None else t_s
        return [] if when is None else self._note(self.monitor.observe_temperature(when, t))

    def report_weight(self, person: str, observed_kg: float, expected_kg: float, t_s: float,
                      censored: bool = False) -> list[Advice]:
        """A known person's measured weight (see :meth:`DriftMonitor.report_weight`)."""
        return self._note(self.monitor.report_weight(person, observed_kg, expected_kg, t_s, censored))

    @property
    def advice(self) -> list[Advice]:
        """Advice whose condition still holds (or latched for good: line failures, age)."""
        self.monitor.refresh_active()
        return list(self.monitor.active.values())

    # ------------------------------------------------------------------ the step

    def process(self, counts: Any, t_s: float, temperature_c: float | None = None) -> Processed:
        c = self.counters
        c["frames"] += 1
        reason, frame, bad = self._validate(counts, t_s)
        if reason is not None:
            c[f"rejected_{reason}"] += 1
            return Processed(None, None, None, [], reason)
        t_s = float(t_s)
        self._last_t = t_s
        c["valid"] += 1
        advice, self._pending = self._pending, []
        if temperature_c is not None:
            advice += self.set_temperature(temperature_c, t_s)
        if bad is not None:  # a few NaN/∞ sensels: read as unloaded for this frame, masked
            frame = np.where(bad, self.tracker.baseline_counts, frame)
        upd = self.tracker.add(frame, t_s)
        out = self.applier.apply(frame, self.temperature_c)
        masked = out.masked if bad is None else out.masked | bad
        saturated = out.saturated if bad is None else out.saturated & ~bad
        if bad is not None:
            out.pressure_kpa[bad] = 0.0
        if upd is not None:
            advice += self._after_update(upd)
        c["saturated_frames"] += bool(saturated.any())
        return Processed(out.pressure_kpa, saturated, masked, advice)

    def _validate(self, counts: Any, t_s: Any) -> tuple[str | None, np.ndarray | None, np.ndarray | None]:
        if not isinstance(counts, np.ndarray) or counts.dtype.kind not in "fiu":
            return "not_an_array", None, None
        if counts.shape != self.tracker.shape:
            return "shape_mismatch", None, None
        try:
            t = float(t_s)
        except (TypeError, ValueError):
            return "bad_time", None, None
        if not math.isfinite(t):
            return "bad_time", None, None
        if self._last_t is not None and t <= self._last_t:
            return "time_not_increasing", None, None
        masked = self.applier.masked
        bad = None
        if counts.dtype.kind == "f":
            finite = np.isfinite(counts)
            if not finite.all():
                if (~finite & ~masked).sum() > self.max_nonfinite_fraction * counts.size:
                    return "non_finite", None, None
                bad = ~finite
                counts = np.where(finite, counts, 0.0)
        if bad is not None:
            live = counts[~masked & ~bad]
        else:
            live = counts[~masked] if masked.any() else counts
        if live.size == 0:
            return "constant", None, None
        lo, hi = live.min(), live.max()
        if lo < 0 or hi > self.full_scale:
            return "out_of_range", None, None
        if lo == hi and live.size > 1:  # one usable sensel cannot tell a frozen front end from a still one
            return "constant", None, None
        return None, counts, bad

    def _after_update(self, upd: BaselineUpdate) -> list[Advice]:
        failures = self.lines.update(upd.t_s, upd.mean_counts, upd.contact)
        advice = self._note(self.monitor.observe_line_failures(upd.t_s, failures))
        tc = self.tracker.counters
        self.counters.update(baseline_updates=tc["updates"], baseline_steps=tc["steps"])
        if advice:
            runtime_mask = self.lines.mask() & ~self.applier.masked
            if runtime_mask.any():
                self.counters["masked_at_runtime"] += int(runtime_mask.sum())
                self.applier.masked = self.applier.masked | runtime_mask  # a new array: earlier frames keep theirs
                self.tracker.usable &= ~runtime_mask
        if self._last_drift_check is None or upd.t_s - self._last_drift_check >= self.drift_check_s:
            self._last_drift_check = upd.t_s
            offsets = self.tracker.offset_counts()
            advice += self._note(self.monitor.observe_offsets(upd.t_s, offsets, self.tracker.usable))
            advice += self._note(self.monitor.check_age(upd.t_s, self.clock()))
        return advice

    def _note(self, advice: list[Advice]) -> list[Advice]:
        self.counters["advice"] += len(advice)
        return advice


__all__ = ["BaselineConfig", "BaselineTracker", "BaselineUpdate", "CalibratedFrames", "Processed", "REJECT_REASONS",
           "status_temperature_c"]

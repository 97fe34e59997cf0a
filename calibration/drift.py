"""Drift monitor: says when and why the carpet should be recalibrated, without spamming.

The rules (``shared/notes/sensor-and-calibration.md``, "At run time"), each a latch
that fires once, after its condition has held for a while, and re-arms only after the
condition has been clearly gone (hysteresis)::

    kind            fires when                                          re-arms when
    offset_drift    |median baseline offset| > 3σ for > 10 min          < 2σ for 1 min
    sensel_drift    > 5 % of sensels moved > 4σ from the carpet's       < 3 % for 1 min
                    median offset, for > 1 min
    line_failed     a line not flagged at calibration is stuck at a     never (one advice per line)
                    rail, or stops responding while both neighbours do
    temperature     |T − T_cal| ≥ 10 °C for > 30 s                      < 8 °C for 1 min
    weight          a known person's reported weight (median of the     < 10 % (per person)
                    last 3 reports) is off by > 15 %
    age             the calibration is older than ``max_age_days``      never

σ is the calibration's per-sensel noise (its median for the global rule). Offsets are
measured on the tracked baseline (``calibration.baseline.BaselineTracker``), in counts
toward the pressure rail. Every :class:`Advice` carries a sentence an installer can
act on. ``DriftMonitor.active`` lists what currently holds.

:class:`LineWatch` finds lines that fail at run time: stuck (≥ 80 % of the line's
sensels at a rail for ``stuck_s``) and dead (an open thread reads like an unloaded
sensel, so it shows only under load: over a window, a run of ≤ 12 adjacent lines with
≤ 5 % of the contacts of BOTH lines beside the run, which each saw ≥ ``dead_min_events``,
and contacts that straddled the run: the lines on both sides touched at the same column
in the same update, so a quiet gap between two walked areas is not mistaken for a dead
line). Lines at the carpet's edge (one neighbour), bands wider than a foot can straddle
(a whole 16-line multiplexer bank) and threads broken part-way are left to the
calibration's coverage walk.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from datetime import datetime, timezone
from typing import Any, ClassVar

import numpy as np

from calibration.file import Calibration
from cavatar_common.config import Check, StrictConfig, at_least_one, at_least_zero, described


def _f(default: Any, doc: str, check: Check = at_least_zero) -> Any:
    return described(default, doc, check)


@dataclass(frozen=True)
class DriftConfig(StrictConfig):
    """Thresholds of the recalibration advice (see ``describe()``); every one ≥ 0."""

    WHAT: ClassVar[str] = "drift"

    offset_sigmas: float = _f(3.0, "global baseline offset (median over sensels) above this many noise σ ...")
    offset_hold_s: float = _f(600.0, "... for longer than this advises recalibration")
    offset_clear_sigmas: float = _f(2.0, "the offset advice re-arms below this many σ")
    sensel_sigmas: float = _f(4.0, "a sensel has drifted when its offset (minus the carpet's median) exceeds this many of its σ")
    sensel_fraction: float = _f(0.05, "advise when more than this fraction of usable sensels have drifted ...")
    sensel_hold_s: float = _f(60.0, "... for longer than this")
    sensel_clear_fraction: float = _f(0.03, "the sensel-drift advice re-arms below this fraction")
    temperature_delta_c: float = _f(10.0, "advise when the board temperature is this far (°C) from the calibration's ...")
    temperature_hold_s: float = _f(30.0, "... for longer than this")
    temperature_clear_c: float = _f(8.0, "the temperature advice re-arms closer than this")
    weight_tolerance: float = _f(0.15, "advise when a known person's weight is off by more than this fraction ...")
    weight_reports: int = _f(3, "... in the median of their last this-many reports", at_least_one)
    weight_clear: float = _f(0.10, "the weight advice re-arms (per person) below this fraction")
    max_age_days: float = _f(180.0, "advise recalibrating a calibration older than this")
    clear_hold_s: float = _f(60.0, "a condition must be gone this long before its advice re-arms")
    stuck_fraction: float = _f(0.8, "a line is stuck when this fraction of its usable sensels read a rail ...")
    stuck_s: float = _f(30.0, "... for longer than this")
    rail_margin_counts: float = _f(2.0, "a reading within this of a rail code counts as at the rail")
    dead_fraction: float = _f(0.05, "a line is dead when it sees at most this fraction of the contacts of both neighbours ...")
    dead_min_events: int = _f(40, "... each of which saw at least this many contact sensel-updates in the window")
    dead_min_straddles: int = _f(5, "... and contacts straddled the quiet lines (the lines on both sides touched at the "
                                    "same place and time) this often")
    dead_max_run: int = _f(12, "at most this many adjacent quiet lines are judged together (a foot must be able to straddle them)",
                           at_least_one)
    activity_window_s: float = _f(600.0, "contacts per line are counted over windows this long")

    def __post_init__(self) -> None:
        self.check_fields()


KINDS = ("offset_drift", "sensel_drift", "line_failed", "temperature", "weight", "age")


@dataclass(frozen=True)
class Advice:
    """One piece of recalibration advice.

    kind: one of ``KINDS``; key: what it is about (``"row 12"``, a person, or the kind);
    reason: a sentence for the installer; t_s: when it fired; value/threshold: the
    measurement and the limit it crossed (units in ``detail["unit"]``).
    """

    kind: str
    key: str
    reason: str
    t_s: float
    value: float
    threshold: float
    detail: dict[str, Any] = field(default_factory=dict, compare=False)

    def __str__(self) -> str:
        return self.reason


@dataclass
class Latch:
    """Fires once when ``on`` has held for ``hold_s``; re-arms when ``off`` has held ``clear_s``."""

    hold_s: float
    clear_s: float
    fired: bool = False
    since: float | None = None  # start of the current on-run (armed) or off-run (fired)

    def update(self, t_s: float, on: bool, off: bool) -> bool:
        """True exactly when the latch fires at this update."""
        if not self.fired:
            if not on:
                self.since = None
                return False
            if self.since is None:
                self.since = t_s
            if t_s - self.since >= self.hold_s:
                self.fired, self.since = True, None
                return True
            return False
        if not off:
            self.since = None
        else:
            if self.since is None:
                self.since = t_s
            if t_s - self.since >= self.clear_s:
                self.fired, self.since = False, None
        return False


@dataclass(frozen=True)
class LineFailure:
    axis: str  # "row" or "col"
    index: int
    kind: str  # "stuck" or "dead"
    detail: dict[str, Any]


class LineWatch:
    """Finds rows/columns that fail during the run (see the module docstring)."""

    def __init__(self, cal: Calibration, config: DriftConfig) -> None:
        self.config = config
        self.shape = cal.shape
        self.usable = cal.usable
        self.full_scale = float(cal.full_scale)
        self.rail = self.full_scale if cal.device["sign"] > 0 else 0.0
        known = ~self.usable
        # a line is "known" when most of it was already unusable at calibration (dead, stuck, noisy, outside)
        self.known = {"row": known.mean(axis=1) > 0.5, "col": known.mean(axis=0) > 0.5}
        self.n_usable = {"row": np.maximum(self.usable.sum(axis=1), 1), "col": np.maximum(self.usable.sum(axis=0), 1)}
        self.failed: dict[tuple[str, int], LineFailure] = {}
        self._stuck_since = {"row": np.full(self.shape[0], np.nan), "col": np.full(self.shape[1], np.nan)}
        self._act = {"row": np.zeros(self.shape[0]), "col": np.zeros(self.shape[1])}
        # _straddle[axis][d, i]: updates×positions where lines i and i + d were both in contact
        self._straddle = {"row": np.zeros((config.dead_max_run + 2, self.shape[0])),
                          "col": np.zeros((config.dead_max_run + 2, self.shape[1]))}
        self._window_start: float | None = None

    def update(self, t_s: float, mean_counts: np.ndarray, contact: np.ndarray) -> list[LineFailure]:
        """One update: ``mean_counts`` (H, W) the update's mean reading; ``contact`` (H, W) bool."""
        cfg = self.config
        new: list[LineFailure] = []
        m = cfg.rail_margin_counts
        at_rail = ((np.abs(mean_counts - self.rail) <= m) | (np.abs(mean_counts - (self.full_scale - self.rail)) <= m)) & self.usable
        for axis, ax in (("row", 1), ("col", 0)):
            frac = at_rail.sum(axis=ax) / self.n_usable[axis]
            stuck = (frac >= cfg.stuck_fraction) & ~self.known[axis]
            since = self._stuck_since[axis]
            since[~stuck] = np.nan
            since[stuck & np.isnan(since)] = t_s
            for i in np.nonzero(stuck & (t_s - since >= cfg.stuck_s))[0]:
                if (axis, int(i)) not in self.failed:
                    f = LineFailure(axis, int(i), "stuck", {"fraction_at_rail": float(frac[i])})
                    self.failed[(axis, int(i))] = f
                    new.append(f)
        if self._window_start is None or t_s - self._window_start >= cfg.activity_window_s:
            self._window_start = t_s
            for a in (*self._act.values(), *self._straddle.values()):
                a[:] = 0.0
        live = contact & self.usable
        if live.any():
            self._act["row"] += live.sum(axis=1)
            self._act["col"] += live.sum(axis=0)
            x = live.astype(np.float32)
            for axis, gram in (("row", x @ x.T), ("col", x.T @ x)):  # gram[i, j]: places both lines touched
                for d in range(2, min(self.config.dead_max_run + 2, gram.shape[0])):
                    self._straddle[axis][d, :-d] += np.diagonal(gram, offset=d)
            for axis in ("row", "col"):
                new += self._dead_lines(axis)
        return new

    def _dead_lines(self, axis: str) -> list[LineFailure]:
        cfg = self.config
        act, known = self._act[axis], self.known[axis]
        n = act.size
        ref = np.maximum(act[:-2], act[2:]) if n > 2 else np.zeros(0)
        quiet = np.zeros(n, bool)
        quiet[1:-1] = act[1:-1] <= cfg.dead_fraction * ref
        quiet |= known
        out: list[LineFailure] = []
        i = 0
        while i < n:
            if not quiet[i]:
                i += 1
                continue
            j = i
            while j + 1 < n and quiet[j + 1]:
                j += 1
            new_lines = [k for k in range(i, j + 1) if not known[k] and (axis, k) not in self.failed]
            if i > 0 and j < n - 1 and new_lines and len(new_lines) <= cfg.dead_max_run:
                left, right = act[i - 1], act[j + 1]
                lo = min(left, right)
                d = j - i + 2
                straddles = self._straddle[axis][d, i - 1] if d < self._straddle[axis].shape[0] else 0.0
                if (lo >= cfg.dead_min_events and straddles >= cfg.dead_min_straddles
                        and all(act[k] <= cfg.dead_fraction * lo for k in new_lines)):
                    for k in new_lines:
                        f = LineFailure(axis, k, "dead", {"contacts": float(act[k]), "straddles": float(straddles),
                                                          "neighbour_contacts": [float(left), float(right)]})
                        self.failed[(axis, k)] = f
                        out.append(f)
            i = j + 1
        return out

    def mask(self) -> np.ndarray:
        """(H, W) bool: sensels on lines that failed at run time."""
        m = np.zeros(self.shape, bool)
        for axis, i in self.failed:
            if axis == "row":
                m[i, :] = True
            else:
                m[:, i] = True
        return m


class DriftMonitor:
    """Collects the runtime's measurements and turns them into :class:`Advice`, once each."""

    def __init__(self, cal: Calibration, config: DriftConfig | None = None) -> None:
        self.cal = cal
        self.config = cfg = config or DriftConfig()
        self.usable = cal.usable
        noise = cal.noise_counts.astype(np.float32)
        self.sigma_sensel = np.maximum(noise, 0.5)
        self.sigma = float(np.median(self.sigma_sensel[self.usable])) if self.usable.any() else 1.0
        self._latches = {
            "offset_drift": Latch(cfg.offset_hold_s, cfg.clear_hold_s),
            "sensel_drift": Latch(cfg.sensel_hold_s, cfg.clear_hold_s),
            "temperature": Latch(cfg.temperature_hold_s, cfg.clear_hold_s),
            "age": Latch(0.0, math.inf),
        }
        self._weights: dict[str, list[float]] = {}
        self._weight_latches: dict[str, Latch] = {}
        self.active: dict[tuple[str, str], Advice] = {}
        self.issued: list[Advice] = []
        self.last: dict[str, float] = {}

    # ------------------------------------------------------------------ inputs

    def observe_offsets(self, t_s: float, offset_counts: np.ndarray, valid: np.ndarray | None = None) -> list[Advice]:
        """``offset_counts`` (H, W): tracked baseline − calibration baseline, toward the rail.
        ``valid`` (H, W) bool: sensels whose offset means something (default: usable)."""
        cfg = self.config
        valid = self.usable if valid is None else valid & self.usable
        if not valid.any():
            return []
        off = offset_counts[valid]
        g = float(np.median(off))
        frac = float(np.mean(np.abs(off - g) > cfg.sensel_sigmas * self.sigma_sensel[valid]))
        self.last.update(offset_counts=g, offset_sigmas=g / self.sigma, drifted_fraction=frac)
        out = []
        a = abs(g) / self.sigma
        if self._latches["offset_drift"].update(t_s, a > cfg.offset_sigmas, a < cfg.offset_clear_sigmas):
            out.append(self._advise(
                "offset_drift", "offset_drift", t_s, a, cfg.offset_sigmas, {"unit": "sigma", "offset_counts": g},
                f"The carpet's empty reading has moved by {g:+.1f} counts ({a:.1f}× its noise) for more than "
                f"{cfg.offset_hold_s / 60:.0f} min. The runtime follows it, but sensitivity has probably changed too "
                "(temperature, humidity, the rug or carpet moved): recalibrate with `cavatar calibrate`."))
        if self._latches["sensel_drift"].update(t_s, frac > cfg.sensel_fraction, frac < cfg.sensel_clear_fraction):
            out.append(self._advise(
                "sensel_drift", "sensel_drift", t_s, frac, cfg.sensel_fraction, {"unit": "fraction"},
                f"{100 * frac:.0f} % of the sensels read more than {cfg.sensel_sigmas:.0f}× their noise away from their "
                "calibrated empty level. Part of the carpet has changed (a tile, a fold or something heavy left on it, "
                "damp): check the carpet is flat and clear, then recalibrate with `cavatar calibrate`."))
        return out

    def observe_temperature(self, t_s: float, temperature_c: float) -> list[Advice]:
        cfg = self.config
        if self.cal.temperature_c is None:
            return []
        d = float(temperature_c) - float(self.cal.temperature_c)
        self.last["temperature_delta_c"] = d
        if self._latches["temperature"].update(t_s, abs(d) >= cfg.temperature_delta_c, abs(d) < cfg.temperature_clear_c):
            return [self._advise(
                "temperature", "temperature", t_s, abs(d), cfg.temperature_delta_c, {"unit": "degC", "temperature_c": float(temperature_c)},
                f"The board reads {temperature_c:.1f} °C, {d:+.1f} °C from the {self.cal.temperature_c:.1f} °C of the "
                "calibration. Readings are compensated, but beyond 10 °C the compensation is an extrapolation: "
                "recalibrate at the room's usual temperature (`cavatar calibrate`).")]
        return []

    def observe_line_failures(self, t_s: float, failures: list[LineFailure]) -> list[Advice]:
        out = []
        for f in failures:
            key = f"{f.axis} {f.index}"
            if (("line_failed", key)) in self.active:
                continue
            if f.kind == "stuck":
                why = (f"{f.axis} {f.index} reads a rail constantly: a short, a damaged thread or a faulty input channel. "
                       "It is masked from now on. Check the tile connector, then recalibrate (`cavatar calibrate`).")
            else:
                why = (f"{f.axis} {f.index} stopped responding while the lines beside it see people step on them: "
                       "a broken thread or a loose connector. It is masked from now on. Check the tile connector, "
                       "then recalibrate (`cavatar calibrate`) so the walk test can confirm it.")
            out.append(self._advise("line_failed", key, t_s, 1.0, 0.0, {"unit": "line", **f.detail, "fault": f.kind}, why))
        return out

    def report_weight(self, person: str, observed_kg: float, expected_kg: float, t_s: float,
                      censored: bool = False) -> list[Advice]:
        """A known person (``person``, entered with their mass ``expected_kg``) was measured at
        ``observed_kg`` (e.g. standing still). ``censored``: part of their contact was
        saturated, so the observation is a lower bound and only a reading too HIGH counts."""
        cfg = self.config
        if not (math.isfinite(observed_kg) and math.isfinite(expected_kg)) or expected_kg <= 0:
            return []
        rel = (observed_kg - expected_kg) / expected_kg
        if censored and rel < 0:
            return []
        hist = self._weights.setdefault(person, [])
        hist.append(rel)
        del hist[:-cfg.weight_reports]
        if len(hist) < cfg.weight_reports:
            return []
        med = float(np.median(hist))
        latch = self._weight_latches.setdefault(person, Latch(0.0, 0.0))
        if latch.update(t_s, abs(med) > cfg.weight_tolerance, abs(med) < cfg.weight_clear):
            return [self._advise(
                "weight", person, t_s, abs(med), cfg.weight_tolerance, {"unit": "fraction", "relative_error": med},
                f"{person} weighs {expected_kg:.0f} kg but the carpet measures {expected_kg * (1 + med):.0f} kg "
                f"({100 * med:+.0f} %). The carpet's sensitivity has changed: recalibrate with `cavatar calibrate` "
                "(the known-weight stance step).")]
        if not latch.fired:
            self.active.pop(("weight", person), None)
        return []

    def check_age(self, t_s: float, now: datetime | None = None) -> list[Advice]:
        cfg = self.config
        try:
            age_d = self.cal.age_s(now or datetime.now(timezone.utc)) / 86400.0
        except (TypeError, ValueError):
            return []
        self.last["age_days"] = age_d
        if self._latches["age"].update(t_s, age_d > cfg.max_age_days, False):
            return [self._advise(
                "age", "age", t_s, age_d, cfg.max_age_days, {"unit": "days"},
                f"The calibration is {age_d:.0f} days old (created {self.cal.created}); films and threads age: "
                "recalibrate with `cavatar calibrate`.")]
        return []

    # ------------------------------------------------------------------ bookkeeping

    def _advise(self, kind: str, key: str, t_s: float, value: float, threshold: float, detail: dict[str, Any],
                reason: str) -> Advice:
        a = Advice(kind, key, reason, float(t_s), float(value), float(threshold), detail)
        self.active[(kind, key)] = a
        self.issued.append(a)
        return a

    def refresh_active(self) -> None:
        """Drop advice whose latch has re-armed (the condition is gone)."""
        for kind, latch in self._latches.items():
            if not latch.fired:
                self.active.pop((kind, kind), None)


__all__ = ["Advice", "DriftConfig", "DriftMonitor", "KINDS", "Latch", "LineFailure", "LineWatch"]

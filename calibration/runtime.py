"""Runtime calibration: raw counts → kPa, frame after frame, for hours.

Per frame (:meth:`CalibratedFrames.process`)::

    validate counts (shape, NaN/∞, out of range, constant, time) ─ reject with a reason, counted
    accumulate the frame for the baseline tracker                 one add
    Applier.apply with the TRACKED baseline and the board's last STATUS temperature
    every ``update_interval_s`` (1 s): BaselineTracker.update → LineWatch → DriftMonitor

Baseline tracking (:class:`BaselineTracker`), on the mean of the frames since the last
update, in counts toward the pressure rail (``d = sign·(mean − baseline)``):

1. contact = ``d − common_mode > σ·(contact_sigmas/√n + contact_margin_sigmas)``; grown by
   ``neighbour_mm`` (``ndimage.maximum_filter``); each sensel remembers when it (or a
   neighbour) was last in contact;
2. common mode, per readout tile (``blocks``): the mean residual (clipped at ±3σ) of the
   sensels NOT in contact, followed with a short time constant ``common_tau_s``. It models the
   front end's offset drift (board, tile, temperature), which is shared by every sensel
   of a tile, so it is applied everywhere, under people too;
3. per sensel, the slow part follows its own residual with ``tau_s`` (minutes), only where
   the sensel and its neighbours have been free of contact for ``holdoff_s``. A person
   lying still is in contact the whole time, so their sensels keep their baseline
   (creep raises their reading; it is never eaten).

An offset step (most of a tile "in contact" at once, all by about the same amount: people
give readings spread over hundreds of counts) moves that tile's common mode to its
median at once.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from datetime import datetime, timezone
from typing import Any, Callable, ClassVar, Iterator

import numpy as np
from scipy import ndimage

from calibration.apply import Applier
from calibration.drift import Advice, DriftConfig, DriftMonitor, LineWatch
from calibration.file import Calibration
from cavatar_common.config import StrictConfig, at_least_zero, described, positive


def _two_positive(v: tuple[int, int]) -> str | None:
    return None if all(b >= 1 for b in v) else "must be two positive integers"


_f = described


@dataclass(frozen=True)
class BaselineConfig(StrictConfig):
    """Contact-gated slow baseline tracking (see ``describe()``)."""

    WHAT: ClassVar[str] = "baseline"

    enabled: bool = _f(True, "track the baseline at all (False: the calibration's baseline, forever)")
    update_interval_s: float = _f(1.0, "the tracker runs on the mean of the frames of this interval", positive)
    tau_s: float = _f(300.0, "time constant of each sensel's own slow baseline", positive)
    holdoff_s: float = _f(60.0, "a sensel updates only after it and its neighbours have been free of contact this long",
                          at_least_zero)
    neighbour_mm: float = _f(60.0, "contact blocks updates within this distance (the contact mask is grown by it)",
                             at_least_zero)
    contact_sigmas: float = _f(5.0, "contact: the update's mean above the baseline by this many σ/√frames ...", positive)
    contact_margin_sigmas: float = _f(0.5, "... plus this many σ (a floor when many frames are averaged)", at_least_zero)
    common_tau_s: float = _f(20.0, "time constant of the per-tile common-mode offset (front-end drift)", positive)
    blocks: tuple[int, int] = _f((3, 3), "tiles (rows, cols) with their own common-mode offset: the readout tiles",
                                 _two_positive)
    min_free_fraction: float = _f(0.2, "a tile's common mode updates only while this fraction of its sensels is free",
                                  at_least_zero)
    step_fraction: float = _f(0.6, "more of a tile than this 'in contact', all by about the same amount, ...",
                              at_least_zero)
    step_spread_sigmas: float = _f(4.0, "... (interquartile range below this many σ) is an offset step, not people",
                                   at_least_zero)
    max_step_s: float = _f(60.0, "one update never counts for more than this much time (after a gap in the stream)",
                           positive)

    def __post_init__(self) -> None:
        self.check_fields()


_RAIL_MARGIN_COUNTS = 2.0  # within this of the rail a mean reading is censored (as Applier's rail_margin_counts)
_MIN_STEP_SENSELS = 8  # a tile needs this many usable sensels before its spread can call an offset step


def _block_index(shape: tuple[int, int], blocks: tuple[int, int]) -> np.ndarray:
    """(H, W) int: the tile of each sensel, tiles from ``np.array_split`` bounds, row-major."""
    def along(n: int, parts: int) -> np.ndarray:
        return np.concatenate([np.full(len(a), i) for i, a in enumerate(np.array_split(np.arange(n), min(parts, n)))])

    br, bc = along(shape[0], blocks[0]), along(shape[1], blocks[1])
    return br[:, None] * (bc.max() + 1) + bc[None, :]


@dataclass
class BaselineUpdate:
    """What one tracker update saw. Arrays (H, W)."""

    t_s: float
    frames: int
    mean_counts: np.ndarray
    contact: np.ndarray  # bool, before growing
    updated: np.ndarray  # bool: sensels whose slow baseline moved
    step: bool  # handled as a carpet-wide offset step


class BaselineTracker:
    """Tracks the empty reading of every sensel; ``baseline_counts`` is updated in place.

    ``add(counts, t_s)`` per frame; when an update is due it runs and returns a
    :class:`BaselineUpdate` (else None). ``usable`` (H, W) bool may shrink at run time
    (lines that fail).
    """

    def __init__(self, cal: Calibration, config: BaselineConfig | None = None) -> None:
        self.cal = cal
        self.config = cfg = config or BaselineConfig()
        self.shape = cal.shape
        self.sign = float(cal.device["sign"])
        self.calibrated = cal.baseline_counts.astype(np.float32)
        self.slow = self.calibrated.copy()  # per-sensel part
        self.baseline_counts = self.calibrated.copy()  # slow + sign · common mode: what Applier uses
        self.sigma = np.maximum(cal.noise_counts.astype(np.float32), 0.5)
        self.usable = cal.usable.copy()
        self.blocks = _block_index(self.shape, cfg.blocks)
        self.n_blocks = int(self.blocks.max()) + 1
        self._block_sel = [self.blocks == b for b in range(self.n_blocks)]
        self._blocks_flat = self.blocks.ravel()
        self._block_size = np.bincount(self._blocks_flat, minlength=self.n_blocks)
        self._usable_size = np.maximum(np.bincount(self._blocks_flat, weights=self.usable.ravel(),
                                                   minlength=self.n_blocks), 1)
        self._sigma_median = float(np.median(self.sigma[self.usable])) if self.usable.any() else 1.0
        self.common = np.zeros(self.n_blocks, np.float32)  # counts toward the rail
        self.rail = 0.0 if self.sign < 0 else float(cal.full_scale)
        self.last_contact_s = np.full(self.shape, -np.inf)
        self.grow = max(int(round(cfg.neighbour_mm * 1e-3 / cal.pitch_m)), 0)
        self._sum = np.zeros(self.shape, np.float64)
        self._n = 0
        self._t_last_update: float | None = None
        self.counters = {"updates": 0, "steps": 0, "sensel_updates": 0}

    def add(self, counts: np.ndarray, t_s: float) -> BaselineUpdate | None:
        """Accumulate one valid frame (H, W, finite); run an update when one is due."""
        self._sum += counts
        self._n += 1
        if self._t_last_update is not None and t_s - self._t_last_update < self.config.update_interval_s:
            return None
        return self._update(t_s)

    def offset_counts(self) -> np.ndarray:
        """(H, W): tracked − calibrated baseline, toward the rail (what the drift monitor judges)."""
        return self.sign * (self.baseline_counts - self.calibrated)

    def _update(self, t_s: float) -> BaselineUpdate:
        cfg = self.config
        n = self._n
        mean = (self._sum / n).astype(np.float32)
        self._sum[:] = 0.0
        self._n = 0
        dt = 0.0 if self._t_last_update is None else min(max(t_s - self._t_last_update, 0.0), cfg.max_step_s)
        self._t_last_update = t_s

        d = self.sign * (mean - self.slow)  # counts toward the rail, vs the per-sensel part
        cm_map = self.common[self.blocks]
        thr = self.sigma * np.float32(cfg.contact_sigmas / math.sqrt(n) + cfg.contact_margin_sigmas)
        contact = ((d - cm_map) > thr) & self.usable
        step = False
        if cfg.enabled:
            # A reading at the rail is censored (at least that far, not how far the offset moved), and
            # an IQR over a handful of sensels says nothing: neither may call an offset step, or an
            # all-saturated second (or one live sensel under a foot) becomes the baseline and the
            # carpet then reads empty for many minutes.
            railed = np.abs(mean - self.rail) <= _RAIL_MARGIN_COUNTS
            step_contact = (contact & ~railed).ravel()
            in_contact = np.bincount(self._blocks_flat, weights=step_contact, minlength=self.n_blocks)
            big = self._usable_size >= _MIN_STEP_SENSELS
            for b in np.nonzero((in_contact > cfg.step_fraction * self._usable_size) & big)[0]:
                # most of a tile "in contact": people give readings spread over hundreds of
                # counts, an offset step moves every sensel alike
                v = d[self._block_sel[b] & self.usable]
                q25, q50, q75 = np.percentile(v, [25, 50, 75])
                if q75 - q25 < cfg.step_spread_sigmas * self._sigma_median:
                    self.common[b] = q50
                    step = True
            if step:
                self.counters["steps"] += 1
                cm_map = self.common[self.blocks]
                contact = ((d - cm_map) > thr) & self.usable
        grown = ndimage.maximum_filter(contact, size=2 * self.grow + 1) if self.grow > 0 else contact
        self.last_contact_s[grown] = t_s

        if cfg.enabled and dt > 0:
            beta = 1.0 - math.exp(-dt / cfg.common_tau_s)
            free_now = (self.usable & ~grown).ravel()
            # robust mean of each tile's free residuals (clipped at ±3σ; contacts are already out)
            resid = np.clip(d - cm_map, -3.0 * self.sigma, 3.0 * self.sigma).ravel()
            n_free = np.bincount(self._blocks_flat, weights=free_now, minlength=self.n_blocks)
            total = np.bincount(self._blocks_flat, weights=np.where(free_now, resid, 0.0), minlength=self.n_blocks)
            ok = n_free >= np.maximum(cfg.min_free_fraction * self._block_size, 1)
            self.common[ok] += np.float32(beta) * (total[ok] / n_free[ok]).astype(np.float32)
            cm_map = self.common[self.blocks]
            alpha = np.float32(1.0 - math.exp(-dt / cfg.tau_s))
            updated = self.usable & (t_s - self.last_contact_s >= cfg.holdoff_s)
            self.slow += np.where(updated, self.sign * alpha * (d - cm_map), np.float32(0.0))
            self.counters["sensel_updates"] += int(updated.sum())
        else:
            updated = np.zeros(self.shape, bool)
        np.add(self.slow, self.sign * cm_map, out=self.baseline_counts, casting="unsafe")
        self.counters["updates"] += 1
        return BaselineUpdate(t_s, n, mean, contact, updated, step)


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

"""The empty reading of every sensel, followed for hours while people come and go.

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
from typing import ClassVar

import numpy as np
from scipy import ndimage

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

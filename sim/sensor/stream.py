"""The frame stream: what a host sees of the sensor over time.

:class:`FrameStream` runs a :class:`~sim.sensor.model.CarpetSensor` at the carpet's
frame rate and applies the stream faults of :class:`~sim.sensor.config.StreamConfig`:
dropped frames (never yielded; the sensor still advances), duplicated frames (the
previous frame again, same timestamp), torn frames (rows rolled by 1–3, or the rows from
a tear row on taken from the previous frame), garbage frames (constant, or out of the
ADC range below 16 bit) and timestamp jitter (Gaussian, clipped to ±0.45 periods, so
timestamps increase strictly except across a duplicate).

Each item is ``(counts, t_s, flags)``; ``flags`` (:class:`FrameFlags`) carries the truth.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable, Iterator

import numpy as np

from .config import StreamConfig
from .model import _LEVEL_STREAM, CarpetSensor, _seq


@dataclass(frozen=True)
class FrameFlags:
    """Ground truth of one yielded frame."""

    seq: int  # index of the true frame this came from (duplicates repeat it)
    true_t_s: float  # when it was really sampled
    dropped_before: int = 0  # frames lost right before this one
    duplicate: bool = False
    torn: str | None = None  # None, "shift" or "old"
    tear_row: int = 0  # "old": rows ≥ tear_row are from the previous frame
    shift: int = 0  # "shift": rows rolled by this many (np.roll along axis 0)
    corrupt: str | None = None  # None, "constant" or "out_of_range"

    @property
    def clean(self) -> bool:
        return not (self.duplicate or self.torn or self.corrupt)


class FrameStream:
    """Yield ``(counts, t_s, flags)`` for a sequence of true pressure frames."""

    def __init__(self, sensor: CarpetSensor, config: StreamConfig | None = None, seed: int | None = None) -> None:
        self.sensor = sensor
        self.config = config if config is not None else StreamConfig()
        s = sensor.seed if seed is None else int(seed)
        self._rng = np.random.default_rng(_seq(s, _LEVEL_STREAM, sensor.session.index))

    def frames(self, pressures: Iterable[np.ndarray], t0_s: float = 0.0) -> Iterator[tuple[np.ndarray, float, FrameFlags]]:
        """Frame k is sampled at ``t0_s + k / rate_hz``; faults drawn per true frame."""
        cfg, rng = self.config, self._rng
        period = 1.0 / self.sensor.config.grid.rate_hz
        fs = self.sensor.carpet.full_scale
        prev_counts: np.ndarray | None = None
        prev_out: tuple[np.ndarray, float, FrameFlags] | None = None
        dropped = 0
        cuts = np.cumsum([cfg.drop_rate, cfg.duplicate_rate, cfg.tear_rate, cfg.corrupt_rate])
        for k, pressure in enumerate(pressures):
            t_true = t0_s + k * period
            counts = self.sensor.counts(pressure, t_true)
            jitter = float(np.clip(rng.normal(0.0, cfg.jitter_s), -0.45 * period, 0.45 * period)) if cfg.jitter_s > 0 else 0.0
            t_out = t_true + jitter
            x = rng.random()
            if x < cuts[0] and k > 0:  # dropped
                dropped += 1
                prev_counts = counts
                continue
            if x < cuts[1] and prev_out is not None:  # the previous frame sent again, then this one
                c0, t0, f0 = prev_out
                yield c0.copy(), t0, FrameFlags(seq=f0.seq, true_t_s=f0.true_t_s, duplicate=True)
            flags = dict(seq=k, true_t_s=t_true, dropped_before=dropped)
            out = counts
            if cuts[1] <= x < cuts[2] and prev_counts is not None:  # torn
                out = counts.copy()
                if rng.random() < cfg.tear_shift_fraction:
                    shift = int(rng.integers(1, 4)) * (1 if rng.random() < 0.5 else -1)
                    out = np.roll(out, shift, axis=0)
                    flags.update(torn="shift", shift=shift)
                else:
                    row = int(rng.integers(1, counts.shape[0]))
                    out[row:] = prev_counts[row:]
                    flags.update(torn="old", tear_row=row)
            elif cuts[2] <= x < cuts[3]:  # garbage
                if fs < 65535 and rng.random() < 0.5:
                    out = rng.integers(fs + 1, 65536, counts.shape).astype(np.uint16)
                    flags.update(corrupt="out_of_range")
                else:
                    out = np.full(counts.shape, int(rng.integers(0, fs + 1)), np.uint16)
                    flags.update(corrupt="constant")
            item = (out, t_out, FrameFlags(**flags))
            yield item
            prev_out = item
            prev_counts = counts
            dropped = 0


__all__ = ["FrameFlags", "FrameStream"]

"""A small virtual carpet: people walking between random spots, as raw sensor counts.

This is the demo and test world of the foundation: each person is a pair of feet
(ellipses of about 25 × 9 cm) that take turns bearing weight as the person walks at
about 1 m/s between random targets, keeping apart from the others. Pressure under a
foot is the person's weight over the contact area; the sensor turns it into counts
with a saturating response around a mid-scale baseline, per-sensel gain spread and
white noise. The full simulator (body motion, contact physics, the complete sensor
model) lives beside this and supersedes it for training and evaluation.

``FootstepCarpet(rows, cols, people, seed)(frame_index)`` returns (rows, cols) uint16
counts; the same seed and index give the same frame.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

G_M_S2 = 9.81


@dataclass
class _Walker:
    pos_m: np.ndarray  # (2,) x, y in the carpet frame
    target_m: np.ndarray
    mass_kg: float
    speed_m_s: float
    phase: float  # gait phase in cycles


class FootstepCarpet:
    """Deterministic frames of ``people`` walkers on a ``rows``×``cols`` carpet."""

    def __init__(
        self,
        rows: int = 96,
        cols: int = 96,
        people: int = 1,
        seed: int = 0,
        pitch_mm: float = 19.05,
        rate_hz: float = 14.0,
        adc_bits: int = 12,
        sign: int = -1,
        half_scale_kpa: float = 8.0,
        noise_counts: float = 1.5,
    ) -> None:
        if people < 0 or people > 3:
            raise ValueError(f"people must be 0..3, got {people}")
        self.rows, self.cols, self.people = rows, cols, people
        self.pitch_m = pitch_mm * 1e-3
        self.dt_s = 1.0 / rate_hz
        self.full_scale = (1 << adc_bits) - 1
        self.baseline = self.full_scale // 2
        self.sign = sign
        self.half_scale_kpa = half_scale_kpa
        self.noise_counts = noise_counts
        self.seed = seed
        size = np.array([cols, rows]) * self.pitch_m
        self.size_m = size
        ys, xs = np.mgrid[0:rows, 0:cols]
        self._xy_m = np.stack([(xs + 0.5) * self.pitch_m, (ys + 0.5) * self.pitch_m], axis=-1)
        self._reset()

    def _reset(self) -> None:
        rows, cols, size = self.rows, self.cols, self.size_m
        rng = np.random.default_rng(self.seed)
        self.gain = np.clip(rng.lognormal(0.0, 0.15, (rows, cols)), 0.5, 2.0)
        self.offset = rng.normal(0.0, 3.0, (rows, cols))
        self._walkers = []
        for _ in range(self.people):  # spawn at least 0.8 m apart, so nobody starts blocked
            for _ in range(100):
                pos = rng.uniform(0.2, 0.8, 2) * size
                if all(np.linalg.norm(pos - w.pos_m) > 0.8 for w in self._walkers):
                    break
            self._walkers.append(_Walker(
                pos_m=pos,
                target_m=rng.uniform(0.15, 0.85, 2) * size,
                mass_kg=float(rng.uniform(50, 95)),
                speed_m_s=float(rng.uniform(0.6, 1.2)),
                phase=float(rng.uniform(0, 1)),
            ))
        self._rng = rng
        self._state_index = 0

    def __call__(self, frame_index: int) -> np.ndarray:
        """Raw counts (rows, cols) uint16 of frame ``frame_index`` (frames are generated in order)."""
        if frame_index < self._state_index:  # going back: replay from the start
            self._reset()
        while self._state_index < frame_index:
            self._step()
        pressure = self.pressure_kpa()
        frame_rng = np.random.default_rng((self.seed, frame_index))
        response = pressure / (pressure + self.half_scale_kpa)  # saturating, 0..1
        delta = response * self.gain * (self.full_scale - self.baseline - 40)
        counts = self.baseline + self.offset + self.sign * delta + frame_rng.normal(0, self.noise_counts, pressure.shape)
        return np.clip(np.rint(counts), 0, self.full_scale).astype(np.uint16)

    def pressure_kpa(self) -> np.ndarray:
        """True pressure (rows, cols) in kPa of the current state."""
        total = np.zeros((self.rows, self.cols))
        for w in self._walkers:
            heading = w.target_m - w.pos_m
            norm = np.linalg.norm(heading)
            fwd = heading / norm if norm > 1e-6 else np.array([1.0, 0.0])
            side = np.array([-fwd[1], fwd[0]])
            stride = 0.3 * min(1.0, w.speed_m_s)
            s = np.sin(2 * np.pi * w.phase)
            loads = (0.5 + 0.5 * s, 0.5 - 0.5 * s) if norm > 0.05 else (0.5, 0.5)
            for k, (sgn, load) in enumerate(zip((1, -1), loads)):
                centre = w.pos_m + sgn * 0.09 * side + sgn * s * stride * 0.5 * fwd
                d = self._xy_m - centre
                u, v = d @ fwd, d @ side
                inside = (u / 0.125) ** 2 + (v / 0.045) ** 2 <= 1.0
                area_m2 = max(inside.sum(), 1) * self.pitch_m**2
                total[inside] += load * w.mass_kg * G_M_S2 / area_m2 / 1e3
        return total

    def _step(self) -> None:
        self._state_index += 1
        for i, w in enumerate(self._walkers):
            heading = w.target_m - w.pos_m
            dist = np.linalg.norm(heading)
            if dist < 0.05:
                w.target_m = self._rng.uniform(0.15, 0.85, 2) * self.size_m
                continue
            step = heading / dist * min(dist, w.speed_m_s * self.dt_s)
            new = w.pos_m + step
            others = [o.pos_m for j, o in enumerate(self._walkers) if j != i]
            # a step may not bring anyone closer than 0.6 m (moving apart is always allowed)
            if all(np.linalg.norm(new - o) > 0.6 or np.linalg.norm(new - o) > np.linalg.norm(w.pos_m - o) for o in others):
                w.pos_m = new
                w.phase = (w.phase + w.speed_m_s * self.dt_s / 1.1) % 1.0
            else:  # someone is in the way: pick another spot
                w.target_m = self._rng.uniform(0.15, 0.85, 2) * self.size_m

"""The one-euro filter (Casiez, Roussel and Vogel, CHI 2012): a low-pass filter whose
cutoff rises with speed, so a still signal is smoothed hard and a moving one lags little.

    cutoff_hz = min_cutoff_hz + beta · |dx/dt|          (dx/dt itself low-passed at d_cutoff_hz)
    alpha(cutoff, dt) = 1 / (1 + 1 / (2π · cutoff · dt))
    x̂ = x̂_prev + alpha · (x − x̂_prev)

Works on scalars or arrays (the speed of a vector is its Euclidean norm). Time comes
from the caller, so dropped frames and jitter are handled.
"""

from __future__ import annotations

import math

import numpy as np


def smoothing_alpha(cutoff_hz: float, dt_s: float) -> float:
    """Weight of the new sample for a first-order low-pass at ``cutoff_hz`` sampled after ``dt_s``."""
    return 1.0 / (1.0 + 1.0 / (2.0 * math.pi * cutoff_hz * dt_s))


class OneEuroFilter:
    """Stateful one-euro filter; ``__call__(x, t_s)`` returns the filtered value (same shape as x)."""

    def __init__(self, min_cutoff_hz: float = 1.0, beta: float = 0.0, d_cutoff_hz: float = 1.0) -> None:
        if min_cutoff_hz <= 0 or d_cutoff_hz <= 0 or beta < 0:
            raise ValueError("one-euro cutoffs must be > 0 and beta ≥ 0")
        self.min_cutoff_hz, self.beta, self.d_cutoff_hz = min_cutoff_hz, beta, d_cutoff_hz
        self._x: np.ndarray | None = None
        self._dx: np.ndarray | None = None
        self._t_s: float | None = None

    def reset(self) -> None:
        self._x = self._dx = self._t_s = None

    def __call__(self, x, t_s: float):
        x = np.asarray(x, dtype=np.float64)
        if self._x is None or self._t_s is None or t_s <= self._t_s:
            if self._x is None or self._t_s is None:
                self._x, self._dx, self._t_s = x.copy(), np.zeros_like(x), t_s
            return self._x.copy() if x.ndim else float(self._x)
        dt = t_s - self._t_s
        dx = (x - self._x) / dt
        self._dx = self._dx + smoothing_alpha(self.d_cutoff_hz, dt) * (dx - self._dx)
        speed = float(np.linalg.norm(self._dx)) if self._dx.ndim else abs(float(self._dx))
        a = smoothing_alpha(self.min_cutoff_hz + self.beta * speed, dt)
        self._x = self._x + a * (x - self._x)
        self._t_s = t_s
        return self._x.copy() if x.ndim else float(self._x)

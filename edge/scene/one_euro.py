"""The one-euro filter (Casiez, Roussel and Vogel, CHI 2012): a low-pass filter whose
cutoff rises with speed, so a still signal is smoothed hard and a moving one lags little.

    cutoff_hz = min_cutoff_hz + beta · |dx/dt|          (dx/dt itself low-passed at d_cutoff_hz)
    alpha(cutoff, dt) = 1 / (1 + 1 / (2π · cutoff · dt))
    x̂ = x̂_prev + alpha · (x − x̂_prev)

Works on scalars or arrays (the speed of a vector is its Euclidean norm). Time comes
from the caller, so dropped frames and jitter are handled. A sample at or before the last
time (dt ≤ 0) returns the last estimate unchanged; a NaN/∞ sample or time, or one that
would make the state non-finite, is skipped the same way and counted in ``skipped``:
nothing non-finite ever enters the state, so one bad frame cannot poison later ones.
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
        self._sx: float | None = None  # the state when filtering plain scalars (see _scalar)
        self._sdx = 0.0
        self._t_s: float | None = None
        self.skipped = 0  # samples refused because they (or their time) were not finite

    def reset(self) -> None:
        self._x = self._dx = self._t_s = self._sx = None

    def __call__(self, x, t_s: float):
        if isinstance(x, (float, int, np.floating, np.integer)) and not isinstance(x, bool):
            return self._scalar(float(x), float(t_s))
        x = np.asarray(x, dtype=np.float64)
        t = float(t_s)
        # NaN compares false and ∞ would freeze the clock: either would poison every later sample.
        if not (math.isfinite(t) and np.all(np.isfinite(x))):
            self.skipped += 1
            last = x if self._x is None else self._x  # nothing to hold yet: the sample is returned as is
            return last.copy() if last.ndim else float(last)
        if self._x is None or self._t_s is None:
            self._x, self._dx, self._t_s = x.copy(), np.zeros_like(x), t
            return self._x.copy() if x.ndim else float(self._x)
        if t <= self._t_s:
            return self._x.copy() if x.ndim else float(self._x)
        dt = t - self._t_s
        assert self._dx is not None  # set with _x
        with np.errstate(over="ignore", invalid="ignore"):
            new_x, new_dx = self._advance(x, self._x, self._dx, dt)
        if not (np.all(np.isfinite(new_x)) and np.all(np.isfinite(new_dx))):  # e.g. a huge jump over a tiny dt
            self.skipped += 1
            return self._x.copy() if x.ndim else float(self._x)
        self._x, self._dx, self._t_s = new_x, new_dx, t
        return self._x.copy() if x.ndim else float(self._x)

    def _scalar(self, x: float, t: float) -> float:
        """``__call__`` for a plain scalar, in Python floats: the same IEEE arithmetic as the array path
        without numpy's per-call cost (the tracker filters every track's force each frame)."""
        last = self._sx
        if not (math.isfinite(t) and math.isfinite(x)):
            self.skipped += 1
            return x if last is None else last
        if last is None or self._t_s is None:
            self._sx, self._sdx, self._t_s = x, 0.0, t
            return x
        if t <= self._t_s:
            return last
        new_x, new_dx = self._advance(x, last, self._sdx, t - self._t_s)
        if not (math.isfinite(new_x) and math.isfinite(new_dx)):  # e.g. a huge jump over a tiny dt
            self.skipped += 1
            return last
        self._sx, self._sdx, self._t_s = new_x, new_dx, t
        return new_x

    def _advance(self, x, last, dx_last, dt: float):
        """One filter step, for floats or arrays alike: (new estimate, new derivative). The speed of a
        vector is its Euclidean norm."""
        new_dx = dx_last + smoothing_alpha(self.d_cutoff_hz, dt) * ((x - last) / dt - dx_last)
        speed = float(np.linalg.norm(new_dx)) if np.ndim(new_dx) else abs(float(new_dx))
        a = smoothing_alpha(self.min_cutoff_hz + self.beta * speed, dt) if math.isfinite(speed) else 1.0
        return last + a * (x - last), new_dx

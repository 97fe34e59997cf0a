"""Per-frame filters on calibrated pressure, as pure functions plus one small stateful chain.

Order (each step can be switched off in ``SceneConfig``):
fill masked sensels → optional 3-frame temporal median → 3×3 median → Gaussian → EMA.

Cost notes (96×96 float32, one core of the 2-core board): ``scipy.ndimage.median_filter``
with size 3 takes ~2 ms, so the 3×3 median here is the exact separable scheme (sort each
vertical triple once, then median of {max of lows, median of mids, min of highs}):
18 vectorised min/max passes, ~0.1 ms, equal to ndimage's result (a test checks).
A frame whose every sensel is below the grow threshold, with no EMA memory above it,
skips the spatial filters entirely: nothing there can become a contact.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage, sparse


def med3(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Element-wise median of three equally shaped arrays."""
    return np.maximum(np.minimum(a, b), np.minimum(np.maximum(a, b), c))


def median3x3(p: np.ndarray) -> np.ndarray:
    """Exact 3×3 median of (H, W) with edge-replicated borders (ndimage ``mode='nearest'``)."""
    h, w = p.shape
    q = np.empty((h + 2, w + 2), dtype=p.dtype)  # edge-replicated border (np.pad costs more than the median)
    q[1:-1, 1:-1] = p
    q[0, 1:-1], q[-1, 1:-1] = p[0], p[-1]
    q[:, 0], q[:, -1] = q[:, 1], q[:, -2]
    a, b, c = q[0:h], q[1 : h + 1], q[2 : h + 2]  # (H, W+2) vertical triples
    mn, mx = np.minimum(a, b), np.maximum(a, b)
    lo, hi = np.minimum(mn, c), np.maximum(mx, c)
    mid = np.maximum(mn, np.minimum(mx, c))
    lo3 = np.maximum(np.maximum(lo[:, 0:w], lo[:, 1 : w + 1]), lo[:, 2 : w + 2])
    hi3 = np.minimum(np.minimum(hi[:, 0:w], hi[:, 1 : w + 1]), hi[:, 2 : w + 2])
    mid3 = med3(mid[:, 0:w], mid[:, 1 : w + 1], mid[:, 2 : w + 2])
    return med3(lo3, mid3, hi3)


def gaussian_kernel(sigma_sensels: float, truncate: float = 3.0) -> np.ndarray:
    """(2r+1,) float64 normalised Gaussian taps, r = ⌊truncate·σ + ½⌋ (ndimage.gaussian_filter's kernel)."""
    radius = int(truncate * sigma_sensels + 0.5)
    x = np.arange(-radius, radius + 1)
    taps = np.exp(-0.5 / (sigma_sensels * sigma_sensels) * x ** 2)
    return taps / taps.sum()


def gaussian_with(p: np.ndarray, taps: np.ndarray) -> np.ndarray:
    """Separable Gaussian with taps computed once (the chain filters every frame); 'reflect' borders keep
    the total unchanged. Rows, then columns, the intermediate in p's dtype: ndimage.gaussian_filter's
    result bit for bit, without its per-call kernel and wrapper cost."""
    out = ndimage.correlate1d(p, taps, axis=0, mode="reflect")
    return ndimage.correlate1d(out, taps, axis=1, output=out, mode="reflect")


class MaskedFill:
    """Replaces unusable sensels from their neighbours; built once per mask, applied as one sparse product.

    A masked sensel with usable 8-neighbours takes their mean; one with none takes its
    nearest usable sensel's value when that is within ``max_distance_m``, else 0.
    """

    def __init__(self, bad: np.ndarray, pitch_m: float, max_distance_m: float) -> None:
        h, w = bad.shape
        self.bad = bad.copy()
        br, bc = np.nonzero(bad)
        self.bad_flat = br * w + bc
        rows, cols = [], []
        for dr in (-1, 0, 1):
            for dc in (-1, 0, 1):
                if dr == dc == 0:
                    continue
                rr, cc = br + dr, bc + dc
                ok = (rr >= 0) & (rr < h) & (cc >= 0) & (cc < w)
                ok[ok] &= ~bad[rr[ok], cc[ok]]
                rows.append(np.nonzero(ok)[0])
                cols.append(rr[ok] * w + cc[ok])
        r, c = np.concatenate(rows), np.concatenate(cols)
        count = np.bincount(r, minlength=len(br))
        deep = np.nonzero(count == 0)[0]
        if len(deep) and (~bad).any():
            dist_m, (ir, ic) = ndimage.distance_transform_edt(bad, sampling=pitch_m, return_indices=True)
            near = deep[dist_m[br[deep], bc[deep]] <= max_distance_m + 1e-9]
            r = np.concatenate([r, near])
            c = np.concatenate([c, ir[br[near], bc[near]] * w + ic[br[near], bc[near]]])
            count[near] = 1
        weights = 1.0 / np.maximum(count[r], 1)
        self.matrix = sparse.csr_matrix((weights.astype(np.float32), (r, c)), shape=(len(br), h * w))

    def __call__(self, p: np.ndarray) -> np.ndarray:
        out = p.copy()
        flat = out.reshape(-1)
        flat[self.bad_flat] = self.matrix @ p.reshape(-1)
        return out


class FilterChain:
    """The stateful part: temporal history, EMA memory and the cached mask fill.

    Geometry-dependent switches are resolved once from the pitch (see SceneConfig).
    """

    def __init__(self, pitch_m: float, config) -> None:
        self.pitch_m = pitch_m
        pitch_mm = pitch_m * 1e3
        self.temporal = config.temporal_median
        self.fill_enabled = config.fill_masked
        self.fill_max_distance_m = config.fill_max_distance_mm * 1e-3
        self.median = config.median_3x3 and pitch_mm <= config.median_max_pitch_mm + 1e-9
        self.sigma_sensels = config.gaussian_sigma_mm / pitch_mm
        self.gauss = self.sigma_sensels >= 0.3
        self._taps = gaussian_kernel(self.sigma_sensels) if self.gauss else None
        self.ema_tau_s = config.ema_tau_s
        self._fill: MaskedFill | None = None
        self.reset()

    def reset(self) -> None:
        self._history: list[np.ndarray] = []
        self._ema: np.ndarray | None = None
        self._ema_peak = 0.0
        self._t_s: float | None = None

    def fill(self, p: np.ndarray, bad: np.ndarray | None) -> np.ndarray:
        """Masked-sensel fill (cached per mask); without a fill, masked sensels read 0."""
        if bad is None:
            return p
        if not self.fill_enabled:
            return np.where(bad, np.float32(0.0), p)
        if self._fill is None or not np.array_equal(self._fill.bad, bad):
            self._fill = MaskedFill(bad, self.pitch_m, self.fill_max_distance_m)
        return self._fill(p)

    def __call__(self, p: np.ndarray, t_s: float, quiet_kpa: float) -> tuple[np.ndarray, np.ndarray | None]:
        """(H, W) float32 filled pressure → (after the temporal median only, fully filtered or None).

        The second is None when nothing can be a contact. The first is what forces are
        integrated on: the 3×3 median erodes thin contacts (~4 % of a foot's force at 19 mm).
        NaN/∞ raise ValueError before any state changes: the history and the EMA would carry
        them into every later frame (``check_frame`` masks or rejects them first).
        """
        if not np.isfinite(p).all():
            raise ValueError(f"FilterChain got {int((~np.isfinite(p)).sum())} NaN/∞ sensel(s): validate frames with "
                             "check_frame and fill masked sensels first (SceneTracker.update does)")
        if self.temporal:
            self._history = (self._history + [p])[-3:]
            if len(self._history) == 3:
                p = med3(*self._history)
        pre = p
        dt = None if self._t_s is None else t_s - self._t_s
        self._t_s = t_s
        if float(p.max()) <= quiet_kpa and self._ema_peak <= quiet_kpa:
            self._ema, self._ema_peak = None, 0.0
            return pre, None
        if self.median:
            p = median3x3(p)
        if self.gauss:
            assert self._taps is not None  # set whenever gauss is
            p = gaussian_with(p, self._taps)
        if self.ema_tau_s > 0:
            if self._ema is not None and dt is not None and dt > 0:
                alpha = np.float32(1.0 - math.exp(-dt / self.ema_tau_s))
                p = self._ema + alpha * (p - self._ema)  # a new array: callers may keep the old one
            self._ema = p
            self._ema_peak = float(p.max())
        return pre, p

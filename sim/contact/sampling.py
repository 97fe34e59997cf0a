"""Rug and sensels: the fine pressure field → pressure per sensel (step 4 of the package docstring).

The fine field is blurred by a Gaussian (the rug) and averaged over each thread crossing:
one exact, separable linear map per axis (``sampling_kernel``), applied to one person's
cropped field by ``sample_sensels``.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ndtr

_SQRT_2PI = math.sqrt(2.0 * math.pi)


def _ramp2(t, sigma):
    """Second antiderivative of the unit Gaussian of width sigma (a ramp when sigma = 0)."""
    if sigma <= 0:
        return np.maximum(t, 0.0)
    u = t / sigma
    return t * ndtr(u) + sigma * np.exp(-0.5 * u * u) / _SQRT_2PI


def sampling_kernel(n_sensels: int, pitch_m: float, cell_m: float, pad: int, sigma_m: float, width_m: float) -> np.ndarray:
    """(n_sensels, n_cells) weights: mean over a crossing window of width ``width_m``
    centred on each sensel of the fine pressure (cells uniform) blurred by a Gaussian
    of ``sigma_m``. Column k is lattice cell k − pad. Exact (closed-form double integral)."""
    centres = (np.arange(n_sensels) + 0.5) * pitch_m
    a = (centres - width_m / 2)[:, None]
    b = (centres + width_m / 2)[:, None]
    lo = ((np.arange(int(round(n_sensels * pitch_m / cell_m)) + 2 * pad) - pad) * cell_m)[None, :]
    hi = lo + cell_m
    w = _ramp2(b - lo, sigma_m) - _ramp2(b - hi, sigma_m) - _ramp2(a - lo, sigma_m) + _ramp2(a - hi, sigma_m)
    w /= width_m  # mean over the window; a cell's pressure acts over its whole width
    w[w < 1e-9 * w.max()] = 0.0
    return w


def sample_sensels(fine_kpa: np.ndarray, origin: tuple[int, int], ky: np.ndarray, kx: np.ndarray, pad: int) -> np.ndarray:
    """(rows, cols) float64 sensel pressure of a fine field.

    fine_kpa (ny, nx): pressure on lattice cells, its [0, 0] at lattice index origin = (j0, i0)
    (cells may lie off the carpet). ky (rows, Ny + 2·pad), kx (cols, Nx + 2·pad): the
    ``sampling_kernel`` of each axis, Ny × Nx the carpet's lattice. Separable, and only the
    lattice cells and sensels that the kernels connect are touched."""
    j0, i0 = origin
    ny, nx = fine_kpa.shape
    ny_lattice, nx_lattice = ky.shape[1] - 2 * pad, kx.shape[1] - 2 * pad
    lo_j, hi_j = max(j0, -pad), min(j0 + ny, ny_lattice + pad)
    lo_i, hi_i = max(i0, -pad), min(i0 + nx, nx_lattice + pad)
    sensels = np.zeros((ky.shape[0], kx.shape[0]))
    if lo_j < hi_j and lo_i < hi_i:
        sub = fine_kpa[lo_j - j0:hi_j - j0, lo_i - i0:hi_i - i0]
        ky_reach = ky[:, lo_j + pad:hi_j + pad]
        kx_reach = kx[:, lo_i + pad:hi_i + pad]
        r = np.flatnonzero(ky_reach.any(1))
        c = np.flatnonzero(kx_reach.any(1))
        if r.size and c.size:
            sensels[r[0]:r[-1] + 1, c[0]:c[-1] + 1] = ky_reach[r[0]:r[-1] + 1] @ sub @ kx_reach[c[0]:c[-1] + 1].T
    return sensels

"""Axis-angle → rotation matrix (Rodrigues), robust at every angle, in float64.

    R = I + a(θ)·K + b(θ)·K²,   K = [r]×,  θ = |r|,
    a(θ) = sin θ / θ,           b(θ) = (1 − cos θ) / θ² = ½·(sin(θ/2) / (θ/2))²

Both coefficients are written as sinc functions of θ (a Taylor series below 1e-4
rad), so there is no division by |r| and no 1 − cos θ cancellation: angle 0 gives
exactly I, 1e-8 gives I + K to round-off, π and 2π + x are exact to round-off, and
1e6 rad agrees with the same angle reduced mod 2π to ~1e-10. The reference PyTorch
code divides by (θ + 1e-8) instead, which is off by ~1e-8 relative and gives NaN at
r = (−1e-8, −1e-8, −1e-8) in float32.
"""

from __future__ import annotations

import numpy as np

# Below this angle sinc(x) uses its Taylor series 1 − x²/6 + x⁴/120 (error < x⁶/5040).
_TAYLOR_BELOW_RAD = 1e-4


def sinc(x: np.ndarray) -> np.ndarray:
    """sin(x)/x for float64 x (any shape), equal to 1 at x = 0, smooth everywhere."""
    x = np.asarray(x, dtype=np.float64)
    small = np.abs(x) < _TAYLOR_BELOW_RAD
    safe = np.where(small, 1.0, x)
    x2 = x * x
    return np.where(small, 1.0 - x2 / 6.0 + x2 * x2 / 120.0, np.sin(safe) / safe)


def skew(v: np.ndarray) -> np.ndarray:
    """Cross-product matrices: v (..., 3) → K (..., 3, 3) with K @ u = v × u."""
    x, y, z = v[..., 0], v[..., 1], v[..., 2]
    zero = np.zeros_like(x)
    return np.stack(
        [
            np.stack([zero, -z, y], axis=-1),
            np.stack([z, zero, -x], axis=-1),
            np.stack([-y, x, zero], axis=-1),
        ],
        axis=-2,
    )


def axis_angle_to_matrix(rotvec: np.ndarray) -> np.ndarray:
    """Rodrigues' formula in float64.

    rotvec: (..., 3) axis × angle in radians (any float dtype; computed in float64).
    Returns (..., 3, 3) float64 rotation matrices.
    """
    r = np.asarray(rotvec, dtype=np.float64)
    theta = np.sqrt(np.sum(r * r, axis=-1))
    a = sinc(theta)[..., None, None]
    half = sinc(0.5 * theta)[..., None, None]
    b = 0.5 * half * half
    k = skew(r)
    return np.eye(3) + a * k + b * (k @ k)

"""The rotation conversions of the whole code base, in float64, robust at every angle.

- :func:`axis_angle_to_matrix` (Rodrigues), :func:`matrix_to_axis_angle` (its inverse, angle in
  [0, π]), :func:`euler_xyz_deg_to_matrix` and :func:`euler_xyz_deg_to_axis_angle` (intrinsic
  x, then y, then z: R = Rx·Ry·Rz), :func:`skew`, :func:`sinc`; vectorised over leading axes.
- edge.infer (model outputs), edge.body.poses (named poses), sim (motion, contact scenes) and
  export import them from here: edge.body is the part of edge that sim may import. (Matrix →
  axis-angle was written three times before: in edge.body.poses with atan2, in sim through
  scipy, and in edge.infer through the quaternion — the one kept, as the runtime publishes it.)

Axis-angle → matrix:

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


def matrix_to_axis_angle(r: np.ndarray) -> np.ndarray:
    """Rotation matrices (..., 3, 3) → axis-angle (..., 3), angle in [0, π]; accurate to round-off near 0 and π.

    Through the unit quaternion of R, built from its largest component (Shepperd's method), so no
    branch divides by a vanishing sin θ or 1 + cos θ; the angle is 2·atan2(|v|, w), not an arccos.
    A matrix that is not quite a rotation (a degenerate 6D model output) still gives a finite
    answer: the zero matrix gives the identity, a shrunken rotation a smaller angle.
    """
    r = np.asarray(r, np.float64)
    m00, m11, m22 = r[..., 0, 0], r[..., 1, 1], r[..., 2, 2]
    q = np.stack([1 + m00 + m11 + m22, 1 + m00 - m11 - m22, 1 - m00 + m11 - m22, 1 - m00 - m11 + m22], -1)
    k = np.argmax(q, -1)  # build the quaternion from its largest component
    s = np.sqrt(np.maximum(np.take_along_axis(q, k[..., None], -1)[..., 0], 1e-12)) * 2  # 4·|q_k|
    d21, d02, d10 = r[..., 2, 1] - r[..., 1, 2], r[..., 0, 2] - r[..., 2, 0], r[..., 1, 0] - r[..., 0, 1]
    s01, s02, s12 = r[..., 0, 1] + r[..., 1, 0], r[..., 0, 2] + r[..., 2, 0], r[..., 1, 2] + r[..., 2, 1]
    cands = np.stack([
        np.stack([s / 4, d21 / s, d02 / s, d10 / s], -1),
        np.stack([d21 / s, s / 4, s01 / s, s02 / s], -1),
        np.stack([d02 / s, s01 / s, s / 4, s12 / s], -1),
        np.stack([d10 / s, s02 / s, s12 / s, s / 4], -1),
    ], -2)
    quat = np.take_along_axis(cands, k[..., None, None], -2)[..., 0, :]  # (w, x, y, z)
    quat = quat * np.where(quat[..., :1] < 0, -1.0, 1.0)
    vec = quat[..., 1:]
    sin_half = np.linalg.norm(vec, axis=-1)
    angle = 2 * np.arctan2(sin_half, quat[..., 0])
    scale = np.where(sin_half > 1e-8, angle / np.maximum(sin_half, 1e-12), 2.0)
    return vec * scale[..., None]


def euler_xyz_deg_to_matrix(e: np.ndarray) -> np.ndarray:
    """Intrinsic x-then-y-then-z angles in degrees (..., 3) → R = Rx·Ry·Rz (..., 3, 3)."""
    e = np.radians(np.asarray(e, dtype=np.float64))
    cx, cy, cz = np.cos(e[..., 0]), np.cos(e[..., 1]), np.cos(e[..., 2])
    sx, sy, sz = np.sin(e[..., 0]), np.sin(e[..., 1]), np.sin(e[..., 2])
    r = np.empty(e.shape[:-1] + (3, 3))
    r[..., 0, 0] = cy * cz
    r[..., 0, 1] = -cy * sz
    r[..., 0, 2] = sy
    r[..., 1, 0] = sx * sy * cz + cx * sz
    r[..., 1, 1] = -sx * sy * sz + cx * cz
    r[..., 1, 2] = -sx * cy
    r[..., 2, 0] = -cx * sy * cz + sx * sz
    r[..., 2, 1] = cx * sy * sz + sx * cz
    r[..., 2, 2] = cx * cy
    return r


def euler_xyz_deg_to_axis_angle(e: np.ndarray) -> np.ndarray:
    """Intrinsic x-then-y-then-z angles in degrees (..., 3) → axis-angle (..., 3)."""
    return matrix_to_axis_angle(euler_xyz_deg_to_matrix(e))


__all__ = ["axis_angle_to_matrix", "euler_xyz_deg_to_axis_angle", "euler_xyz_deg_to_matrix", "matrix_to_axis_angle",
           "sinc", "skew"]

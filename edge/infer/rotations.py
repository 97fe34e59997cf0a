"""Rotation conversions for the model outputs (numpy, vectorised).

6D layout per joint: the first column of R then the second column (Zhou et al. 2019);
Gram–Schmidt gives R. Axis-angle via the quaternion of R (stable near 0 and π).
"""

from __future__ import annotations

import numpy as np


def rot6d_to_matrix(x: np.ndarray) -> np.ndarray:
    """(…,6) → (…,3,3)."""
    x = np.asarray(x, np.float64)
    a1, a2 = x[..., 0:3], x[..., 3:6]
    b1 = a1 / np.maximum(np.linalg.norm(a1, axis=-1, keepdims=True), 1e-6)
    a2 = a2 - (b1 * a2).sum(-1, keepdims=True) * b1
    b2 = a2 / np.maximum(np.linalg.norm(a2, axis=-1, keepdims=True), 1e-6)
    return np.stack([b1, b2, np.cross(b1, b2)], -1)


def matrix_to_axis_angle(r: np.ndarray) -> np.ndarray:
    """(…,3,3) → (…,3), angle in [0, π]."""
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


def rot6d_to_axis_angle(x: np.ndarray) -> np.ndarray:
    """(B, 6·J) → (B, 3·J) float32."""
    x = np.asarray(x)
    b = x.shape[0]
    return matrix_to_axis_angle(rot6d_to_matrix(x.reshape(b, -1, 6))).reshape(b, -1).astype(np.float32)

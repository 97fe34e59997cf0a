"""Rotation conversions for the model outputs (numpy, vectorised).

6D layout per joint: the first column of R then the second column (Zhou et al. 2019);
Gram–Schmidt gives R. Axis-angle by edge.body.rotations.matrix_to_axis_angle, the one
conversion of the code base (accurate near 0 and π).
"""

from __future__ import annotations

import numpy as np

from edge.body.rotations import matrix_to_axis_angle


def rot6d_to_matrix(x: np.ndarray) -> np.ndarray:
    """(…,6) → (…,3,3)."""
    x = np.asarray(x, np.float64)
    a1, a2 = x[..., 0:3], x[..., 3:6]
    b1 = a1 / np.maximum(np.linalg.norm(a1, axis=-1, keepdims=True), 1e-6)
    a2 = a2 - (b1 * a2).sum(-1, keepdims=True) * b1
    b2 = a2 / np.maximum(np.linalg.norm(a2, axis=-1, keepdims=True), 1e-6)
    return np.stack([b1, b2, np.cross(b1, b2)], -1)


def rot6d_to_axis_angle(x: np.ndarray) -> np.ndarray:
    """(B, 6·J) → (B, 3·J) float32."""
    x = np.asarray(x)
    b = x.shape[0]
    return matrix_to_axis_angle(rot6d_to_matrix(x.reshape(b, -1, 6))).reshape(b, -1).astype(np.float32)

"""The SMPL function as pure array functions (after smplx's ``lbs.py``).

Names as in SMPL: ``v_template`` (V,3), ``shapedirs`` (V,3,NB), ``posedirs``
(V,3,9·(J−1)), ``J_regressor`` (J,V), ``weights`` (V,J), ``parents`` (J,).
B is the batch, J the number of joints (24 for SMPL), V the number of vertices.

Precision: rotations, joints and the kinematic chain are float64; the products over
vertices (shape blend, pose correctives, skinning) run in the dtype of the vertex
arrays given (float32 on the board, float64 for evaluation and parity tests).
"""

from __future__ import annotations

import numpy as np


def kinematic_levels(parents: np.ndarray) -> list[tuple[np.ndarray, np.ndarray]]:
    """Group the non-root joints by depth so that the chain is one product per level.

    parents: (J,) with parents[0] < 0 and 0 <= parents[i] < i for i >= 1.
    Returns [(children, their parents), ...] for depth 1, 2, ...
    """
    parents = np.asarray(parents)
    depth = np.zeros(len(parents), dtype=np.int64)
    for i in range(1, len(parents)):
        depth[i] = depth[parents[i]] + 1
    levels = []
    for d in range(1, int(depth.max(initial=0)) + 1):
        children = np.flatnonzero(depth == d)
        levels.append((children, parents[children]))
    return levels


def shape_joints(j_template: np.ndarray, j_shapedirs: np.ndarray, betas: np.ndarray) -> np.ndarray:
    """Rest joints of each shape without touching the vertices.

    j_template: (J,3) = J_regressor @ v_template; j_shapedirs: (J,3,NB) = J_regressor
    applied to shapedirs; betas: (B,NB). Returns (B,J,3) float64. Exactly
    J_regressor @ (v_template + shapedirs · betas), since regression is linear.
    """
    # J[b,j,k] = Jt[j,k] + sum_l JS[j,k,l] * betas[b,l]
    return j_template[None] + np.einsum("jkl,bl->bjk", j_shapedirs, betas)


def shape_vertices(v_template: np.ndarray, shapedirs_flat: np.ndarray, betas: np.ndarray) -> np.ndarray:
    """Shaped rest vertices: v_template (V,3), shapedirs_flat (3V,NB), betas (B,NB) → (B,V,3)."""
    offsets = betas.astype(shapedirs_flat.dtype, copy=False) @ shapedirs_flat.T  # (B,3V)
    return v_template[None] + offsets.reshape(len(betas), -1, 3)


def forward_kinematics(
    rotations: np.ndarray, joints: np.ndarray, levels: list[tuple[np.ndarray, np.ndarray]]
) -> tuple[np.ndarray, np.ndarray]:
    """World transforms of every joint.

    rotations: (B,J,3,3) local rotations (joint 0: the global orientation);
    joints: (B,J,3) rest joints; levels: from ``kinematic_levels``.
    Returns (G_rot (B,J,3,3), G_t (B,J,3)): joint i maps a point p of its rest frame
    to G_rot[i] @ (p − joints[i]) + G_t[i]; G_t are the posed joint positions, and
    G_t[:,0] == joints[:,0] (the root turns about itself).
    """
    g_rot = np.empty_like(rotations)
    g_t = np.empty_like(joints)
    g_rot[:, 0] = rotations[:, 0]
    g_t[:, 0] = joints[:, 0]
    for children, pars in levels:
        parent_rot = g_rot[:, pars]
        g_rot[:, children] = parent_rot @ rotations[:, children]
        bone = joints[:, children] - joints[:, pars]
        g_t[:, children] = (parent_rot @ bone[..., None])[..., 0] + g_t[:, pars]
    return g_rot, g_t


def pose_feature(rotations: np.ndarray) -> np.ndarray:
    """SMPL's pose-corrective input: (R_i − I) of joints 1..J−1, flattened → (B, 9·(J−1))."""
    b = rotations.shape[0]
    return (rotations[:, 1:] - np.eye(3)).reshape(b, -1)


def skin(
    rest_vertices: np.ndarray,
    weights: np.ndarray,
    g_rot: np.ndarray,
    g_t: np.ndarray,
    rest_joints: np.ndarray,
) -> np.ndarray:
    """Linear blend skinning.

    rest_vertices: (B,V,3) (shaped, with pose correctives); weights: (V,J);
    g_rot, g_t: (B,J,3,3), (B,J,3) from ``forward_kinematics``; rest_joints: (B,J,3).
    Returns (B,V,3) in the dtype of ``weights``.
    """
    dtype = weights.dtype
    # Each joint's rest→posed transform [G_rot | G_t − G_rot @ J] as 3x4.
    t = g_t - (g_rot @ rest_joints[..., None])[..., 0]
    a = np.concatenate([g_rot, t[..., None]], axis=-1).astype(dtype)  # (B,J,3,4)
    b, j = a.shape[:2]
    # T[b,v,:] = sum_j weights[v,j] * A[b,j,:]  (one (V,J) @ (J,12) product per body)
    per_vertex = (weights @ a.reshape(b, j, 12)).reshape(b, -1, 3, 4)
    v = rest_vertices.astype(dtype, copy=False)
    return (
        per_vertex[..., 0] * v[..., 0:1]
        + per_vertex[..., 1] * v[..., 1:2]
        + per_vertex[..., 2] * v[..., 2:3]
        + per_vertex[..., 3]
    )

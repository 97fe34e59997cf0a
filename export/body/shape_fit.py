"""The shape space and the joint regressor fitted to posed samples (steps 5–7 of ``make body-model``).

Pure numpy on float64 arrays in SMPL's frame: vertices (N,V,3), joints (N,J,3), betas (N,B).

- :func:`pca_shape_space`: PCA over the full mesh → mean and shapedirs scaled so betas ~ N(0, 1);
  :func:`shape_space` also orients beta 0 so that + is taller (:func:`stature_sign`);
- :func:`fit_on_betas`: another mesh (the decimated one) as a least-squares fit on the same betas;
- :func:`fit_regressor`: an affine ridge ``J_regressor`` per joint on its nearest vertices, and
  :func:`pick_regressor` choosing its λ on held-out shapes.
"""

from __future__ import annotations

import numpy as np

RIDGE_LAMBDAS = (1e-5, 1e-4, 1e-3, 1e-2, 1e-1)  # the regressor's λ candidates, picked on held-out shapes


def pca_shape_space(verts: np.ndarray, num: int):
    """verts (N,V,3) → (mean (V,3), shapedirs (V,3,num), betas (N,num), explained fraction)."""
    n = len(verts)
    flat = verts.reshape(n, -1)
    mean = flat.mean(0)
    centred = flat - mean
    gram = centred @ centred.T  # (N,N): the cheap side of the SVD
    eigval, eigvec = np.linalg.eigh(gram)
    order = np.argsort(eigval)[::-1]
    eigval, eigvec = eigval[order], eigvec[:, order]
    comps = (centred.T @ eigvec[:, :num]) / np.sqrt(eigval[:num])  # (3V,num) orthonormal
    std = np.sqrt(eigval[:num] / (n - 1))
    dirs = comps * std  # betas ~ N(0,1)
    for k in range(num):  # deterministic signs: largest entry positive (beta 0: see stature_sign)
        if dirs[np.argmax(np.abs(dirs[:, k])), k] < 0:
            dirs[:, k] *= -1
    betas = centred @ dirs / (std**2)  # projection: betas_k = <x, c_k>/std_k
    explained = float(eigval[:num].sum() / eigval.sum())
    return mean.reshape(-1, 3), dirs.reshape(-1, 3, num), betas, explained


def stature_sign(mean: np.ndarray, dirs: np.ndarray) -> float:
    """+1 if adding shapedirs[..., 0] makes the body taller (head up, feet down); mean (V,3), dirs (V,3,B)."""
    top = np.argmax(mean[:, 1])
    bottom = np.argmin(mean[:, 1])
    return float(np.sign(dirs[top, 1, 0] - dirs[bottom, 1, 0]))


def shape_space(verts: np.ndarray, num: int):
    """:func:`pca_shape_space` with beta 0 turned so that + is taller (:func:`stature_sign`); same returns."""
    mean, dirs, betas, explained = pca_shape_space(verts, num)
    if stature_sign(mean, dirs) < 0:
        dirs[..., 0] *= -1
        betas[:, 0] *= -1
    return mean, dirs, betas, explained


def project_betas(mean: np.ndarray, dirs: np.ndarray, verts: np.ndarray) -> np.ndarray:
    """Least-squares betas (N,B) of meshes verts (N,V,3) in the shape space mean (V,3), dirs (V,3,B)."""
    flat_dirs = dirs.reshape(-1, dirs.shape[-1])
    return np.linalg.lstsq(flat_dirs, (verts - mean).reshape(len(verts), -1).T, rcond=None)[0].T


def fit_on_betas(verts: np.ndarray, betas: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """A mesh's own (v_template (V,3), shapedirs (V,3,B)): least squares [1, β] → its vertices verts (N,V,3)."""
    samples = len(verts)
    design = np.concatenate([np.ones((samples, 1)), betas], axis=1)
    coef = np.linalg.lstsq(design, verts.reshape(samples, -1), rcond=None)[0]
    return coef[0].reshape(-1, 3), coef[1:].T.reshape(-1, 3, betas.shape[1])


def blend_shapes(v_template: np.ndarray, shapedirs: np.ndarray, betas: np.ndarray) -> np.ndarray:
    """Meshes (N,V,3) of betas (N,B): v_template (V,3) + Σ_l shapedirs[v,k,l]·betas[n,l]."""
    return v_template + np.einsum("vkl,nl->nvk", shapedirs, betas)


def fit_regressor(verts: np.ndarray, joints: np.ndarray, template: np.ndarray, support: int, lam: float) -> np.ndarray:
    """Affine ridge J_regressor: rows sum to 1, nonzero on each joint's nearest vertices.

    verts (N,V,3), joints (N,J,3), template (V,3) (picks the support of each joint).
    Per joint, with c_n the mean of its support in sample n, solves
    min Σ_n |δ·(V_n − c_n) − (J_n − c_n)|² + λ'|δ|², then row = 1/m + δ (Σδ = 0 holds
    because every design row is centred). λ' = λ · trace(AᵀA)/m (scale-free λ).
    """
    n_j = joints.shape[1]
    j_template = joints.mean(0)
    reg = np.zeros((n_j, verts.shape[1]))
    for j in range(n_j):
        dist = np.linalg.norm(template - j_template[j], axis=1)
        sup = np.sort(np.argsort(dist)[:support])
        local = verts[:, sup]  # (N,m,3)
        centre = local.mean(1, keepdims=True)
        a = (local - centre).transpose(0, 2, 1).reshape(-1, len(sup))  # (3N, m)
        b = (joints[:, j] - centre[:, 0]).reshape(-1)
        ata = a.T @ a
        scale = np.trace(ata) / len(sup)
        delta = np.linalg.solve(ata + lam * scale * np.eye(len(sup)), a.T @ b)
        reg[j, sup] = 1.0 / len(sup) + delta
    return reg


def joint_errors_mm(reg: np.ndarray, verts: np.ndarray, joints: np.ndarray) -> dict:
    """Mean and max distance (mm, rounded to µm) of the joints reg (J,V) gives on verts (N,V,3) from joints (N,J,3)."""
    err = np.linalg.norm(np.einsum("jv,nvk->njk", reg, verts) - joints, axis=-1) * 1000
    return {"mean_mm": round(float(err.mean()), 3), "max_mm": round(float(err.max()), 3)}


def pick_regressor(verts: np.ndarray, joints: np.ndarray, template: np.ndarray, support: int,
                   heldout_verts: np.ndarray, heldout_joints: np.ndarray,
                   lambdas: tuple[float, ...] = RIDGE_LAMBDAS) -> tuple[float, np.ndarray]:
    """(λ, J_regressor (J,V)) of :func:`fit_regressor` on verts/joints with the lowest mean held-out joint error.

    The held-out error is of the joints regressed from heldout_verts (the shape model's own meshes:
    what the runtime does) against heldout_joints (the true joints of the same people); the first
    λ wins a tie at µm precision.
    """
    if not lambdas:
        raise ValueError("pick_regressor needs at least one λ to try")
    best = None
    for lam in lambdas:
        reg = fit_regressor(verts, joints, template, support, lam)
        err = joint_errors_mm(reg, heldout_verts, heldout_joints)
        if best is None or err["mean_mm"] < best[1]["mean_mm"]:
            best = (lam, err, reg)
    return best[0], best[2]


__all__ = ["RIDGE_LAMBDAS", "blend_shapes", "fit_on_betas", "fit_regressor", "joint_errors_mm", "pca_shape_space",
           "pick_regressor", "project_betas", "shape_space", "stature_sign"]

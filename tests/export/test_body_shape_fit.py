"""The body-model derivation's pure fits on synthetic arrays (export.body.shape_fit, export.body.tpose).

The derivation itself needs Anny (``make body-model``); these hold the arithmetic it relies on.
"""

import numpy as np
import pytest

from export.body.shape_fit import (
    blend_shapes,
    fit_on_betas,
    fit_regressor,
    pca_shape_space,
    pick_regressor,
    project_betas,
    shape_space,
    stature_sign,
)
from export.body.tpose import apply_pose, tpose_rotations, world_rotations


def linear_shapes(n=80, v=60, b=3, seed=0):
    """Meshes (n,v,3) exactly linear in b random shape directions, and their template."""
    rng = np.random.default_rng(seed)
    template = rng.normal(size=(v, 3))
    dirs = rng.normal(size=(v, 3, b)) * np.array([3.0, 2.0, 1.0])[:b]
    coeff = rng.normal(size=(n, b))
    return blend_shapes(template, dirs, coeff), template


def test_pca_betas_are_unit_variance_and_rebuild_the_meshes():
    verts, _ = linear_shapes()
    mean, dirs, betas, explained = pca_shape_space(verts, 3)
    assert mean.shape == (60, 3) and dirs.shape == (60, 3, 3) and betas.shape == (80, 3)
    np.testing.assert_allclose(betas.mean(0), 0.0, atol=1e-12)
    np.testing.assert_allclose(betas.std(0, ddof=1), 1.0, rtol=1e-10)
    np.testing.assert_allclose(blend_shapes(mean, dirs, betas), verts, atol=1e-10)
    assert explained == pytest.approx(1.0)
    np.testing.assert_allclose(project_betas(mean, dirs, verts[:5]), betas[:5], atol=1e-10)


def test_beta_zero_plus_is_taller():
    rng = np.random.default_rng(1)
    heights = rng.uniform(1.5, 1.9, 40)
    for y_bottom in (0.0, -1.0):  # head or feet farthest from y = 0: PCA's own sign differs, beta 0's must not
        body = np.column_stack([rng.normal(size=50), np.linspace(y_bottom, y_bottom + 1.0, 50), rng.normal(size=50)])
        verts = body[None] * np.stack([np.ones(40), heights, np.ones(40)], 1)[:, None]  # stature: y scaled
        raw_dirs = pca_shape_space(verts, 1)[1]
        mean, dirs, betas, _ = shape_space(verts, 1)
        assert stature_sign(mean, raw_dirs) == (1.0 if y_bottom == 0.0 else -1.0)
        assert stature_sign(mean, dirs) == 1.0
        np.testing.assert_allclose(blend_shapes(mean, dirs, betas), verts, atol=1e-10)
        assert np.corrcoef(betas[:, 0], heights)[0, 1] > 0.999


def test_another_mesh_fitted_on_the_same_betas():
    rng = np.random.default_rng(2)
    betas = rng.normal(size=(30, 4))
    template, dirs = rng.normal(size=(20, 3)), rng.normal(size=(20, 3, 4))
    got_template, got_dirs = fit_on_betas(blend_shapes(template, dirs, betas), betas)
    np.testing.assert_allclose(got_template, template, atol=1e-10)
    np.testing.assert_allclose(got_dirs, dirs, atol=1e-10)


def test_ridge_regressor_rows_sum_to_one_on_their_support():
    verts, template = linear_shapes(n=60, v=80)
    rng = np.random.default_rng(3)
    true = rng.dirichlet(np.ones(80), size=5)  # joints: convex combinations of the vertices
    joints = np.einsum("jv,nvk->njk", true, verts)
    reg = fit_regressor(verts, joints, template, support=30, lam=1e-3)
    np.testing.assert_allclose(reg.sum(1), 1.0, atol=1e-12)
    assert ((reg != 0).sum(1) <= 30).all()
    lam, picked = pick_regressor(verts[:50], joints[:50], template, 80, verts[50:], joints[50:], (1e-1, 1e-6))
    assert lam == 1e-6  # full support, tiny λ: the exact combination is found
    np.testing.assert_allclose(np.einsum("jv,nvk->njk", picked, verts[50:]), joints[50:], atol=1e-4)
    with pytest.raises(ValueError, match="at least one"):
        pick_regressor(verts, joints, template, 30, verts, joints, ())


def tiny_arm():
    """An A-posed arm per side (Anny frame: z up, facing −y) under one root bone."""
    labels, heads, parents = ["root"], [[0.0, 0.0, 1.0]], [-1]
    for s, x in (("L", 1.0), ("R", -1.0)):
        for name, at, parent in (("upperarm01", [0.2 * x, 0.0, 1.4], "root"), ("lowerarm01", [0.4 * x, 0.0, 1.2], "upperarm01"),
                                 ("wrist", [0.6 * x, 0.05, 1.0], "lowerarm01"), ("finger2-1", [0.7 * x, -0.03, 0.9], "wrist"),
                                 ("finger5-1", [0.7 * x, 0.03, 0.9], "wrist")):
            labels.append(f"{name}.{s}")
            heads.append(at)
            parents.append(labels.index(f"{parent}.{s}") if parent != "root" else 0)
    return labels, np.array(heads), parents


def test_tpose_puts_both_arms_level_and_straight():
    labels, heads, parents = tiny_arm()
    rotations, angles = tpose_rotations(heads, labels)
    rots = world_rotations(labels, parents, rotations)
    np.testing.assert_allclose(rots[0], np.eye(3))
    np.testing.assert_allclose(rots[labels.index("finger2-1.L")], rotations["wrist.L"])  # inherited from the wrist
    _, posed = apply_pose(np.zeros((1, 1, 3)), heads[None], np.eye(len(labels))[:1], rots, parents)
    at = {label: posed[0, i] for i, label in enumerate(labels)}
    for s, x in (("L", 1.0), ("R", -1.0)):
        for a, b in (("upperarm01", "lowerarm01"), ("lowerarm01", "wrist")):
            d = at[f"{b}.{s}"] - at[f"{a}.{s}"]
            np.testing.assert_allclose(d / np.linalg.norm(d), [x, 0.0, 0.0], atol=1e-12)
        assert at[f"finger2-1.{s}"][1] < at[f"finger5-1.{s}"][1]  # index knuckle in front (−y): palm down
    assert set(angles) == {f"{side} {n}" for side in ("left", "right") for n in ("upper arm", "elbow", "hand roll")}

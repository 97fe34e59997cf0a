"""The shared pose metrics: each one against a case whose answer is known by construction."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from export.metrics import (
    heading_error_rad,
    heading_rad,
    joint_errors,
    local_mpjpe,
    mpjpe,
    pa_mpjpe,
    procrustes_align,
    pve,
    with_true_orientation,
)

UPRIGHT = np.array([np.pi / 2, 0.0, 0.0])  # canonical Y up → carpet z up


def _skeleton(rng, n=5, j=24):
    return rng.normal(0, 0.3, (n, j, 3))


def test_mpjpe_is_pelvis_aligned_and_averages_joints():
    rng = np.random.default_rng(0)
    true = _skeleton(rng)
    pred = true + np.array([1.0, -2.0, 0.5])  # the whole body moved: no pose error
    assert np.allclose(mpjpe(pred, true), 0)
    pred[:, 3] += [0.0, 0.24, 0.0]  # one joint of 24 off by 24 cm → 1 cm mean
    assert np.allclose(mpjpe(pred, true), 0.01)
    assert joint_errors(pred, true, root=None).shape == (5, 24)


def test_mpjpe_rejects_mismatched_shapes():
    with pytest.raises(ValueError, match="same"):
        mpjpe(np.zeros((2, 24, 3)), np.zeros((2, 23, 3)))


def test_pa_mpjpe_removes_similarity_but_not_mirror():
    rng = np.random.default_rng(1)
    true = _skeleton(rng, n=8)
    rot = Rotation.random(8, random_state=2).as_matrix()
    pred = 1.3 * np.einsum("nab,njb->nja", rot, true) + rng.normal(0, 1, (8, 1, 3))
    assert mpjpe(pred, true).min() > 0.05
    assert np.allclose(pa_mpjpe(pred, true), 0, atol=1e-9)
    assert np.allclose(procrustes_align(pred, true), true, atol=1e-9)
    mirrored = true * np.array([-1.0, 1.0, 1.0])  # a reflection is not a rotation: must stay an error
    assert (pa_mpjpe(mirrored, true) > 0.01).all()


def test_procrustes_minimises_the_squared_error():
    rng = np.random.default_rng(3)
    true = _skeleton(rng, n=20)
    pred = true + rng.normal(0, 0.05, true.shape)
    sq = lambda a: ((a - true) ** 2).sum((-2, -1))  # noqa: E731 — what Procrustes minimises
    best = sq(procrustes_align(pred, true))
    centred = sq(pred - pred.mean(1, keepdims=True) + true.mean(1, keepdims=True))
    assert (best <= centred + 1e-12).all()
    nudged = Rotation.from_rotvec([0, 0, 0.02]).as_matrix()
    moved = procrustes_align(pred, true)
    c = moved.mean(1, keepdims=True)
    assert (best <= sq((moved - c) @ nudged.T + c)).all()


@pytest.mark.parametrize("tilt", [UPRIGHT, np.zeros(3), np.array([0.0, 0.0, np.pi / 2]), np.array([0.3, -1.2, 2.0])])
def test_heading_error_is_the_turn_about_the_vertical(tilt):
    turns = np.radians([0.0, 30.0, -75.0, 179.0, -120.0])
    true = np.tile(tilt, (len(turns), 1))
    pred = (Rotation.from_rotvec(turns[:, None] * [0, 0, 1]) * Rotation.from_rotvec(true)).as_rotvec()
    assert np.allclose(heading_error_rad(pred, true), turns, atol=1e-9)


def test_heading_error_ignores_a_pure_tilt_and_wraps():
    true = np.tile(UPRIGHT, (3, 1))
    tilted = (Rotation.from_rotvec([[0.4, 0, 0], [0, -0.6, 0], [0.2, 0.3, 0]]) * Rotation.from_rotvec(true)).as_rotvec()
    assert np.allclose(heading_error_rad(tilted, true), 0, atol=1e-9)
    turned = (Rotation.from_rotvec([0, 0, np.radians(270)]) * Rotation.from_rotvec(UPRIGHT)).as_rotvec()
    assert np.isclose(heading_error_rad(turned, UPRIGHT), np.radians(-90))


def test_heading_of_one_body_is_its_turn_from_upright():
    turns = np.radians([0.0, 45.0, -100.0, 180.0])
    orient = (Rotation.from_rotvec(turns[:, None] * [0, 0, 1]) * Rotation.from_rotvec(UPRIGHT)).as_rotvec()
    assert np.allclose(np.cos(heading_rad(orient) - turns), 1)
    assert np.allclose(heading_rad(UPRIGHT), 0)


def test_local_mpjpe_ignores_the_global_orientation():
    from edge.body import BodyModel

    body = BodyModel.load("lite")
    rng = np.random.default_rng(4)
    true_pose = rng.normal(0, 0.2, (3, 72))
    true_pose[:, :3] = UPRIGHT
    betas = rng.normal(0, 0.5, (3, 10))
    true_joints = body.forward(true_pose, betas)["joints"]
    pred_pose = true_pose.copy()
    pred_pose[:, :3] = [[0, 0, 1.0], [1.0, 0, 0], [0.5, 0.5, 0.5]]  # wrong heading/tilt, right local pose
    assert mpjpe(body.forward(pred_pose, betas)["joints"], true_joints).min() > 0.05
    assert np.allclose(local_mpjpe(body, pred_pose, betas, true_joints, true_pose), 0, atol=1e-6)
    assert np.allclose(with_true_orientation(pred_pose, true_pose)[:, 3:], pred_pose[:, 3:])
    bent = pred_pose.copy()
    bent[:, 3 * 18:3 * 19] += 1.0  # the left elbow differs: local error remains
    assert (local_mpjpe(body, bent, betas, true_joints, true_pose) > 0.005).all()


def test_pve_moves_each_mesh_by_its_pelvis():
    rng = np.random.default_rng(5)
    verts = rng.normal(0, 0.3, (2, 50, 3))
    pelvis = rng.normal(0, 1, (2, 3))
    shift = np.array([0.5, 0.1, -0.2])
    assert np.allclose(pve(verts + shift, verts, pelvis + shift, pelvis), 0)
    off = verts + shift
    off[:, :10] += [0, 0, 0.1]  # a fifth of the vertices 10 cm off → 2 cm
    assert np.allclose(pve(off, verts, pelvis + shift, pelvis), 0.02)

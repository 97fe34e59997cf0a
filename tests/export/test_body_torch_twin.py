"""The torch twin of edge.body: parity with numpy, gradients, hard angles."""

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from edge.body import BodyModel  # noqa: E402
from edge.body.rotations import axis_angle_to_matrix as np_rodrigues  # noqa: E402
from export.body.torch_body import TorchBodyModel, axis_angle_to_matrix  # noqa: E402


@pytest.mark.parametrize("name", ["lite", "full"])
def test_parity_float64(name):
    """Random poses (σ = 1 rad), shapes (|β| ≤ 3) and translations: joints and vertices of
    the twin equal numpy's within 1e-6 m in float64 (measured ~1e-15)."""
    rng = np.random.default_rng(0)
    pose, betas, transl = rng.normal(size=(6, 72)), np.clip(rng.normal(size=(6, 10)) * 1.5, -3, 3), rng.normal(size=(6, 3))
    ref = BodyModel.load(name, vertex_dtype=np.float64).forward(pose, betas, transl, vertices=True)
    twin = TorchBodyModel.load(name, dtype=torch.float64)
    out = twin(torch.tensor(pose), torch.tensor(betas), torch.tensor(transl), vertices=True)
    for key in ("joints", "vertices"):
        err = np.abs(out[key].numpy() - ref[key]).max()
        assert err < 1e-6, (key, err)


def test_gradients_finite_at_zero_and_pi():
    """d(vertices)/d(pose) is finite at the rest pose (angle 0) and at π."""
    twin = TorchBodyModel.load("lite", dtype=torch.float64)
    for value in (0.0, np.pi):
        pose = torch.zeros(1, 72, dtype=torch.float64)
        pose[0, 3:] = value / np.sqrt(3)
        pose.requires_grad_(True)
        betas = torch.zeros(1, 10, dtype=torch.float64, requires_grad=True)
        out = twin(pose, betas, None, vertices=True)
        (out["vertices"].sum() + out["joints"].square().sum()).backward()
        assert torch.isfinite(pose.grad).all() and torch.isfinite(betas.grad).all()
        assert pose.grad.abs().sum() > 0


def test_rodrigues_hard_angles_match_numpy():
    """0, 1e-8, π, π−1e-9, 2π+0.3, 1e6 rad: torch and numpy Rodrigues agree to 1e-12."""
    axis = np.array([0.36, -0.48, 0.8])
    angles = [0.0, 1e-8, np.pi, np.pi - 1e-9, 2 * np.pi + 0.3, 1e6]
    v = np.stack([a * axis for a in angles] + [np.full(3, -1e-8)])
    t = axis_angle_to_matrix(torch.tensor(v)).numpy()
    assert np.abs(t - np_rodrigues(v)).max() < 1e-12
    assert torch.isfinite(axis_angle_to_matrix(torch.full((1, 3), -1e-8, dtype=torch.float32))).all()


def test_float32_twin_close_to_float64():
    """Training runs in float32: within 20 µm of float64 on random bodies."""
    rng = np.random.default_rng(1)
    pose, betas = torch.tensor(rng.normal(size=(4, 72))), torch.tensor(rng.normal(size=(4, 10)))
    a = TorchBodyModel.load("lite", dtype=torch.float32)(pose.float(), betas.float(), None, vertices=True)
    b = TorchBodyModel.load("lite", dtype=torch.float64)(pose, betas, None, vertices=True)
    assert (a["vertices"].double() - b["vertices"]).abs().max() < 2e-5

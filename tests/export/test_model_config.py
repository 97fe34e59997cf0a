"""Model configuration, presets, rotations and output shapes (fast, no data)."""

from __future__ import annotations

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from export.model import CAvatarNet, ModelConfig, matrix_to_rot6d, rot6d_to_matrix  # noqa: E402
from export.model.heads import OUTPUT_SIZES  # noqa: E402


def test_presets_and_unknown_keys():
    paper = ModelConfig.preset("paper")
    assert (paper.encoder, paper.features, paper.layers, paper.heads, paper.d_model, paper.ff) == ("resnet18", 256, 6, 4, 256, 2048)
    assert paper.dropout == 0.1 and paper.layer_norm_eps == 1e-5 and paper.window == 40
    assert ModelConfig.from_dict(paper.to_dict()) == paper
    with pytest.raises(ValueError, match="unknown model config option.*colour.*accepted: .*head"):
        ModelConfig.from_dict({**paper.to_dict(), "colour": "red"})
    with pytest.raises(ValueError, match="head must be"):
        ModelConfig.preset("lean", head="lstm")


@pytest.mark.parametrize("head", ["transformer", "gru", "mean"])
def test_output_shapes_for_every_head(head):
    cfg = ModelConfig.preset("lean", grid=(32, 32), head=head, encoder_widths=(8, 16), features=16, d_model=16, heads=2, ff=32)
    net = CAvatarNet(cfg).eval()
    out = net.forward_chunk(torch.rand(42, 1, 32, 32))
    assert {k: tuple(v.shape) for k, v in out.items()} == {k: (3, n) if k != "confidence" else (3,) for k, n in OUTPUT_SIZES.items()}


def test_paper_transformer_has_no_nested_tensor_fast_path():
    net = CAvatarNet(ModelConfig.preset("paper", grid=(32, 32)))
    assert net.head.encoder.enable_nested_tensor is False
    assert len(net.head.encoder.layers) == 6


def test_rot6d_round_trip_and_upright_default():
    from edge.infer.rotations import rot6d_to_axis_angle

    r = rot6d_to_matrix(torch.randn(100, 6))
    torch.testing.assert_close(r.transpose(-1, -2) @ r, torch.eye(3).expand(100, 3, 3), atol=1e-5, rtol=0)
    torch.testing.assert_close(rot6d_to_matrix(matrix_to_rot6d(r)), r, atol=1e-5, rtol=0)
    # a zero network output is a person standing upright: +90° about x
    net = CAvatarNet(ModelConfig.preset("lean", grid=(32, 32), encoder_widths=(8,), features=8, d_model=8, heads=2, ff=8))
    torch.nn.init.zeros_(net.head.params.out.weight)
    with torch.no_grad():
        out = net.forward_chunk(torch.zeros(40, 1, 32, 32))
    aa = rot6d_to_axis_angle(out["rot6d"].numpy())
    np.testing.assert_allclose(aa[0, :3], [np.pi / 2, 0, 0], atol=1e-6)
    np.testing.assert_allclose(aa[0, 3:], 0, atol=1e-6)


def test_training_normalisation_matches_the_board():
    from edge.infer.normalise import normalise_kpa

    p = np.abs(np.random.default_rng(0).normal(0, 5, (4, 8, 8))).astype(np.float32)
    np.testing.assert_allclose(torch.log1p(torch.from_numpy(p)).numpy(), normalise_kpa(p), rtol=1e-6)


def test_person_masks_split_two_people():
    from export.data import person_masks

    pitch = 0.05
    p = np.zeros((20, 20), np.float32)
    p[5, 3] = p[5, 16] = 10.0
    joints = np.zeros((3, 24, 3))
    joints[0, :, :2] = [3.5 * pitch, 5.5 * pitch]
    joints[1, :, :2] = [16.5 * pitch, 5.5 * pitch]
    m = person_masks(p, joints, np.array([True, True, False]), pitch)
    assert m[0, 5, 3] and not m[0, 5, 16] and m[1, 5, 16] and not m[1, 5, 3] and not m[2].any()

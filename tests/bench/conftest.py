"""Fixtures of the benchmark tests: a tiny simulated dataset (32×32, three subjects, like tests/export's) and a tiny
bundle with random weights and its weights.npz (what `cavatar bundle` writes, without the training)."""

from __future__ import annotations

import pytest

PITCH_MM = 19.05 * 3


@pytest.fixture(scope="session")
def tiny_data(tmp_path_factory):
    from sim.dataset.generate import generate

    out = tmp_path_factory.mktemp("tiny32") / "data"
    generate(out, subjects=3, seconds_per_activity=1.0, grid=32, pitch_mm=PITCH_MM, seed=3, workers=1, progress=False,
             activities=("stepping", "squat"))
    return out


def _tiny_bundle(out):
    import numpy as np
    import torch

    from export.bundle import write_bundle
    from export.model import CAvatarNet, ModelConfig
    from export.onnx_export import export_onnx
    from export.quantize import quantize_encoder

    torch.manual_seed(1)
    cfg = ModelConfig.preset("tiny", grid=(32, 32))
    net = CAvatarNet(cfg).eval()
    rng = np.random.default_rng(0)
    calib = np.log1p(rng.gamma(0.5, 4.0, (8, 1, 32, 32)) * (rng.random((8, 1, 32, 32)) < 0.2)).astype(np.float32)
    graphs = export_onnx(net, out / "graphs")
    enc8 = quantize_encoder(graphs["encoder"], out / "graphs" / "encoder.int8.onnx", calib)
    weights = {k: v.detach().numpy() for k, v in net.state_dict().items()}
    return write_bundle(out / "bundle", enc8, graphs["head"], cfg, name="tiny-32", pitch_m=PITCH_MM / 1000,
                        body_model="lite", quantization={"precision": "int8", "head_quantization": "float"}, weights=weights)


@pytest.fixture(scope="session")
def tiny_bundle(tmp_path_factory):
    """A 32×32 bundle: int8 encoder, float head, weights.npz (random weights: the numbers are not the point)."""
    pytest.importorskip("torch")
    pytest.importorskip("onnxscript")
    return _tiny_bundle(tmp_path_factory.mktemp("tiny_bundle"))


@pytest.fixture(scope="session")
def bundle_without_weights(tiny_bundle, tmp_path_factory):
    """The same graphs in a bundle that carries no weights.npz (as the untrained placeholder does)."""
    import json
    import shutil

    from edge.infer.bundle import sha256_file

    out = tmp_path_factory.mktemp("no_weights") / "bundle"
    out.mkdir()
    for name in ("encoder.onnx", "head.onnx"):
        shutil.copyfile(tiny_bundle / name, out / name)
    manifest = json.loads((tiny_bundle / "manifest.json").read_text())
    manifest.pop("weights", None)
    manifest["files"] = {f: sha256_file(out / f) for f in ("encoder.onnx", "head.onnx")}
    from edge.infer.bundle import write_manifest

    write_manifest(out, manifest)
    return out

"""Train a tiny model on a tiny simulated dataset, resume it, export it, quantize it, bundle it."""

from __future__ import annotations

import json

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("onnxscript")

from export.model import ModelConfig  # noqa: E402
from export.train import TrainConfig, Trainer, load_model  # noqa: E402


def _trainer(data, out, steps, lr=3e-3, **kw):
    cfg = TrainConfig(data=str(data), out=str(out), steps=steps, batch=6, lr=lr, val_every=0, checkpoint_every=1000,
                      log_every=1, progress=False, seed=5, threads=1, **kw)
    return Trainer(cfg, ModelConfig.preset("tiny"))


@pytest.fixture(scope="module")
def trained(tiny_data, tmp_path_factory):
    out = tmp_path_factory.mktemp("run")
    tr = _trainer(tiny_data, out, steps=40)
    tr.cfg.val_every = 40
    tr.run()
    return out


def test_loss_goes_down(trained):
    lines = [json.loads(x) for x in (trained / "log.jsonl").read_text().splitlines()]
    losses = [x["loss"] for x in lines if "loss" in x]
    assert len(losses) == 40
    assert np.mean(losses[-8:]) < 0.8 * np.mean(losses[:8])
    val = [x["val"] for x in lines if "val" in x]
    assert val and np.isfinite(val[-1]["mpjpe_cm"])
    assert (trained / "checkpoint.pt").exists() and (trained / "best.pt").exists()


def test_resume_gives_the_same_next_step(tiny_data, tmp_path):
    straight = _trainer(tiny_data, tmp_path / "a", steps=5)
    straight.run()
    first = _trainer(tiny_data, tmp_path / "b", steps=3)
    first.run()
    resumed = _trainer(tiny_data, tmp_path / "b", steps=5)
    resumed.load(tmp_path / "b" / "checkpoint.pt")
    assert resumed.step == 3
    resumed.run()
    for (name, a), (_, b) in zip(straight.net.state_dict().items(), resumed.net.state_dict().items()):
        assert torch.equal(a, b), name


def test_chunk_path_equals_window_path(trained):
    net = load_model(trained / "checkpoint.pt")
    x = torch.rand(45, 1, 32, 32)
    chunk = net.forward_chunk(x)
    windows = x.unfold(0, 40, 1).permute(0, 4, 1, 2, 3)  # (6,40,1,32,32)
    direct = net(windows)
    for k in chunk:
        torch.testing.assert_close(chunk[k], direct[k], atol=1e-5, rtol=1e-5)


def test_export_parity_quantize_gate_and_bundle(trained, tiny_data, tmp_path):
    from edge.body import BodyModel
    from edge.infer import ModelBundle
    from export.bundle import write_bundle
    from export.data import load_tracks
    from export.evaluate import track_inputs
    from export.onnx_export import export_onnx, parity
    from export.quantize import quantize_and_gate

    net = load_model(trained / "checkpoint.pt")
    paths = export_onnx(net, tmp_path / "fp32")
    diffs = parity(net, paths["encoder"], paths["head"], batch=5)
    assert max(diffs.values()) <= 1e-4, diffs

    pitch = 19.05e-3 * 3
    tracks = load_tracks(tiny_data, "val")
    calib = track_inputs(load_tracks(tiny_data, "train")[0], pitch, 0)[0]
    report = quantize_and_gate(paths, tmp_path / "int8", calib, tracks, 40, pitch, BodyModel.load("lite"), latency_repeats=3)
    assert report["gate_passed"], report
    assert report["head_quantization"] in ("float", "dynamic_uint8")

    bundle_dir = write_bundle(tmp_path / "bundle", paths["encoder"], paths["head"], net.cfg, name="tiny-32", pitch_m=pitch,
                              quantization={k: v for k, v in report.items() if k not in ("encoder", "head")})
    b = ModelBundle.load(bundle_dir, grid=(32, 32))
    x = np.asarray(calib[:45], np.float32)
    feats = b.encode(x)
    windows = np.lib.stride_tricks.sliding_window_view(feats, 40, axis=0).transpose(0, 2, 1)
    out = b.head(np.ascontiguousarray(windows))
    assert out["pose_aa"].shape == (6, 72) and out["activity_probs"].shape == (6, 12) and out["confidence"].shape == (6,)
    with torch.no_grad():
        ref = net.forward_chunk(torch.from_numpy(x))
    np.testing.assert_allclose(out["betas"], ref["betas"].numpy(), atol=1e-4)
    np.testing.assert_allclose(out["transl_rel_m"], ref["transl_rel_m"].numpy(), atol=1e-4)

"""Export a trained CAvatarNet as two ONNX graphs (the bundle contract, design.md):

    encoder.onnx   input "pressure" (B,1,H,W) float32, normalised  → "features" (B,F); B dynamic
    head.onnx      input "features" (B,T,F), T fixed (40)          → rot6d (B,144), betas (B,10),
                   transl_rel_m (B,3), activity_logits (B,12), confidence (B,); B dynamic

Measured facts this follows (readout-and-edge.md): the dynamo exporter (the legacy one fails on
the transformer's fast path), ``external_data=False`` (weights inside the file), an example
batch of 2 (a batch of 1 silently fixes B = 1), T fixed (a dynamic T breaks quant_pre_process).
"""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import torch

from export.model import OUTPUTS, CAvatarNet

ENCODER_INPUT, ENCODER_OUTPUT, HEAD_INPUT = "pressure", "features", "features"
OPSET = 20


class _Head(torch.nn.Module):
    def __init__(self, head: torch.nn.Module):
        super().__init__()
        self.head = head

    def forward(self, features: torch.Tensor):
        return tuple(self.head(features))


def export_onnx(net: CAvatarNet, out_dir: str | Path, example_batch: int = 2) -> dict[str, Path]:
    """Write encoder.onnx and head.onnx into ``out_dir``; returns their paths."""
    if example_batch < 2:
        raise ValueError("export with an example batch of at least 2 (a batch of 1 fixes B = 1 in the graph)")
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    net = net.cpu().eval()
    cfg = net.cfg
    h, w = cfg.grid
    batch = torch.export.Dim("batch", min=1, max=65536)
    paths = {"encoder": out / "encoder.onnx", "head": out / "head.onnx"}
    with warnings.catch_warnings(), torch.no_grad():
        warnings.simplefilter("ignore")
        torch.onnx.export(net.encoder, (torch.rand(example_batch, 1, h, w),), paths["encoder"], dynamo=True,
                          external_data=False, opset_version=OPSET, input_names=[ENCODER_INPUT],
                          output_names=[ENCODER_OUTPUT], dynamic_shapes=({0: batch},), verbose=False)
        torch.onnx.export(_Head(net.head).eval(), (torch.randn(example_batch, cfg.window, cfg.features),), paths["head"],
                          dynamo=True, external_data=False, opset_version=OPSET, input_names=[HEAD_INPUT],
                          output_names=list(OUTPUTS), dynamic_shapes=({0: batch},), verbose=False)
    return paths


def parity(net: CAvatarNet, encoder_path: str | Path, head_path: str | Path, batch: int = 3, seed: int = 0,
           inputs: np.ndarray | None = None) -> dict[str, float]:
    """Max |ONNX fp32 − torch| per output (encoder 'features' and every head output)."""
    import onnxruntime as ort

    net = net.cpu().eval()
    cfg = net.cfg
    rng = np.random.default_rng(seed)
    x = inputs if inputs is not None else np.log1p(rng.gamma(0.5, 4.0, (batch, 1, *cfg.grid)) * (rng.random((batch, 1, *cfg.grid)) < 0.1))
    x = np.asarray(x, np.float32)
    opts = ort.SessionOptions()
    opts.intra_op_num_threads = 1
    enc = ort.InferenceSession(str(encoder_path), opts, providers=["CPUExecutionProvider"])
    head = ort.InferenceSession(str(head_path), opts, providers=["CPUExecutionProvider"])
    with torch.no_grad():
        f_t = net.encoder(torch.from_numpy(x)).numpy()
        windows = rng.standard_normal((x.shape[0], cfg.window, cfg.features)).astype(np.float32) * f_t.std() + f_t.mean()
        h_t = [v.numpy() for v in net.head(torch.from_numpy(windows))]
    f_o = enc.run(None, {ENCODER_INPUT: x})[0]
    h_o = head.run(None, {HEAD_INPUT: windows})
    diffs = {"features": float(np.abs(f_o - f_t).max())}
    for name, a, b in zip(OUTPUTS, h_o, h_t):
        diffs[name] = float(np.abs(a - b).max())
    return diffs

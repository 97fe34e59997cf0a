"""Per-frame model cost on ONE thread: encoder and head, fp32 vs int8, for the shipped bundle
(and, with --paper, the paper-size architecture with random weights for comparison).
Writes bench/results/model_latency.json.

    python -m bench.model_latency --checkpoint RUN/best.pt --bundle edge/models/lean-96 [--paper]

Per published frame the runtime runs the encoder once (batch 1, the new frame) and the head once
(batch 1, the 40-frame window), so "per_frame_ms" = encoder + head. onnxruntime sessions as on the
board: intra-op threads 1, allow_spinning 0. Sessions are timed interleaved, median of rounds.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import tempfile
import time
from pathlib import Path

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import numpy as np  # noqa: E402

from export.quantize import session  # noqa: E402


def median_ms(sess, feed, rounds: int = 7, per_round: int = 30) -> float:
    for _ in range(5):
        sess.run(None, feed)
    times = []
    for _ in range(rounds):
        t = time.perf_counter()
        for _ in range(per_round):
            sess.run(None, feed)
        times.append((time.perf_counter() - t) / per_round)
    return round(float(np.median(times)) * 1e3, 3)


def measure(graphs: dict[str, Path], grid, window, features, rng) -> dict:
    x = np.log1p(rng.gamma(0.5, 4.0, (1, 1, *grid)) * (rng.random((1, 1, *grid)) < 0.1)).astype(np.float32)
    w = rng.standard_normal((1, window, features)).astype(np.float32)
    out = {}
    for key, path in graphs.items():
        feed = {"pressure": x} if key.startswith("encoder") else {"features": w}
        out[f"{key}_ms"] = median_ms(session(path, threads=1), feed)
    return out


def lean_from_bundle(checkpoint: Path, bundle: Path, rng) -> dict:
    from export.onnx_export import export_onnx
    from export.train import load_model

    manifest = json.loads((bundle / "manifest.json").read_text())
    net = load_model(checkpoint)
    with tempfile.TemporaryDirectory() as tmp:
        fp32 = export_onnx(net, tmp)
        graphs = {"encoder_fp32": fp32["encoder"], "encoder_int8": bundle / "encoder.onnx",
                  "head_fp32": fp32["head"], "head_shipped": bundle / "head.onnx"}
        r = measure(graphs, tuple(manifest["grid"]), manifest["window"], manifest["features"], rng)
    r["head_shipped_precision"] = manifest["quantization"].get("head_quantization")
    r["per_frame_fp32_ms"] = round(r["encoder_fp32_ms"] + r["head_fp32_ms"], 3)
    r["per_frame_shipped_ms"] = round(r["encoder_int8_ms"] + r["head_shipped_ms"], 3)
    r["bundle"] = manifest["name"]
    r["model_config"] = manifest["model_config"]
    return r


def paper_random(rng, grid=(96, 96)) -> dict:
    import torch

    from export.model import CAvatarNet, ModelConfig
    from export.onnx_export import export_onnx
    from export.quantize import quantize_encoder, quantize_head_dynamic

    torch.manual_seed(0)
    cfg = ModelConfig.preset("paper", grid=grid)
    net = CAvatarNet(cfg).eval()
    with tempfile.TemporaryDirectory() as tmp:
        fp32 = export_onnx(net, tmp)
        calib = np.log1p(rng.gamma(0.5, 4.0, (32, 1, *grid)) * (rng.random((32, 1, *grid)) < 0.1)).astype(np.float32)
        graphs = {"encoder_fp32": fp32["encoder"], "encoder_int8": quantize_encoder(fp32["encoder"], Path(tmp) / "e8.onnx", calib),
                  "head_fp32": fp32["head"], "head_int8": quantize_head_dynamic(fp32["head"], Path(tmp) / "h8.onnx")}
        r = measure(graphs, grid, cfg.window, cfg.features, rng)
    r["per_frame_fp32_ms"] = round(r["encoder_fp32_ms"] + r["head_fp32_ms"], 3)
    r["per_frame_int8_ms"] = round(r["encoder_int8_ms"] + r["head_int8_ms"], 3)
    r["note"] = "random weights: latency only"
    return r


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--checkpoint", type=Path, required=True)
    ap.add_argument("--bundle", type=Path, default=Path("edge/models/lean-96"))
    ap.add_argument("--paper", action="store_true", help="also time the paper-size architecture (random weights)")
    ap.add_argument("--out", type=Path, default=Path("bench/results/model_latency.json"))
    args = ap.parse_args(argv)
    import onnxruntime as ort

    rng = np.random.default_rng(0)
    result = {"bench": "model_latency", "threads": 1, "batch": 1,
              "machine": {"platform": platform.platform(), "processor": platform.processor() or platform.machine(),
                          "cpus": os.cpu_count(), "load_average_at_start": [round(x, 2) for x in os.getloadavg()]},
              "onnxruntime": ort.__version__, "lean": lean_from_bundle(args.checkpoint, args.bundle, rng)}
    if args.paper:
        result["paper_random_weights"] = paper_random(rng)
    result["goal"] = "lean encoder + head ≤ 3 ms per frame in int8 on one core"
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(json.dumps(result, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The model variants speed_error times: a bundle as it ships, its fp32 twin, an untrained architecture in
fp32 and int8; and the simulated model inputs they are timed on."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bench import BenchmarkError
from bench.simulated_day import ACTIVE_1, RATE_HZ


@dataclass
class Variant:
    name: str
    source: str
    precision: str
    weights: str
    trained: bool | None  # None: unknown (a bundle without weights.npz)
    encoder: Path
    head: Path
    grid: tuple[int, int]
    pitch_m: float
    window: int
    features: int
    bundle_dir: Path | None = None  # a bundle folder (evaluate_bundle loads it as the board does)

    def describe(self) -> dict[str, Any]:
        enc, head = self.encoder.stat().st_size, self.head.stat().st_size
        return {"name": self.name, "source": self.source, "precision": self.precision, "weights": self.weights,
                "trained": self.trained, "grid": list(self.grid), "window": self.window, "features": self.features,
                "size_bytes": {"encoder": enc, "head": head, "total": enc + head}}



def person_frames(grid: tuple[int, int], pitch_m: float, n: int = 32, seed: int = 0) -> tuple[np.ndarray, str]:
    """(n,1,H,W) normalised model inputs of one simulated moving person on this carpet, and what they are."""
    from edge.infer.model_input import person_pressure_kpa
    from edge.infer.normalise import normalise_kpa

    try:
        from sim.live import LiveCarpet

        carpet = LiveCarpet(grid[0], grid[1], people=1, seed=seed, pitch_mm=pitch_m * 1e3, activities=ACTIVE_1)
        p = np.stack([person_pressure_kpa(f, f > 0) for f in (carpet.pressure_kpa(2 * k) for k in range(n))])
        what = f"{n} frames of one simulated person (sim.live, {', '.join(ACTIVE_1)}), floored/clipped as in training"
    except ValueError:  # a carpet the simulator does not make
        rng = np.random.default_rng(seed)
        p = (rng.gamma(0.5, 4.0, (n, *grid)) * (rng.random((n, *grid)) < 0.1)).astype(np.float32)
        what = f"{n} synthetic sparse frames (gamma pressure on 10 % of sensels)"
    return normalise_kpa(p)[:, None].astype(np.float32), what



def manifest_of(folder: Path) -> dict[str, Any]:
    from edge.infer import BundleError, verify

    try:
        return verify(folder)
    except BundleError as exc:
        raise BenchmarkError(str(exc)) from None


def require_weights(folder: Path, manifest: dict[str, Any]) -> None:
    """Errors are wanted: a bundle must carry the weights its fp32 twin is exported from."""
    from export.bundle import WEIGHTS

    if WEIGHTS not in manifest["files"]:
        raise BenchmarkError(f"{folder}: the bundle carries no {WEIGHTS}, so its fp32 twin cannot be exported and its "
                             "errors would not be those of a trained model. Rebuild it with `cavatar bundle` from its "
                             "checkpoint, or run without --data (speed only: the twin then gets random weights).")


def bundle_variants(folder: str | Path, work: Path, need_weights: bool, seed: int = 0):
    """A bundle as it ships and its fp32 twin (exported from weights.npz into ``work``)
    → (variants, torch net, the fp32 variant, manifest)."""
    import torch

    from export.bundle import WEIGHTS, load_net, write_bundle
    from export.model import CAvatarNet, ModelConfig
    from export.onnx_export import export_onnx

    folder = Path(folder)
    manifest = manifest_of(folder)
    has_weights = WEIGHTS in manifest["files"]
    if need_weights:
        require_weights(folder, manifest)
    name = manifest["name"]
    cfg = ModelConfig.from_dict(manifest["model_config"])
    if has_weights:
        net, _ = load_net(folder)
    else:
        torch.manual_seed(seed)
        net = CAvatarNet(cfg).eval()
    q = manifest.get("quantization") or {}
    precision = q.get("precision", "fp32")
    common = dict(grid=tuple(int(g) for g in manifest["grid"]), pitch_m=float(manifest["pitch_m"]),
                  window=int(manifest["window"]), features=int(manifest["features"]))
    head_kind = "int8 dynamic (uint8 weights)" if q.get("head_quantization") == "dynamic_uint8" else "float"
    shipped = Variant(f"{name} {precision}", f"bundle {folder}",
                      "encoder int8 (static QDQ per channel), head " + head_kind if precision == "int8" else "fp32",
                      "trained (bundle weights.npz)" if has_weights else "as shipped (the bundle has no weights.npz)",
                      True if has_weights else None, folder / "encoder.onnx", folder / "head.onnx", bundle_dir=folder, **common)
    if precision == "fp32":
        return [shipped], net, shipped, manifest
    graphs = export_onnx(net, work / "graphs")
    twin_dir = write_bundle(work / "bundle", graphs["encoder"], graphs["head"], cfg, name=f"{name}-fp32-twin",
                            pitch_m=common["pitch_m"], rate_hz=float(manifest.get("rate_hz", RATE_HZ)),
                            body_model=manifest["body_model"]["name"], quantization={"precision": "fp32"})
    twin = Variant(f"{name} fp32", f"fp32 twin of {folder}: {WEIGHTS} → export.onnx_export", "fp32",
                   "trained (bundle weights.npz)" if has_weights else "random (the bundle has no weights.npz)",
                   has_weights, twin_dir / "encoder.onnx", twin_dir / "head.onnx", bundle_dir=twin_dir, **common)
    return [shipped, twin], net, twin, manifest


def untrained_variants(name: str, cfg: Any, pitch_m: float, tmp: Path, calib: np.ndarray, seed: int = 0) -> list[Variant]:
    """An architecture with random weights, fp32 and int8 (encoder static QDQ per channel, head dynamic uint8)."""
    import torch

    from export.model import CAvatarNet
    from export.onnx_export import export_onnx
    from export.quantize import quantize_encoder, quantize_head_dynamic

    torch.manual_seed(seed)
    net = CAvatarNet(cfg).eval()
    work = tmp / f"untrained-{name}"
    fp = export_onnx(net, work)
    enc8 = quantize_encoder(fp["encoder"], work / "encoder.int8.onnx", calib)
    head8 = quantize_head_dynamic(fp["head"], work / "head.int8.onnx")
    common = dict(source=f"ModelConfig preset {cfg.name!r}, random weights", weights="random (untrained)", trained=False,
                  grid=tuple(cfg.grid), pitch_m=pitch_m, window=cfg.window, features=cfg.features)
    return [Variant(f"{name} fp32", precision="fp32", encoder=fp["encoder"], head=fp["head"], **common),
            Variant(f"{name} int8", precision="encoder int8 (static QDQ per channel), head int8 dynamic (uint8 weights)",
                    encoder=enc8, head=head8, **common)]

"""Write a model bundle (design.md): encoder.onnx, head.onnx, manifest.json.

    build_bundle("runs/lean/best.pt", data="/work/data/sim96", out="edge/models/lean-96", name="lean-96")

exports fp32 graphs (parity checked against torch), quantizes them (encoder static QDQ per
channel; head dynamic uint8 if it measures best, else float), gates int8 against fp32 on the
validation tracks, and writes the bundle with the int8 graphs (``precision="int8"``) or the fp32
ones (``precision="fp32"``). The manifest records everything the runtime and a reader need.
"""

from __future__ import annotations

import datetime as _dt
import json
import shutil
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from cavatar_common.provenance import git_revision, sha256_file
from edge.infer.bundle import SCHEMA, seal_manifest, write_manifest
from edge.infer.normalise import NORMALISATION
from export.model import OUTPUT_SIZES, OUTPUTS, ModelConfig

WEIGHTS = "weights.npz"
OUTPUT_MEANING = {
    "rot6d": "24 joints × 6D rotation (first column of R, then second); published as axis-angle pose_aa (72)",
    "betas": "10 shape coefficients of the body model",
    "transl_rel_m": "pelvis joint minus (CoP_x, CoP_y, 0) of the window's last frame, carpet frame, metres",
    "activity_logits": "activity classes, in the order of 'activities'",
    "confidence": "sigmoid; trained to predict exp(-pelvis-aligned MPJPE / 10 cm)",
}


def write_bundle(out_dir: str | Path, encoder: str | Path, head: str | Path, cfg: ModelConfig, *, name: str,
                 pitch_m: float, rate_hz: float = 14.0, body_model: str = "lite", training: dict[str, Any] | None = None,
                 metrics: dict[str, Any] | None = None, quantization: dict[str, Any] | None = None,
                 weights: dict[str, np.ndarray] | None = None, overwrite: bool = True) -> Path:
    """Copy the two graphs into ``out_dir`` and write manifest.json (last, with every file's hash).

    ``weights``: the torch model's float32 state dict, saved as ``weights.npz`` for ``cavatar finetune``
    (the export stage); the runtime verifies its hash like every file but never reads it."""
    from edge.body.model import SHIPPED_MODELS, shipped_model_path

    out = Path(out_dir)
    if out.exists() and any(out.iterdir()) and not overwrite:
        raise FileExistsError(f"{out} is not empty")
    out.mkdir(parents=True, exist_ok=True)
    (out / "manifest.json").unlink(missing_ok=True)
    shutil.copyfile(encoder, out / "encoder.onnx")
    shutil.copyfile(head, out / "head.onnx")
    names = ["encoder.onnx", "head.onnx"]
    if weights is not None:
        np.savez_compressed(out / "weights.npz", **{k: np.asarray(v, np.float32) for k, v in weights.items()})
        names.append(WEIGHTS)
    else:
        (out / WEIGHTS).unlink(missing_ok=True)
    body_path = shipped_model_path(body_model) if body_model in SHIPPED_MODELS else Path(body_model)
    h, w = cfg.grid
    manifest = {
        "schema": SCHEMA, "name": name, "created": _dt.datetime.now(_dt.timezone.utc).isoformat(timespec="seconds"),
        "git_revision": git_revision(),
        "grid": [h, w], "pitch_m": pitch_m, "rate_hz": rate_hz, "window": cfg.window, "features": cfg.features,
        "input": {"name": "pressure", "shape": ["batch", 1, h, w], "dtype": "float32",
                  "content": "ONE person's calibrated pressure in kPa (other people's sensels zeroed), normalised",
                  "normalisation": NORMALISATION},
        "encoder": {"file": "encoder.onnx", "input": "pressure", "output": "features", "shape": ["batch", cfg.features]},
        "head": {"file": "head.onnx", "input": "features", "shape": ["batch", cfg.window, cfg.features],
                 "window": "causal: the target frame is the LAST of the window; a new track's history is its first frame repeated"},
        "outputs": {k: {"shape": ["batch", OUTPUT_SIZES[k]] if k != "confidence" else ["batch"], "meaning": OUTPUT_MEANING[k]}
                    for k in OUTPUTS},
        "translation": "transl_m = transl_rel_m + (CoP_x, CoP_y, 0); CoP of the model input's last frame in carpet metres "
                       "(edge.infer.normalise.center_of_pressure_m)",
        "activities": _activities(),
        "body_model": {"name": body_model, "file": body_path.name, "sha256": sha256_file(body_path)},
        "model_config": cfg.to_dict(),
        "training": training or {},
        "quantization": quantization or {"precision": "fp32"},
        "metrics": metrics or {},
        **({"weights": {"file": WEIGHTS, "meaning": "float32 state dict of the torch model, for `cavatar finetune` "
                        "(export stage only; the runtime never reads it)"}} if weights is not None else {}),
        "files": {f: sha256_file(out / f) for f in names},
    }
    write_manifest(out, manifest, default=_json_default)  # with its manifest.json.sha256, checked at load
    return out


def _activities() -> list[str]:
    from sim.motion import ACTIVITIES

    return list(ACTIVITIES)


def _json_default(o: Any) -> Any:
    if isinstance(o, (np.floating, np.integer)):
        return o.item()
    if isinstance(o, Path):
        return str(o)
    raise TypeError(type(o))


def build_bundle(checkpoint: str | Path, data: str | Path, out: str | Path, name: str, precision: str = "int8",
                 calib_frames: int = 256, frame_stride: int = 2, seed: int = 0, max_eval_tracks: int | None = None) -> dict:
    """Checkpoint → fp32 ONNX (+ parity) → int8 (+ gate on the val split) → bundle, then the bundle as the
    board loads it on the test split beside the mean-pose baseline. Returns the report written in the manifest."""
    import torch

    from edge.body import BodyModel
    from export.data import load_tracks
    from export.train import load_model
    from sim.dataset import Dataset

    ck = torch.load(checkpoint, map_location="cpu", weights_only=False)
    net = load_model(checkpoint)
    ds = Dataset(data)
    pitch = float(ds.manifest["pitch_m"])
    tc = ck.get("train_config", {})
    board = tc.get("input", "clean") == "board"  # calibrate, gate and score on what the run trained on
    val = load_tracks(ds, "val", board=board) or load_tracks(ds, "test", board=board)
    if max_eval_tracks:
        val = val[:max_eval_tracks]
    training = {"data": tc.get("data", str(data)), "dataset_schema": ds.manifest.get("schema"),
                "dataset_settings": ds.manifest.get("settings"), "dataset_git_revision": ds.manifest.get("git_revision"),
                "frames": len(ds),
                "subjects": {s: [x["subject_id"] for x in ds.subjects if x["split"] == s] for s in ("train", "val", "test")},
                "steps": int(ck["step"]),
                **{k: tc.get(k) for k in ("input", "stage", "init", "batch", "chunks", "lr", "weight_decay", "optimizer", "seed")}}
    split = "val" if load_tracks(ds, "val", max_tracks=1) else "test"
    report = bundle_from_net(net, out, name, pitch_m=pitch, rate_hz=float(ds.manifest.get("rate_hz", 14.0)),
                             calib_tracks=load_tracks(ds, "train", max_tracks=8, board=board), gate_tracks=val,
                             gate_split=split,
                             training=training, precision=precision, calib_frames=calib_frames, frame_stride=frame_stride, seed=seed)
    test = load_tracks(ds, "test", board=board)
    if test:  # the shipped bundle itself (as the board loads it) on subjects never seen in training
        body = BodyModel.load(net.cfg.body_model)
        metrics = report["metrics"]
        metrics["test"] = bundle_metrics(out, test, pitch, body, frame_stride=frame_stride)
        train = load_tracks(ds, "train", board=board)
        metrics["test"]["baseline_mean_pose_mpjpe_cm"] = mean_pose_baseline_cm(train, test)
        update_manifest(out, metrics=metrics, baseline=baseline_pose(train))
        report["test"] = metrics["test"]
    return report


def bundle_from_net(net, out: str | Path, name: str, *, pitch_m: float, rate_hz: float, calib_tracks, gate_tracks,
                    gate_split: str, training: dict[str, Any], precision: str = "int8", calib_frames: int = 256,
                    frame_stride: int = 2, seed: int = 0) -> dict:
    """A torch CAvatarNet → fp32 ONNX (parity) → int8 (gate on ``gate_tracks``) → bundle with its weights."""
    from edge.body import BodyModel
    from export.data import TRAINING_INPUT, TRAINING_INPUT_BOARD
    from export.evaluate import track_inputs
    from export.onnx_export import export_onnx, parity
    from export.quantize import quantize_and_gate

    if precision not in ("int8", "fp32"):
        raise ValueError("precision must be 'int8' or 'fp32'")
    cfg = net.cfg
    net.eval()
    rng = np.random.default_rng(seed)
    frames = np.concatenate([track_inputs(t, pitch_m, seed + i)[0] for i, t in enumerate(calib_tracks)])
    calib = frames[rng.choice(len(frames), min(calib_frames, len(frames)), replace=False)]
    with tempfile.TemporaryDirectory() as tmp:
        fp32 = export_onnx(net, tmp)
        par = parity(net, fp32["encoder"], fp32["head"], inputs=calib[:4])
        report = quantize_and_gate(fp32, Path(tmp) / "int8", calib, gate_tracks, cfg.window, pitch_m, BodyModel.load(cfg.body_model),
                                   frame_stride=frame_stride)
        report["parity_max_abs"] = par
        report["precision"] = precision
        if precision == "int8" and not report["gate_passed"]:
            raise RuntimeError(f"int8 gate failed: MPJPE +{report['gate_delta_cm']:.3f} cm > {report['gate_cm']} cm")
        enc, head = (report["encoder"], report["head"]) if precision == "int8" else (fp32["encoder"], fp32["head"])
        metrics = {"split": gate_split, "frames": report["frames"],
                   "mpjpe_cm": report["mpjpe_int8_fake_quant_cm"] if precision == "int8" else report["mpjpe_fp32_cm"],
                   "mpjpe_fp32_cm": report["mpjpe_fp32_cm"], "mpjpe_int8_x86_kernels_cm": report["mpjpe_int8_x86_kernels_cm"],
                   "latency_1_thread_ms": report["latency_1_thread"]}
        quant = {k: v for k, v in report.items() if k not in ("encoder", "head")}
        weights = {k: v.detach().cpu().numpy() for k, v in net.state_dict().items()}
        described = TRAINING_INPUT_BOARD if training.get("input") == "board" else TRAINING_INPUT
        write_bundle(out, enc, head, cfg, name=name, pitch_m=pitch_m, rate_hz=rate_hz, body_model=cfg.body_model,
                     training={**training, "input": described}, metrics=metrics, quantization=quant, weights=weights)
    report["metrics"] = metrics
    return report


def baseline_pose(train_tracks) -> dict[str, Any]:
    """The mean-pose baseline of `cavatar eval`, from the training tracks, for the manifest."""
    from export.tables import mean_pose

    pose, betas, height = mean_pose(train_tracks)
    return {"meaning": "mean training pose (per-joint rotation mean) and betas, pelvis over the centre of pressure at the "
                       "mean training pelvis height: the baseline of `cavatar eval`",
            "pose_aa": pose.tolist(), "betas": betas.tolist(), "pelvis_height_m": height}


def update_manifest(folder: str | Path, **fields: Any) -> None:
    """Replace top-level manifest fields (metrics, evaluation) atomically; file hashes are unaffected."""
    mpath = Path(folder) / "manifest.json"
    manifest = json.loads(mpath.read_text())
    manifest.update(fields)
    write_manifest(folder, manifest, default=_json_default)


def load_net(folder: str | Path):
    """The torch CAvatarNet of a bundle (its weights.npz and model_config), for fine-tuning."""
    import torch

    from edge.infer.bundle import verify
    from export.model import CAvatarNet, ModelConfig

    manifest = verify(folder)
    if WEIGHTS not in manifest["files"]:
        raise ValueError(f"{folder}: the bundle carries no {WEIGHTS} (bundles written before fine-tuning existed); "
                         "rebuild it with `cavatar bundle` from its checkpoint")
    net = CAvatarNet(ModelConfig.from_dict(manifest["model_config"]))
    with np.load(Path(folder) / WEIGHTS) as z:
        net.load_state_dict({k: torch.from_numpy(z[k]) for k in z.files})
    return net.eval(), manifest


def bundle_metrics(folder: str | Path, tracks, pitch_m: float, body, frame_stride: int = 2) -> dict:
    """MPJPE / translation / activity of a bundle loaded as the board loads it (x86 kernels here)."""
    from export.evaluate import bundle_callables, track_metrics

    encode, head, window = bundle_callables(folder)
    m = track_metrics(tracks, encode, head, window, pitch_m, body, frame_stride=frame_stride)
    m["subjects"] = sorted({int(t.subject) for t in tracks})
    return m


def mean_pose_baseline_cm(train_tracks, test_tracks) -> float:
    """The mean training pose (pelvis-centred joints) at every test frame: pelvis-aligned MPJPE, cm."""
    mean = np.mean(np.concatenate([t.joints_m - t.joints_m[:, :1] for t in train_tracks]), 0)
    err = np.concatenate([np.linalg.norm((t.joints_m - t.joints_m[:, :1]) - mean, axis=-1).mean(-1) for t in test_tracks])
    return float(err.mean() * 100)


def main(argv: list[str] | None = None) -> int:
    """``python -m export.bundle --seal DIR``: rewrite DIR's manifest.json.sha256 for its manifest as it is now
    (after a deliberate edit; the runtime refuses a manifest whose sidecar does not match)."""
    import argparse

    parser = argparse.ArgumentParser(prog="python -m export.bundle", description=main.__doc__)
    parser.add_argument("--seal", metavar="DIR", required=True, help="bundle folder whose manifest to seal")
    args = parser.parse_args(argv)
    from edge.infer.bundle import BundleError, verify

    digest = seal_manifest(args.seal)
    try:
        verify(args.seal)
    except BundleError as exc:
        print(f"sealed {args.seal}/manifest.json ({digest[:12]}), but the bundle is still refused: {exc}")
        return 2
    print(f"sealed {args.seal}/manifest.json: SHA-256 {digest}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

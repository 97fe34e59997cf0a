"""`cavatar train` and `cavatar bundle`: the export stage's commands (torch imported lazily,
so `cavatar --help` works on a board without torch)."""

from __future__ import annotations

import argparse
import json

from edge.cli import CliError


def register(sub: argparse._SubParsersAction) -> None:
    t = sub.add_parser("train", help="train the CAvatar model on a simulated dataset (needs the export extra)",
                       description="Train the CAvatar model: chunks of consecutive frames are encoded once and unfolded "
                       "into 40-frame windows. Checkpoints every N steps and on Ctrl-C; --resume continues a run.")
    t.add_argument("--data", required=True, help="dataset folder (cavatar sim generate)")
    t.add_argument("--out", required=True, help="run folder: config.json, checkpoint.pt, best.pt, log.jsonl")
    t.add_argument("--preset", default="lean", choices=("lean", "paper"), help="architecture (default lean)")
    t.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a model config field, e.g. --set head=gru --set discriminator=false (ablations)")
    t.add_argument("--steps", type=int, default=5000, help="total steps (default 5000)")
    t.add_argument("--batch", type=int, default=32, help="windows per chunk (default 32)")
    t.add_argument("--chunks", type=int, default=1, help="chunks per step (default 1)")
    t.add_argument("--lr", type=float, default=1e-4, help="Adam learning rate (default 1e-4)")
    t.add_argument("--weight-decay", type=float, default=1e-3, help="Adam weight decay (default 1e-3)")
    t.add_argument("--optimizer", default="adam", choices=("adam", "adamw"),
                   help="adam (the paper's, weight decay as L2 in the gradient) or adamw (decoupled decay)")
    t.add_argument("--seed", type=int, default=0)
    t.add_argument("--checkpoint-every", type=int, default=200)
    t.add_argument("--val-every", type=int, default=500)
    t.add_argument("--device", default="auto", help="auto (CUDA when present), cpu, cuda")
    t.add_argument("--threads", type=int, default=0, help="torch threads (default: torch's choice)")
    t.add_argument("--resume", action="store_true", help="continue from OUT/checkpoint.pt")
    t.set_defaults(func=run_train)

    b = sub.add_parser("bundle", help="export a checkpoint to a quantized ONNX model bundle (needs the export extra)",
                       description="Export encoder/head ONNX (parity-checked), quantize (encoder static QDQ per channel, "
                       "head whatever measures best), gate int8 MPJPE against fp32 (≤ +0.3 cm) and write the bundle.")
    b.add_argument("checkpoint", help="checkpoint.pt or best.pt of a run")
    b.add_argument("--data", required=True, help="dataset the metrics and calibration frames come from")
    b.add_argument("--out", required=True, help="bundle folder to write")
    b.add_argument("--name", required=True, help="bundle name, e.g. lean-96")
    b.add_argument("--precision", default="int8", choices=("int8", "fp32"))
    b.set_defaults(func=run_bundle)


def _parse_sets(items: list[str]) -> dict:
    out = {}
    for item in items:
        key, sep, value = item.partition("=")
        if not sep:
            raise CliError(f"--set takes KEY=VALUE, got {item!r}")
        try:
            out[key] = json.loads(value)
        except ValueError:
            out[key] = {"true": True, "false": False}.get(value.lower(), value)
    return out


def run_train(args: argparse.Namespace) -> int:
    try:
        from export.model import ModelConfig
        from export.train import TrainConfig, train
    except ImportError as exc:
        raise CliError(f"training needs the export extra (pip install '.[export]'): {exc}") from None
    try:
        model_cfg = ModelConfig.preset(args.preset, **_parse_sets(args.set))
    except (TypeError, ValueError) as exc:
        raise CliError(str(exc)) from None
    cfg = TrainConfig(data=args.data, out=args.out, steps=args.steps, batch=args.batch, chunks=args.chunks, lr=args.lr,
                      weight_decay=args.weight_decay, optimizer=args.optimizer, seed=args.seed, checkpoint_every=args.checkpoint_every,
                      val_every=args.val_every, device=args.device, threads=args.threads)
    from sim.dataset import DatasetError

    try:
        trainer = train(cfg, model_cfg, resume=args.resume)
    except (DatasetError, ValueError) as exc:
        raise CliError(str(exc)) from None
    print(f"step {trainer.step}; best validation MPJPE {trainer.best_val} cm; run in {args.out}")
    return 0


def run_bundle(args: argparse.Namespace) -> int:
    try:
        from export.bundle import build_bundle
    except ImportError as exc:
        raise CliError(f"bundling needs the export extra (pip install '.[export]'): {exc}") from None
    try:
        report = build_bundle(args.checkpoint, args.data, args.out, args.name, precision=args.precision)
    except (RuntimeError, ValueError, FileNotFoundError) as exc:
        raise CliError(str(exc)) from None
    print(json.dumps({k: report[k] for k in ("mpjpe_fp32_cm", "mpjpe_int8_fake_quant_cm", "gate_passed", "head_quantization")}))
    print(f"wrote {args.out}")
    return 0

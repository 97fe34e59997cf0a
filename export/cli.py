"""`cavatar train` and `cavatar bundle`: the export stage's commands (torch imported lazily,
so `cavatar --help` works on a board without torch)."""

from __future__ import annotations

import argparse
import contextlib
import json

from cavatar_common.errors import CliError


def register(sub: argparse._SubParsersAction) -> None:
    """The export commands: train, bundle, eval, finetune, bench."""
    for add in (_add_train, _add_bundle, _add_eval, _add_finetune, _add_bench):
        add(sub)


def _add_train(sub: argparse._SubParsersAction) -> None:
    t = sub.add_parser("train", help="train the CAvatar model on a simulated dataset (needs the export extra)",
                       description="Train the CAvatar model in stages (export/stages.py): --stage frames (encoder, frames "
                       "drawn independently), --stage head (encoder frozen, cached features, windows drawn independently), "
                       "--stage windows (end to end: chunks of consecutive frames encoded once, unfolded into 40-frame "
                       "windows). --init starts a stage from another run's weights. Checkpoints every N steps and on "
                       "Ctrl-C; --resume continues a run. `make model` runs the shipped recipe.")
    t.add_argument("--data", required=True, action="append",
                   help="dataset folder (cavatar sim generate); repeat to train on several of one grid")
    t.add_argument("--stage", default="windows", choices=("frames", "head", "windows"), help="training stage (default windows)")
    t.add_argument("--init", default="", help="checkpoint whose model weights start this run (e.g. the previous stage's best.pt)")
    t.add_argument("--out", required=True, help="run folder: config.json, checkpoint.pt, best.pt, log.jsonl")
    t.add_argument("--preset", default="lean", choices=("lean", "paper"), help="architecture (default lean)")
    t.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                   help="override a model config field, e.g. --set head=gru --set discriminator=false (ablations)")
    t.add_argument("--steps", type=int, default=5000, help="total steps (default 5000)")
    t.add_argument("--batch", type=int, default=32, help="windows per chunk (windows); frames or windows per step (frames, head)")
    t.add_argument("--chunks", type=int, default=1, help="chunks per step (default 1)")
    t.add_argument("--lr", type=float, default=1e-4, help="Adam learning rate (default 1e-4)")
    t.add_argument("--lr-schedule", default="constant", choices=("constant", "cosine"),
                   help="constant, or cosine decay to lr/100 at --steps (default constant)")
    t.add_argument("--weight-decay", type=float, default=1e-3, help="Adam weight decay (default 1e-3)")
    t.add_argument("--optimizer", default="adam", choices=("adam", "adamw"),
                   help="adam (the paper's, weight decay as L2 in the gradient) or adamw (decoupled decay)")
    t.add_argument("--seed", type=int, default=0)
    t.add_argument("--checkpoint-every", type=int, default=200)
    t.add_argument("--val-every", type=int, default=500)
    t.add_argument("--device", default="auto", help="auto (CUDA when present), cpu, cuda")
    t.add_argument("--threads", type=int, default=0, help="torch threads (default: torch's choice)")
    t.add_argument("--resume", action="store_true", help="continue from OUT/checkpoint.pt")
    t.add_argument("--cache-copies", type=int, default=2,
                   help="--stage head: feature-cache copies of every frame, copy c turned by c quarter turns "
                        "(default 2; 4 sees every heading)")
    t.add_argument("--input", default="clean", choices=("clean", "board"),
                   help="clean (default): the simulator's true pressure through the training corruption; board: the raw "
                   "counts through each carpet's calibration, as a board reads them (datasets generated with "
                   "`cavatar sim generate --calibration installer`)")
    t.add_argument("--no-turns", action="store_true", help="do not turn the carpet by random quarter turns (frames, head stages)")
    t.add_argument("--exclude-activity", action="append", default=[], metavar="NAME",
                   help="never train on this activity (leave-one-activity-out); repeatable")
    t.set_defaults(func=run_train)


def _add_bundle(sub: argparse._SubParsersAction) -> None:
    b = sub.add_parser("bundle", help="export a checkpoint to a quantized ONNX model bundle (needs the export extra)",
                       description="Export encoder/head ONNX (parity-checked), quantize (encoder static QDQ per channel, "
                       "head whatever measures best), gate int8 MPJPE against fp32 (≤ +0.3 cm) and write the bundle.")
    b.add_argument("checkpoint", help="checkpoint.pt or best.pt of a run")
    b.add_argument("--data", required=True, help="dataset the metrics and calibration frames come from")
    b.add_argument("--out", required=True, help="bundle folder to write")
    b.add_argument("--name", required=True, help="bundle name, e.g. lean-96")
    b.add_argument("--precision", default="int8", choices=("int8", "fp32"))
    b.set_defaults(func=run_bundle)


def _add_eval(sub: argparse._SubParsersAction) -> None:
    e = sub.add_parser("eval", help="evaluate a model bundle on simulated subjects: paper-shaped tables (needs the export extra)",
                       description="Run a bundle as the board loads it (heading resolved from the feet, as the runtime "
                       "does) on a dataset and write the paper's tables: MPJPE (24 joints, pelvis-aligned), PA-MPJPE, "
                       "root-aligned MPJPE (local pose under the true global orientation), heading error (median, % of "
                       "frames beyond 45° and 90°), PVE (full mesh) and the translation error, overall and per activity, "
                       "subject, number of people and joint, beside the mean-pose baseline. Two protocols: unseen "
                       "(subjects never seen in training: the --split's tracks whole) and seen-time (the paper's: the "
                       "training subjects' tracks split in time 80/10/10, scored on the last 10 %).")
    e.add_argument("--bundle", required=True, help="model bundle folder")
    e.add_argument("--data", required=True, action="append", help="dataset folder; repeat to pool several")
    e.add_argument("--split", default="test", choices=("test", "val", "train", "all"),
                   help="split to evaluate (default test: subjects never seen in training; 'all' for a dataset of new "
                   "subjects); --protocol seen-time always uses the training split")
    e.add_argument("--protocol", default="unseen", choices=("unseen", "seen-time"),
                   help="unseen (default: the split's tracks whole) or seen-time (the paper's: training subjects, every "
                   "track's last 10 %% in time; the model still sees the frames before)")
    e.add_argument("--no-resolve-heading", action="store_true",
                   help="score the model's own global orientation (default: resolved from the feet, as the runtime does)")
    e.add_argument("--heading-params", default="", help="heading parameters JSON (default: the packaged edge/infer/heading.json)")
    e.add_argument("--input", default="clean", choices=("clean", "board"),
                   help="clean (default): each person's true pressure through the training corruption; board: the "
                   "dataset's raw counts through its carpets' calibrations (`cavatar sim generate --calibration "
                   "installer`), floored and clipped as the runtime does — what a board feeds the model")
    e.add_argument("--stride", type=int, default=2, help="evaluate every Nth frame (default 2)")
    e.add_argument("--people", default="", help="only tracks from scenes with this many people, e.g. 2 or 2..3")
    e.add_argument("--out", required=True, help="output prefix: writes PREFIX.json and PREFIX.md")
    e.add_argument("--title", default="", help="title of the Markdown table")
    e.set_defaults(func=run_eval)


def _add_finetune(sub: argparse._SubParsersAction) -> None:
    f = sub.add_parser("finetune", help="fine-tune a bundle on a new user's data (needs the export extra)",
                       description="Fine-tune a bundle on the first FRACTION of every track of a new user's recording "
                       "(lr 3e-5, the paper's recipe), hold out the rest in time, and write a new bundle (int8 gate and all).")
    f.add_argument("--bundle", required=True, help="bundle to start from (must carry weights.npz)")
    f.add_argument("--data", required=True, help="the user's dataset folder")
    f.add_argument("--fraction", type=float, required=True, help="fraction of every track to train on, e.g. 0.5")
    f.add_argument("--out", required=True, help="bundle folder to write")
    f.add_argument("--subject", action="append", default=[], help="only these subjects (e.g. s06); default all")
    f.add_argument("--split", default="all", choices=("test", "val", "train", "all"), help="dataset split (default all)")
    f.add_argument("--steps", type=int, default=300, help="optimiser steps (default 300)")
    f.add_argument("--lr", type=float, default=3e-5, help="learning rate (default 3e-5)")
    f.add_argument("--stage", default="windows", choices=("windows", "head"),
                   help="windows: whole model end to end (the paper); head: temporal head only, cached features (fast)")
    f.add_argument("--threads", type=int, default=1)
    f.add_argument("--precision", default="int8", choices=("int8", "fp32"),
                   help="int8 (default; must pass the int8 gate on the held-out frames) or fp32")
    f.set_defaults(func=run_finetune)


def _add_bench(sub: argparse._SubParsersAction) -> None:
    from bench.speed_error_run import add_arguments as bench_arguments  # numpy only at import: torch comes with the run

    k = sub.add_parser("bench", help="speed against error of every model variant, and the measured ratios (needs the export extra)",
                       description="Per-frame latency (median, p99), frames/s, peak memory and size of every model variant "
                       "(the shipped bundle, its fp32 twin, --bundle folders, the untrained paper architecture) at 1 and 2 "
                       "onnxruntime threads, beside MPJPE/PVE/translation on unseen subjects (--data; none: speed only); "
                       "ratios measured side by side (onnxruntime vs PyTorch, feature cache, joints vs mesh, scene-adaptive "
                       "vs always-infer, runtime vs the frame interval). Writes the JSON, a Markdown table and the "
                       "latency-vs-MPJPE plot with its Pareto front. See bench/README.md.")
    bench_arguments(k)
    k.set_defaults(func=run_bench)


@contextlib.contextmanager
def _export_extra(what: str):
    """Imports of the export stage inside: a missing torch/onnx becomes a CliError naming the extra."""
    try:
        yield
    except ImportError as exc:
        raise CliError(f"{what} needs the export extra (pip install '.[export]'): {exc}") from None


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
    with _export_extra("training"):
        from export.model import ModelConfig
        from export.train import TrainConfig, train
    try:
        model_cfg = ModelConfig.preset(args.preset, **_parse_sets(args.set))
    except (TypeError, ValueError) as exc:
        raise CliError(str(exc)) from None
    cfg = TrainConfig(data=args.data, out=args.out, stage=args.stage, init=args.init, exclude_activities=args.exclude_activity,
                      cache_copies=args.cache_copies, input=args.input, turns=not args.no_turns, steps=args.steps,
                      batch=args.batch, chunks=args.chunks, lr=args.lr, lr_schedule=args.lr_schedule,
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
    with _export_extra("bundling"):
        from export.bundle import build_bundle
    try:
        report = build_bundle(args.checkpoint, args.data, args.out, args.name, precision=args.precision)
    except (RuntimeError, ValueError, FileNotFoundError) as exc:
        raise CliError(str(exc)) from None
    print(json.dumps({k: report[k] for k in ("mpjpe_fp32_cm", "mpjpe_int8_fake_quant_cm", "gate_passed", "head_quantization")}))
    print(f"wrote {args.out}")
    return 0


SEEN_TIME_TEST_FROM = 0.9  # the paper's protocol: 80 % train, 10 % val, 10 % test, in time
PROTOCOLS = {
    "unseen": "subjects never seen in training, whole tracks (zero-shot)",
    "seen-time": "the paper's: subjects seen in training, every track split in time 80/10/10, scored on the last 10 % "
                 "(the shipped bundle trained on every frame of its training recordings: on a dataset regenerated with the same "
                 "seed and length these frames were seen, which is optimistic; other lengths give new motions of seen bodies)",
}


def _people_filter(text: str) -> tuple[int, int] | None:
    if not text:
        return None
    lo, _, hi = text.partition("..")
    try:
        return int(lo), int(hi or lo)
    except ValueError:
        raise CliError(f"--people takes N or LO..HI, got {text!r}") from None


def run_eval(args: argparse.Namespace) -> int:
    with _export_extra("evaluation"):
        import numpy as np
        import torch  # noqa: F401  (the tables' model outputs and body twin are the export stage's)

        from export.finetune import user_tracks
        from export.tables import evaluate_bundle, markdown
    from pathlib import Path

    from edge.infer import BundleError, verify
    from sim.dataset import DatasetError

    split = "train" if args.protocol == "seen-time" else args.split
    try:
        manifest = verify(args.bundle)
        heading_file = args.heading_params or None
        if heading_file and not args.no_resolve_heading:
            from edge.infer.heading import HeadingParams

            HeadingParams.load(heading_file)
        tracks, pitch = [], None
        for d in args.data:
            t, p, _ = user_tracks(d, split, board=args.input == "board")
            if pitch is not None and p != pitch:
                raise ValueError(f"{d}: pitch {p} m differs from the other datasets' {pitch} m")
            tracks, pitch = tracks + t, p
    except (BundleError, DatasetError, ValueError) as exc:
        raise CliError(str(exc)) from None
    people = _people_filter(args.people)
    if people:
        tracks = [t for t in tracks if people[0] <= t.people <= people[1]]
        if not tracks:
            raise CliError(f"no tracks from scenes of {args.people} people in {args.data}")
    base = manifest.get("baseline")
    baseline = (np.array(base["pose_aa"]), np.array(base["betas"]), float(base["pelvis_height_m"])) if base else None
    result = evaluate_bundle(args.bundle, tracks, pitch, frame_stride=args.stride, baseline=baseline,
                             resolve_heading=not args.no_resolve_heading, heading_params=heading_file,
                             score_from=SEEN_TIME_TEST_FROM if args.protocol == "seen-time" else 0.0)
    result["setup"] = {"bundle": f"{manifest['name']}@{manifest['files']['encoder.onnx'][:12]}", "data": args.data,
                       "split": split, "protocol": PROTOCOLS[args.protocol], "people": args.people or "all",
                       "input": args.input,
                       "heading": ("model alone" if args.no_resolve_heading
                                   else f"resolved from the feet ({heading_file or 'edge/infer/heading.json'})"),
                       "frame_stride": args.stride,
                       "tracks": len(tracks), "subjects": sorted({f"s{t.subject:02d}" for t in tracks}),
                       "baseline": "mean training pose at the centre of pressure" if baseline else "none (bundle has no baseline)",
                       "precision": manifest.get("quantization", {}).get("precision", "fp32")}
    out = Path(args.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    title = args.title or f"{manifest['name']} on {split}, protocol {args.protocol} ({', '.join(result['setup']['subjects'])})"
    out.with_suffix(".json").write_text(json.dumps(result, indent=1) + "\n")
    out.with_suffix(".md").write_text(markdown(result, title))
    o = result["overall"]
    print(f"MPJPE {o['mpjpe_cm']:.2f} cm, PA-MPJPE {o['pa_mpjpe_cm']:.2f} cm, root-aligned {o['local_mpjpe_cm']:.2f} cm, "
          f"heading median {o['heading_median_deg']:.1f}° (>90° in {o['heading_over90_pct']:.1f} % of frames), "
          f"PVE {o['pve_cm']:.2f} cm, translation {o['transl_cm']:.2f} cm over {o['frames']} frames"
          + (f"; baseline MPJPE {result['baseline']['mpjpe_cm']:.2f} cm" if baseline else ""))
    print(f"wrote {out.with_suffix('.json')} and {out.with_suffix('.md')}")
    return 0


def run_finetune(args: argparse.Namespace) -> int:
    with _export_extra("fine-tuning"):
        import torch  # noqa: F401  (export.finetune imports the model lazily)

        from export.finetune import finetune
    from edge.infer import BundleError
    from sim.dataset import DatasetError

    try:
        report = finetune(args.bundle, args.data, args.fraction, args.out, steps=args.steps, lr=args.lr, stage=args.stage,
                          split=args.split, subjects=args.subject or None, threads=args.threads,
                          precision=args.precision)
    except (BundleError, DatasetError, ValueError, RuntimeError) as exc:
        raise CliError(str(exc)) from None
    m = report["metrics"]
    print(f"held-out MPJPE {m['mpjpe_cm']:.2f} cm over {m['frames']} frames (fp32 {m['mpjpe_fp32_cm']:.2f}); wrote {args.out}")
    return 0


def run_bench(args: argparse.Namespace) -> int:
    with _export_extra("benchmarking"):
        import torch  # noqa: F401

        from bench import BenchmarkError
        from bench.speed_error_run import run_from_args, summary
    try:
        result = run_from_args(args, prog="cavatar bench")
    except BenchmarkError as exc:
        raise CliError(str(exc)) from None
    print(summary(result))
    print(f"wrote {args.json}, {args.markdown}, {args.plot}")
    return 0

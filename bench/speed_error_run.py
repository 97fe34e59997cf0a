"""The speed_error run (bench/speed_error.py is its command line, `cavatar bench` the same run): the variants
timed, their errors, the ratios, and the options both commands take."""

from __future__ import annotations

import argparse
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

from bench import BenchmarkError
from bench.accuracy import baseline_error, load_eval_tracks, variant_error
from bench.machine import describe
from bench.model_speed import (
    peak_memory,
    ratio_body,
    ratio_feature_cache,
    ratio_onnxruntime_vs_torch,
    time_variants,
)
from bench.simulated_day import ratio_scene_adaptive, runtime_vs_interval, simulated_day
from bench.speed_error_report import pareto, write_outputs
from bench.variants import (
    Variant,
    bundle_variants,
    manifest_of,
    person_frames,
    require_weights,
    untrained_variants,
)

SCHEMA = "cavatar.bench.speed_error/1"
DEFAULT_JSON = "bench/results/speed_error.json"
DEFAULT_MARKDOWN = "docs/bench/speed_error.md"
DEFAULT_PLOT = "docs/bench/pareto.png"
DEFAULT_RUNTIME_LATENCY = "bench/results/runtime_latency.json"


def _stderr(text: str) -> None:
    print(text, file=sys.stderr, flush=True)


@dataclass
class SpeedErrorConfig:
    bundles: list[str]                              # bundle folders; the first is the reference (ratios, the day)
    data: list[str] = field(default_factory=list)   # dataset folders for the errors (none: speed only)
    split: str = "test"
    stride: int = 4                                 # evaluate every Nth frame
    threads: tuple[int, ...] = (1, 2)               # onnxruntime intra-op threads
    latency_rounds: int = 12                        # timed frames per variant and thread count = rounds × per round
    frames_per_round: int = 20
    memory_frames: int = 200
    memory_baseline_runs: int = 3
    ratio_rounds: int = 15
    ratio_calls: int = 20
    day_s: float = 60.0
    day_rounds: int = 7
    untrained: dict[str, Any] | None = None         # name → ModelConfig; None: the paper preset on the reference grid
    runtime_latency: str | None = DEFAULT_RUNTIME_LATENCY
    seed: int = 0
    log: Callable[[str], None] = _stderr



def _machine() -> dict[str, Any]:
    """bench.machine's record, the load average to two decimals."""
    m = describe()
    return {**m, "load_average_1_5_15_min": [round(x, 2) for x in m["load_average_1_5_15_min"]]}


def _variants(cfg: SpeedErrorConfig, tmp: Path, log: Callable[[str], None]):
    """Every variant to time, the reference bundle's parts, and the model inputs per grid."""
    from export.model import ModelConfig

    variants: list[Variant] = []
    ref: dict[str, Any] = {}
    for i, b in enumerate(cfg.bundles):
        log(f"bundle {b}: loading, exporting its fp32 twin")
        vs, net, twin, manifest = bundle_variants(b, tmp / f"bundle-{i}", need_weights=bool(cfg.data), seed=cfg.seed)
        taken = {v.name for v in variants}
        for v in vs:
            if v.name in taken:
                v.name = f"{v.name} ({Path(b).name})"
        variants += vs
        if not ref:
            ref = {"bundle": vs[0], "net": net, "twin": twin, "manifest": manifest}
    grid, pitch = ref["bundle"].grid, ref["bundle"].pitch_m
    inputs, what_inputs = {}, {}
    log("model inputs: simulated frames")
    for g, p in sorted({(v.grid, v.pitch_m) for v in variants}):
        inputs[g], what_inputs[f"{g[0]}x{g[1]}"] = person_frames(g, p, seed=cfg.seed)
    untrained = cfg.untrained if cfg.untrained is not None else {"paper": ModelConfig.preset("paper", grid=grid)}
    for name, mcfg in untrained.items():
        log(f"{name}: random weights, exporting fp32 and int8")
        g = tuple(mcfg.grid)
        if g not in inputs:
            inputs[g], what_inputs[f"{g[0]}x{g[1]}"] = person_frames(g, pitch, seed=cfg.seed)
        variants += untrained_variants(name, mcfg, pitch, tmp, inputs[g], seed=cfg.seed)
    return variants, ref, inputs, what_inputs


def _rows(cfg: SpeedErrorConfig, variants: list[Variant], inputs: dict, groups: dict, log: Callable[[str], None]):
    """Per variant: what it is, its speed and peak memory per thread count, its error; and the memory record."""
    log(f"latency: {len(variants)} variants × threads {list(cfg.threads)}, "
        f"{cfg.latency_rounds * cfg.frames_per_round} frames each")
    speed = time_variants(variants, inputs, cfg.threads, cfg.latency_rounds, cfg.frames_per_round)
    log("peak memory: fresh subprocesses")
    memory = peak_memory(variants, cfg.threads, cfg.memory_frames, cfg.memory_baseline_runs)
    rows = []
    for v in variants:
        row = v.describe()
        row["speed"] = [{"threads": t, **speed[(v.name, t)], "peak_rss_mb": memory[(v.name, t)]} for t in cfg.threads]
        if v.trained and groups:
            log(f"errors: {v.name}")
        row["error"] = variant_error(v, groups, cfg.stride)
        rows.append(row)
    return rows, memory


def _ratios(cfg: SpeedErrorConfig, ref: dict[str, Any], inputs: dict, log: Callable[[str], None]) -> dict[str, Any]:
    """The ratios on the reference bundle: onnxruntime vs torch, feature cache, body, the simulated day."""
    grid, pitch = ref["bundle"].grid, ref["bundle"].pitch_m
    log("ratios: onnxruntime vs torch, feature cache, body")
    ref_inputs = inputs[grid]
    ratios = {"onnxruntime_vs_torch_eager": ratio_onnxruntime_vs_torch(ref["net"], ref["twin"], ref_inputs,
                                                                       cfg.ratio_rounds, cfg.ratio_calls),
              "feature_cache": ratio_feature_cache(ref["bundle"], ref_inputs, cfg.ratio_rounds, cfg.ratio_calls),
              "body_mesh_vs_joints": ratio_body(cfg.ratio_rounds, cfg.ratio_calls, cfg.seed)}
    log(f"the simulated day: {cfg.day_s:g} s, {cfg.day_rounds} rounds of adaptive and always-infer")
    day = simulated_day(grid, pitch, cfg.day_s, seed=cfg.seed)
    log("the day: generated; timing")
    ratios["scene_adaptive"], adaptive = ratio_scene_adaptive(ref["bundle"].bundle_dir, day, cfg.day_rounds)
    ratios["runtime_vs_frame_interval"] = runtime_vs_interval(adaptive, cfg.runtime_latency)
    return ratios


def _evaluation(cfg: SpeedErrorConfig, groups: dict, ref: dict[str, Any], log: Callable[[str], None]) -> dict[str, Any]:
    if not groups:
        return {"status": "not evaluated", "reason": "no --data given (speed only)"}
    log("the mean-pose baseline on the same frames")
    grid = ref["bundle"].grid
    return {"status": "evaluated", "split": cfg.split, "frame_stride": cfg.stride, "grids": {
        f"{g[0]}x{g[1]}": {"data": grp["data"], "pitch_m": grp["pitch_m"], "tracks": len(grp["tracks"]),
                           "subjects": grp["subjects"], "baseline_mean_pose": baseline_error(ref["manifest"], grp, cfg.stride)
                           if g == grid else None} for g, grp in groups.items()}}


def _method(cfg: SpeedErrorConfig, what_inputs: dict[str, str], memory: dict) -> dict[str, Any]:
    return {
        "latency": f"per published frame: encoder batch 1 (the new frame) + head batch 1 over the (1,T,F) window of "
                   f"cached features; onnxruntime CPU, intra-op threads as listed, inter-op 1, no spinning; "
                   f"{cfg.latency_rounds} rounds × {cfg.frames_per_round} frames per variant and thread count, "
                   "variants round-robin; each frame timed alone (perf_counter); frames/s = 1000 / mean ms",
        "inputs": what_inputs,
        "peak_memory": f"ru_maxrss of a fresh subprocess that loads the two graphs and runs {cfg.memory_frames} frames, "
                       f"minus the median of {cfg.memory_baseline_runs} subprocesses that only import onnxruntime and numpy "
                       f"({memory['baseline_kb'] / 1024:.1f} MiB); MiB",
        "size": "bytes of encoder.onnx + head.onnx",
        "error": "export.tables.evaluate_bundle: the variant loaded as the board loads it; MPJPE (24 joints) and PVE "
                 "(full mesh), pelvis-aligned, and translation, cm, on every frame_stride-th frame of the same tracks",
        "ratios": f"side by side: per round both sides ({cfg.ratio_calls} calls each; the day: one pass each), "
                  "alternating which goes first; the per-round ratio a/b; median and interquartile range over rounds",
    }


def run_speed_error(cfg: SpeedErrorConfig, command: str = "") -> dict[str, Any]:
    import onnxruntime as ort
    import torch

    from cavatar_common.provenance import git_revision

    if not cfg.bundles:
        raise BenchmarkError("no bundle given")
    t_start = time.perf_counter()
    start = _machine()

    def log(text: str) -> None:
        cfg.log(f"[{time.perf_counter() - t_start:6.1f} s] {text}")

    with tempfile.TemporaryDirectory(prefix="cavatar-bench-") as tmpdir:
        if cfg.data:
            for b in cfg.bundles:  # refuse before the slow parts
                require_weights(Path(b), manifest_of(Path(b)))
            log(f"loading the {cfg.split} tracks of {', '.join(cfg.data)}")
        groups = load_eval_tracks(cfg.data, cfg.split) if cfg.data else {}
        variants, ref, inputs, what_inputs = _variants(cfg, Path(tmpdir), log)
        rows, memory = _rows(cfg, variants, inputs, groups, log)
        ratios = _ratios(cfg, ref, inputs, log)
        evaluation = _evaluation(cfg, groups, ref, log)
    log("done")
    front = pareto(rows)
    end = _machine()
    return {
        "schema": SCHEMA, "benchmark": "speed_error", "command": command, "date": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "git_revision": git_revision(),
        "machine": {**start, "load_average_1_5_15_min_at_end": end["load_average_1_5_15_min"],
                    "onnxruntime": ort.__version__, "torch": torch.__version__},
        "method": _method(cfg, what_inputs, memory),
        "evaluation": evaluation,
        "variants": rows,
        "pareto_front": front,
        "ratios": ratios,
        "elapsed_s": round(time.perf_counter() - t_start, 1),
    }


# ---------------------------------------------------------------------------------------------- arguments
def add_arguments(p: argparse.ArgumentParser) -> None:
    """The options of `cavatar bench` and bench/speed_error.py."""
    p.add_argument("--shipped", default=None, help="the reference bundle (default: the shipped edge/models/lean-96)")
    p.add_argument("--bundle", action="append", default=[], help="another bundle folder to compare; repeatable")
    p.add_argument("--data", action="append", default=[],
                   help="dataset folder for the errors; repeatable (none: speed only, errors 'not evaluated')")
    p.add_argument("--split", default="test", choices=("test", "val", "train", "all"), help="split (default test: unseen subjects)")
    p.add_argument("--stride", type=int, default=4, help="evaluate every Nth frame (default 4)")
    p.add_argument("--threads", default="1,2", help="onnxruntime thread counts (default 1,2)")
    p.add_argument("--rounds", type=int, default=12, help="latency rounds of --frames-per-round frames (default 12 × 20)")
    p.add_argument("--frames-per-round", type=int, default=20)
    p.add_argument("--day-s", type=float, default=60.0, help="length of the simulated day in seconds (default 60)")
    p.add_argument("--day-rounds", type=int, default=7, help="rounds of the day, each mode once per round (default 7)")
    p.add_argument("--no-paper", action="store_true", help="leave out the untrained paper architecture")
    p.add_argument("--json", default=DEFAULT_JSON, help=f"results (default {DEFAULT_JSON})")
    p.add_argument("--markdown", default=DEFAULT_MARKDOWN, help=f"table (default {DEFAULT_MARKDOWN})")
    p.add_argument("--plot", default=DEFAULT_PLOT, help=f"latency vs MPJPE (default {DEFAULT_PLOT})")
    p.add_argument("--runtime-latency", default=DEFAULT_RUNTIME_LATENCY,
                   help="runtime per-stage results to compare with the frame interval, when present")


def command_line(args: argparse.Namespace, prog: str) -> str:
    """``prog`` and the options that differ from their defaults: the command that repeats this run."""
    ap = argparse.ArgumentParser()
    add_arguments(ap)
    defaults = vars(ap.parse_args([]))
    parts = [prog]
    for key, default in defaults.items():
        value = getattr(args, key, default)
        if value == default:
            continue
        flag = "--" + key.replace("_", "-")
        if isinstance(value, bool):
            parts.append(flag)
        elif isinstance(value, list):
            parts += [x for v in value for x in (flag, str(v))]
        else:
            parts += [flag, str(value)]
    return " ".join(parts)


def config_from_args(args: argparse.Namespace) -> SpeedErrorConfig:
    from edge.runtime.config import default_bundle_path

    try:
        threads = tuple(int(t) for t in str(args.threads).split(",") if t.strip())
    except ValueError:
        raise BenchmarkError(f"--threads takes N[,N…], got {args.threads!r}") from None
    if not threads or min(threads) < 1 or args.stride < 1 or args.rounds < 1 or args.frames_per_round < 1 or args.day_rounds < 1:
        raise BenchmarkError("--threads, --stride, --rounds, --frames-per-round and --day-rounds must be ≥ 1")
    return SpeedErrorConfig(bundles=[args.shipped or str(default_bundle_path()), *args.bundle], data=list(args.data),
                            split=args.split, stride=args.stride, threads=threads, latency_rounds=args.rounds,
                            frames_per_round=args.frames_per_round, day_s=args.day_s, day_rounds=args.day_rounds,
                            untrained={} if args.no_paper else None, runtime_latency=args.runtime_latency)


def run_from_args(args: argparse.Namespace, prog: str) -> dict[str, Any]:
    """Run and write the JSON, the Markdown table and the plot; returns the result."""
    result = run_speed_error(config_from_args(args), command=command_line(args, prog))
    write_outputs(result, args.json, args.markdown, args.plot)
    return result


def summary(result: dict[str, Any]) -> str:
    lines = []
    for r in result["variants"]:
        e = r["error"]
        err = f"MPJPE {e['mpjpe_cm']:.2f} cm" if e["status"] == "evaluated" else e["status"]
        lines.append(f"{r['name']:28s} " + "  ".join(f"{s['threads']} thr {s['median_ms']:7.3f} ms (p99 {s['p99_ms']:.3f})"
                                                      for s in r["speed"]) + f"  {err}")
    for k, v in result["ratios"].items():
        if "ratio" in v:
            lines.append(f"{k}: {v['ratio']['median']:.2f}× (IQR {v['ratio']['p25']:.2f}–{v['ratio']['p75']:.2f})")
        elif k == "scene_adaptive":
            for part in ("model_time", "frame_time"):
                r = v[part]["ratio"]
                lines.append(f"{k} {part}: {r['median']:.2f}× (IQR {r['p25']:.2f}–{r['p75']:.2f})")
        else:
            lines.append(f"{k}: {100 * v['fraction_median']:.1f} % of the {v['interval_ms']:.1f} ms interval (median)")
    lines.append(f"{result['elapsed_s']} s")
    return "\n".join(lines)

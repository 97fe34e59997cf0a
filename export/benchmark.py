"""Speed against error (issue 8): every model variant's cost per frame beside its error, and the measured
ratios behind the runtime's design. `cavatar bench` and bench/speed_error.py are thin wrappers.

    result = run_speed_error(SpeedErrorConfig(bundles=["edge/models/lean-96"], data=["/work/data/many48"]))
    write_outputs(result, "bench/results/speed_error.json", "docs/bench/speed_error.md", "docs/bench/pareto.png")

Variants: each bundle as it ships (the first is the reference) and its fp32 twin, exported from the bundle's
weights.npz; an untrained architecture (the paper's ResNet18 + 6-layer transformer, random weights) in fp32
and int8, for speed only ("not trained": never on the error axis). Per variant and onnxruntime thread count:

- latency of one published frame as the board does it: encoder (batch 1, the new frame) + head (batch 1,
  the (1,T,F) window of cached features); median and p99 over the timed frames, frames/s = 1000 / mean.
  Variants and thread counts are timed round-robin, a few frames each per round, so load hits all alike;
- peak memory: ru_maxrss of a fresh subprocess that loads the two graphs and runs N frames, minus that of a
  subprocess that only imports onnxruntime and numpy (MiB);
- size: bytes of the two ONNX files;
- error (trained variants): MPJPE, PVE, translation (cm) from export.tables.evaluate_bundle, the variant
  loaded as the board loads it, on the SAME unseen-subject tracks (one set per grid).

Ratios, each measured side by side: per round both sides run (alternating which goes first) and the
round's ratio is taken; reported as the median and interquartile range over rounds.
- PyTorch eager / onnxruntime, same fp32 weights, one thread, encoder + head per frame;
- re-encoding all T frames (encoder batch T + head) / the feature cache (encoder batch 1 + head);
- full mesh / joints only (BodyModel "full", batch 1);
- always-infer / scene-adaptive on a simulated day through the real FrameStages (model time and total
  per-frame time), with the inferences each did;
- the runtime's per-frame cost / the frame interval (bench/results/runtime_latency.json when present,
  else the adaptive day's FrameStages time: calibrate → record, decoding and publishing not included).
"""

from __future__ import annotations

import argparse
import itertools
import json
import os
import platform
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

SCHEMA = "cavatar.bench.speed_error/1"
RATE_HZ = 14.0
DEFAULT_JSON = "bench/results/speed_error.json"
DEFAULT_MARKDOWN = "docs/bench/speed_error.md"
DEFAULT_PLOT = "docs/bench/pareto.png"
DEFAULT_RUNTIME_LATENCY = "bench/results/runtime_latency.json"

# The simulated day, in order: (kind, fraction of the day, people). "still" holds one simulated pose (sensor
# noise stays live): the simulator's own standing sways, and the scene calls only ~30 % of those frames still.
DAY = (("empty", 0.20, 0), ("active", 0.04, 1), ("still", 0.12, 1), ("active", 0.03, 1), ("empty", 0.20, 0),
       ("active", 0.05, 2), ("still", 0.13, 1), ("active", 0.03, 1), ("empty", 0.20, 0))
ACTIVE_1 = ("walking", "stepping", "squat", "lunge", "turning", "raising_arms")
ACTIVE_2 = ("walking", "stepping")
STILL = ("standing", "sitting")


class BenchmarkError(Exception):
    """A benchmark that cannot run as asked (a bundle without weights.npz when errors are wanted, bad data)."""


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


# ---------------------------------------------------------------------------------------------- statistics
def spread(values) -> dict[str, float]:
    """Median and interquartile range of per-round values."""
    a = np.asarray(values, float)
    p25, p50, p75 = np.percentile(a, [25, 50, 75])
    return {"median": float(p50), "p25": float(p25), "p75": float(p75), "iqr": float(p75 - p25), "rounds": int(a.size)}


def latency_stats(ms) -> dict[str, float]:
    a = np.asarray(ms, float)
    return {"median_ms": float(np.median(a)), "p99_ms": float(np.percentile(a, 99)), "mean_ms": float(a.mean()),
            "frames_per_s": float(1e3 / a.mean()), "frames": int(a.size)}


def side_by_side(a: Callable[[], Any], b: Callable[[], Any], rounds: int, calls: int, warmup: int = 3) -> dict[str, Any]:
    """Time ``calls`` calls of a and of b per round, alternating which goes first; the per-round ratio a/b."""
    for _ in range(warmup):
        a()
        b()
    ms: dict[int, list[float]] = {0: [], 1: []}
    for r in range(rounds):
        for side in ((0, 1) if r % 2 == 0 else (1, 0)):
            fn = (a, b)[side]
            t0 = time.perf_counter()
            for _ in range(calls):
                fn()
            ms[side].append((time.perf_counter() - t0) / calls * 1e3)
    return {"a_ms": float(np.median(ms[0])), "b_ms": float(np.median(ms[1])),
            "ratio": spread(np.divide(ms[0], ms[1])), "calls_per_round": calls}


def pareto_front(points: list[tuple[float, float]]) -> list[int]:
    """Indices of the points no other point beats in both coordinates (lower is better), by increasing x."""
    front = []
    for i, (x, y) in enumerate(points):
        dominated = any(xj <= x and yj <= y and (xj < x or yj < y) for j, (xj, yj) in enumerate(points) if j != i)
        if not dominated:
            front.append(i)
    return sorted(front, key=lambda i: (points[i][0], points[i][1]))


# ---------------------------------------------------------------------------------------------- inputs
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


# ---------------------------------------------------------------------------------------------- variants
def _manifest(folder: Path) -> dict[str, Any]:
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
    manifest = _manifest(folder)
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


# ---------------------------------------------------------------------------------------------- speed
def _frame_fn(enc, head, inputs: np.ndarray, window: int, features: int) -> Callable[[], None]:
    """One published frame: encoder on the next input, push into the window, head on the window."""
    from edge.infer import FeatureWindow

    win = FeatureWindow(window, features)
    ein, hin = enc.get_inputs()[0].name, head.get_inputs()[0].name
    order = itertools.cycle(range(len(inputs)))

    def frame() -> None:
        f = enc.run(None, {ein: inputs[next(order)][None]})[0]
        win.push(f[0])
        head.run(None, {hin: win.window()})

    return frame


def time_variants(variants: list[Variant], inputs: dict, threads: tuple[int, ...], rounds: int, per_round: int,
                  warmup: int = 10) -> dict[tuple[str, int], dict[str, float]]:
    """(variant name, threads) → latency statistics, all combinations timed round-robin."""
    from export.quantize import session

    combos = []
    for v in variants:
        for t in threads:
            fn = _frame_fn(session(v.encoder, t), session(v.head, t), inputs[v.grid], v.window, v.features)
            for _ in range(warmup):
                fn()
            combos.append(((v.name, t), fn))
    ms: dict[tuple[str, int], list[float]] = {k: [] for k, _ in combos}
    for r in range(rounds):
        k = r % len(combos)
        for key, fn in combos[k:] + combos[:k]:
            for _ in range(per_round):
                t0 = time.perf_counter()
                fn()
                ms[key].append((time.perf_counter() - t0) * 1e3)
    return {k: latency_stats(v) for k, v in ms.items()}


_MEMORY_CHILD = r"""
import json, resource, sys
import numpy as np
import onnxruntime as ort
spec = json.loads(sys.argv[1])
if spec["encoder"]:
    opts = ort.SessionOptions()
    opts.intra_op_num_threads, opts.inter_op_num_threads, opts.log_severity_level = spec["threads"], 1, 3
    opts.add_session_config_entry("session.intra_op.allow_spinning", "0")
    enc = ort.InferenceSession(spec["encoder"], opts, providers=["CPUExecutionProvider"])
    head = ort.InferenceSession(spec["head"], opts, providers=["CPUExecutionProvider"])
    rng = np.random.default_rng(0)
    h, w = spec["grid"]
    x = np.log1p(rng.gamma(0.5, 4.0, (8, 1, 1, h, w)) * (rng.random((8, 1, 1, h, w)) < 0.1)).astype(np.float32)
    win = np.zeros((1, spec["window"], spec["features"]), np.float32)
    ein, hin = enc.get_inputs()[0].name, head.get_inputs()[0].name
    for k in range(spec["frames"]):
        f = enc.run(None, {ein: x[k % 8]})[0]
        win[0, :-1] = win[0, 1:]
        win[0, -1] = f[0]
        head.run(None, {hin: win})
print(json.dumps({"maxrss_kb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss}))
"""


def _child_rss_kb(spec: dict[str, Any]) -> int:
    """ru_maxrss (KiB) of a fresh Python running _MEMORY_CHILD. Linux keeps a process's peak RSS across exec and a
    forked child starts with its parent's peak, so a child of this (large) process would report ours: the child is
    started by a shell that forks it (``; exit``: no exec shortcut), whose own peak is a few MiB."""
    env = {**os.environ, "OMP_NUM_THREADS": "1", "OPENBLAS_NUM_THREADS": "1"}
    out = subprocess.run(["/bin/sh", "-c", '"$0" "$@"; exit $?', sys.executable, "-c", _MEMORY_CHILD, json.dumps(spec)],
                         capture_output=True, text=True, timeout=600, env=env)
    if out.returncode != 0:
        raise BenchmarkError(f"memory subprocess failed: {out.stderr.strip()[-500:]}")
    return int(json.loads(out.stdout.strip().splitlines()[-1])["maxrss_kb"])


def peak_memory(variants: list[Variant], threads: tuple[int, ...], frames: int, baseline_runs: int = 3) -> dict:
    """{"baseline_kb": …, (name, threads): MiB above the baseline} from fresh subprocesses."""
    base = int(np.median([_child_rss_kb({"encoder": None}) for _ in range(baseline_runs)]))
    out: dict[Any, Any] = {"baseline_kb": base}
    for v in variants:
        for t in threads:
            kb = _child_rss_kb({"encoder": str(v.encoder), "head": str(v.head), "threads": t, "grid": list(v.grid),
                                "window": v.window, "features": v.features, "frames": frames})
            out[(v.name, t)] = (kb - base) / 1024
    return out


# ---------------------------------------------------------------------------------------------- errors
def load_eval_tracks(data: list[str], split: str) -> dict[tuple[int, int], dict[str, Any]]:
    """grid → {"tracks", "pitch_m", "data", "subjects"} from every dataset folder given (one set per grid)."""
    from export.finetune import user_tracks
    from sim.dataset import DatasetError

    groups: dict[tuple[int, int], dict[str, Any]] = {}
    for d in data:
        try:
            tracks, pitch, ds = user_tracks(d, split)
        except (DatasetError, ValueError) as exc:
            raise BenchmarkError(str(exc)) from None
        grid = (int(ds.manifest["rows"]), int(ds.manifest["cols"]))
        g = groups.setdefault(grid, {"tracks": [], "pitch_m": pitch, "data": []})
        if abs(g["pitch_m"] - pitch) > 1e-6:
            raise BenchmarkError(f"{d}: pitch {pitch} m differs from the other {grid[0]}×{grid[1]} datasets' {g['pitch_m']} m")
        g["tracks"] += tracks
        g["data"].append(str(d))
    for g in groups.values():
        g["subjects"] = sorted({f"s{t.subject:02d}" for t in g["tracks"]})
    return groups


ERROR_KEYS = ("mpjpe_cm", "pa_mpjpe_cm", "heading_over90_pct", "pve_cm", "transl_cm")  # export.tables.summarise's


def variant_error(v: Variant, groups: dict, stride: int) -> dict[str, Any]:
    from export.tables import evaluate_bundle

    if v.trained is False:
        return {"status": "not trained"}
    if not groups:
        return {"status": "not evaluated", "reason": "no --data given (speed only)"}
    if v.trained is None:
        return {"status": "not evaluated", "reason": "the bundle has no weights.npz"}
    g = groups.get(v.grid)
    if g is None or v.bundle_dir is None:
        return {"status": "not evaluated", "reason": f"no --data of a {v.grid[0]}×{v.grid[1]} carpet"}
    if abs(g["pitch_m"] - v.pitch_m) > 0.05 * v.pitch_m:
        return {"status": "not evaluated", "reason": f"data pitch {g['pitch_m']} m, bundle pitch {v.pitch_m} m"}
    o = evaluate_bundle(v.bundle_dir, g["tracks"], g["pitch_m"], frame_stride=stride)["overall"]  # heading resolved
    return {"status": "evaluated", **{k: o[k] for k in ERROR_KEYS}, "frames": o["frames"]}


def baseline_error(manifest: dict[str, Any], group: dict[str, Any], stride: int) -> dict[str, Any] | None:
    """The mean-pose baseline of the reference bundle's manifest on the same frames (context for the table)."""
    from export.tables import baseline_errors, summarise

    base = manifest.get("baseline")
    if not base:
        return None
    e = baseline_errors((np.array(base["pose_aa"]), np.array(base["betas"]), float(base["pelvis_height_m"])),
                        group["tracks"], group["pitch_m"], frame_stride=stride)
    o = summarise(e)["overall"]
    return {**{k: o[k] for k in ERROR_KEYS}, "frames": o["frames"]}


# ---------------------------------------------------------------------------------------------- ratios
def ratio_onnxruntime_vs_torch(net, twin: Variant, inputs: np.ndarray, rounds: int, calls: int) -> dict[str, Any]:
    import torch

    from edge.infer import FeatureWindow
    from export.quantize import session

    prev = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        win = FeatureWindow(twin.window, twin.features)
        order = itertools.cycle(range(len(inputs)))

        def eager() -> None:
            with torch.inference_mode():
                f = net.encoder(torch.from_numpy(inputs[next(order)][None]))
                win.push(f[0].numpy())
                net.head(torch.from_numpy(win.window()))

        ort_frame = _frame_fn(session(twin.encoder, 1), session(twin.head, 1), inputs, twin.window, twin.features)
        r = side_by_side(eager, ort_frame, rounds, calls)
    finally:
        torch.set_num_threads(prev)
    return {"what": f"PyTorch eager / onnxruntime, {twin.name} weights, encoder + head per frame, 1 thread "
                    "(torch.set_num_threads(1), inference_mode; onnxruntime intra-op 1)",
            "a": "pytorch eager", "b": "onnxruntime", **r}


def ratio_feature_cache(v: Variant, inputs: np.ndarray, rounds: int, calls: int) -> dict[str, Any]:
    from export.quantize import session

    enc, head = session(v.encoder, 1), session(v.head, 1)
    ein, hin = enc.get_inputs()[0].name, head.get_inputs()[0].name
    n = len(inputs)
    windows = [np.ascontiguousarray(inputs[(k - np.arange(v.window)[::-1]) % n]) for k in range(min(n, 8))]
    order = itertools.cycle(range(len(windows)))

    def reencode() -> None:
        f = enc.run(None, {ein: windows[next(order)]})[0]
        head.run(None, {hin: f[None]})

    cached = _frame_fn(enc, head, inputs, v.window, v.features)
    r = side_by_side(reencode, cached, rounds, calls)
    return {"what": f"re-encoding all {v.window} frames (encoder batch {v.window} + head) / the feature cache "
                    f"(encoder batch 1 + head), {v.name}, 1 thread", "a": "re-encode window", "b": "feature cache", **r}


def ratio_body(rounds: int, calls: int, seed: int = 0) -> dict[str, Any]:
    from edge.body import BodyModel

    body = BodyModel.load("full")
    rng = np.random.default_rng(seed)
    pose, betas, transl = rng.normal(0, 0.3, (1, 72)), rng.normal(0, 1, (1, 10)), rng.normal(0, 0.5, (1, 3))
    r = side_by_side(lambda: body.forward(pose, betas, transl, vertices=True),
                     lambda: body.forward(pose, betas, transl, vertices=False), rounds, calls)
    return {"what": f"full mesh ({body.num_vertices} vertices) / joints only, BodyModel 'full', batch 1",
            "a": "vertices=True", "b": "vertices=False", **r}


# ---------------------------------------------------------------------------------------------- the day
@dataclass
class Day:
    counts: list[np.ndarray]
    kinds: list[str]
    people: list[int]
    calibration: Any
    grid: tuple[int, int]
    pitch_m: float
    seed: int

    def describe(self) -> dict[str, Any]:
        n = len(self.kinds)
        frac = {k: round(self.kinds.count(k) / n, 4) for k in ("empty", "still", "active")}
        return {"frames": n, "seconds": round(n / RATE_HZ, 2), "rate_hz": RATE_HZ, "grid": list(self.grid),
                "pitch_m": self.pitch_m, "fraction": frac, "two_person_frames": self.people.count(2),
                "segments": [{"kind": k, "fraction": f, "people": p} for k, f, p in DAY],
                "source": (f"sim.live.LiveCarpet pressure through one simulated sensor (sim.live.live_sensor seed "
                           f"{self.seed}), calibrated with calibration_from_truth; active: one person ({', '.join(ACTIVE_1)}) "
                           f"or two ({', '.join(ACTIVE_2)}); still: one person holding a pose of the simulator's "
                           f"{' / '.join(STILL)} (the sensor's noise stays live); empty: no load. Every frame goes through "
                           "CalibratedFrames → SceneTracker → FrameStages (the runtime's own classes)")}


def simulated_day(grid: tuple[int, int], pitch_m: float, seconds: float, seed: int = 0) -> Day:
    from calibration.from_truth import calibration_from_truth
    from sim.live import LiveCarpet, live_sensor

    total = max(len(DAY), int(round(seconds * RATE_HZ)))
    sizes = [max(1, int(round(f * total))) for _, f, _ in DAY]
    pitch_mm = pitch_m * 1e3
    sensor = live_sensor(seed, grid[0], pitch_mm=pitch_mm)
    cal = calibration_from_truth(sensor, 0.0, device_id=f"bench-day-{seed}")
    # a chunk (one scene: activities and places) as long as the longest segment: placing scenes is the slow part
    longest = {k: max(n for (kind, _, p), n in zip(DAY, sizes) if (kind, p) == k) / RATE_HZ for k in (("active", 1), ("active", 2))}
    active = {1: LiveCarpet(grid[0], grid[1], 1, seed + 1, pitch_mm=pitch_mm, activities=ACTIVE_1, chunk_s=longest["active", 1]),
              2: LiveCarpet(grid[0], grid[1], 2, seed + 2, pitch_mm=pitch_mm, activities=ACTIVE_2, chunk_s=longest["active", 2])}
    still = LiveCarpet(grid[0], grid[1], 1, seed + 3, pitch_mm=pitch_mm, activities=STILL, chunk_s=1.0)
    next_frame = {1: 0, 2: 0}
    still_chunk = 0
    counts, kinds, people = [], [], []
    for (kind, _, n_people), n in zip(DAY, sizes):
        if kind == "still":
            held = still.pressure_kpa(still_chunk * still.chunk_frames + still.chunk_frames // 2)
            still_chunk += 1
        for _ in range(n):
            if kind == "empty":
                p = np.zeros(grid, np.float32)
            elif kind == "still":
                p = held
            else:
                p = active[n_people].pressure_kpa(next_frame[n_people])
                next_frame[n_people] += 1
            counts.append(sensor.counts(p, len(counts) / RATE_HZ))
            kinds.append(kind)
            people.append(n_people)
    return Day(counts, kinds, people, cal, grid, pitch_m, seed)


def _summing_times(frames: int):
    from edge.runtime.counters import StageTimes

    class SummingTimes(StageTimes):
        """StageTimes that also keeps every value (sums and per-frame distributions for the benchmark)."""

        def __init__(self) -> None:
            super().__init__(frames)
            self.values: dict[str, list[float]] = {}

        def add(self, stage: str, ms: float) -> None:
            super().add(stage, ms)
            self.values.setdefault(stage, []).append(float(ms))

    return SummingTimes()


def day_pass(bundle: Any, day: Day, adaptive: bool) -> dict[str, Any]:
    """The whole day through fresh CalibratedFrames → SceneTracker → FrameStages."""
    from calibration.runtime import CalibratedFrames
    from edge.frames import RawFrame
    from edge.runtime.counters import Counters
    from edge.runtime.stages import FrameStages
    from edge.scene import SceneTracker

    times, counters = _summing_times(len(day.counts)), Counters()
    stages = FrameStages(CalibratedFrames(day.calibration), SceneTracker(day.grid[0], day.grid[1], day.pitch_m), bundle,
                         device="bench-day", times=times, counters=counters, adaptive=adaptive)
    host0 = time.time()
    for k, c in enumerate(day.counts):
        stages.process(RawFrame(c, k, k, k / RATE_HZ, host0 + k / RATE_HZ))
    v = times.values
    return {"model_ms": sum(v.get("encoder", [])) + sum(v.get("head", [])), "frame_ms": sum(v["frame"]),
            "frames": len(day.counts), "counters": counters.snapshot(), "values": v}


def ratio_scene_adaptive(bundle_dir: Path, day: Day, rounds: int) -> tuple[dict[str, Any], dict[str, Any]]:
    """Always-infer / scene-adaptive over the day, and the adaptive passes' per-frame costs."""
    from edge.infer import ModelBundle

    bundle = ModelBundle.load(bundle_dir, threads=1)
    day_pass(bundle, day, True)  # warm-up
    passes: dict[bool, list[dict]] = {True: [], False: []}
    for r in range(rounds):
        for adaptive in ((True, False) if r % 2 == 0 else (False, True)):
            passes[adaptive].append(day_pass(bundle, day, adaptive))
    model = [b["model_ms"] / a["model_ms"] for a, b in zip(passes[True], passes[False])]
    total = [b["frame_ms"] / a["frame_ms"] for a, b in zip(passes[True], passes[False])]

    def work(p: dict) -> dict[str, int]:
        c = p["counters"]
        return {"encoder_runs": c.get("encoder_runs", 0), "head_runs": c.get("head_runs", 0),
                "still_reuses": c.get("still_reuses", 0), "idle_runs": c.get("idle_runs", 0),
                "frames_empty": c.get("frames_empty", 0), "frames_unconfirmed": c.get("frames_unconfirmed", 0),
                "frames_people": c.get("frames_people", 0), "person_frames": c.get("person_frames", 0),
                "records": c.get("records", 0), "heartbeats": c.get("heartbeats", 0)}

    n = len(day.counts)
    result = {
        "what": "always-infer / scene-adaptive: the same simulated day through FrameStages(adaptive=False) and "
                "FrameStages(adaptive=True) (the runtime's logic: empty → heartbeat, still person → reuse, else one "
                "inference per person); always-infer runs encoder + head on every frame, for every tracked person and "
                f"on the whole carpet when nobody is there. {bundle_dir.name}, onnxruntime 1 thread",
        "day": day.describe(),
        "model_time": {"a_ms_per_frame": float(np.median([p["model_ms"] / n for p in passes[False]])),
                       "b_ms_per_frame": float(np.median([p["model_ms"] / n for p in passes[True]])), "ratio": spread(model)},
        "frame_time": {"a_ms_per_frame": float(np.median([p["frame_ms"] / n for p in passes[False]])),
                       "b_ms_per_frame": float(np.median([p["frame_ms"] / n for p in passes[True]])), "ratio": spread(total)},
        "a": "always-infer", "b": "scene-adaptive",
        "inferences": {"always_infer": work(passes[False][0]), "scene_adaptive": work(passes[True][0])},
    }
    return result, {"passes": passes[True], "frames": n}


def runtime_vs_interval(adaptive: dict[str, Any], runtime_latency: str | None) -> dict[str, Any]:
    """Per-frame runtime cost / the 71.4 ms frame interval at 14 Hz: bench/runtime_latency.py's results when present
    (its "frame_total" per scene: decode + calibrate … record + publish, one thread), else the adaptive day's."""
    interval = 1e3 / RATE_HZ
    if runtime_latency and Path(runtime_latency).is_file():
        rl = json.loads(Path(runtime_latency).read_text())
        scenes = [r for r in rl.get("results", []) if isinstance(r, dict) and (r.get("frame_total") or {}).get("median_ms")]
        if scenes:
            rows = [{"people": r.get("people"), "frame_median_ms": r["frame_total"]["median_ms"],
                     "frame_p99_ms": r["frame_total"].get("p99_ms"), "fraction_median": r["frame_total"]["median_ms"] / interval,
                     "fraction_p99": r["frame_total"]["p99_ms"] / interval if r["frame_total"].get("p99_ms") else None}
                    for r in scenes]
            worst = max(rows, key=lambda r: r["frame_median_ms"])
            return {"what": "runtime per-frame cost (decode + calibrate … record + publish, one thread; bench/runtime_latency.py) "
                            "/ frame interval; the headline is its slowest scene",
                    "source": f"{runtime_latency}: `{rl.get('command', 'command not recorded')}` at git "
                              f"{str(rl.get('git_revision', 'unknown'))[:12]}",
                    "interval_ms": interval, **{k: worst[k] for k in ("frame_median_ms", "frame_p99_ms", "fraction_median",
                                                                       "fraction_p99")},
                    "people": worst["people"], "scenes": rows}
    passes, n = adaptive["passes"], adaptive["frames"]
    every = np.concatenate([p["values"]["frame"] for p in passes])
    stages = {}
    for stage in ("calibrate", "scene", "encoder", "head", "record", "frame"):
        vals = [np.asarray(p["values"].get(stage, []), float) for p in passes]
        allv = np.concatenate(vals)
        stages[stage] = {"median_ms": float(np.median(allv)) if allv.size else None,
                         "p99_ms": float(np.percentile(allv, 99)) if allv.size else None,
                         "frames_run": int(allv.size // len(passes)),
                         "mean_ms_per_frame": float(np.median([v.sum() / n for v in vals]))}
    return {"what": "runtime per-frame cost (FrameStages.process: calibrate → scene → model → record; decoding and "
                    "publishing not included) / frame interval, on the simulated day, scene-adaptive",
            "source": "measured: the scene-adaptive passes of the simulated day", "interval_ms": interval,
            "frame_median_ms": float(np.median(every)), "frame_p99_ms": float(np.percentile(every, 99)),
            "fraction_median": float(np.median(every)) / interval, "fraction_p99": float(np.percentile(every, 99)) / interval,
            "fraction_mean_per_round": spread([p["frame_ms"] / n / interval for p in passes]), "stages_ms": stages}


# ---------------------------------------------------------------------------------------------- the run
def _machine() -> dict[str, Any]:
    """As bench/machine.py records it: platform, CPU, cores, versions, the load average now."""
    cpu = platform.processor()
    try:
        cpu = next(line.split(":", 1)[1].strip() for line in Path("/proc/cpuinfo").read_text().splitlines()
                   if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return {"platform": platform.platform(), "cpu_model": cpu, "cpu_count": os.cpu_count(), "python": platform.python_version(),
            "numpy": np.__version__, "load_average_1_5_15_min": [round(x, 2) for x in os.getloadavg()]}


def run_speed_error(cfg: SpeedErrorConfig, command: str = "") -> dict[str, Any]:
    import onnxruntime as ort
    import torch

    from cavatar_common.provenance import git_revision
    from export.model import ModelConfig

    if not cfg.bundles:
        raise BenchmarkError("no bundle given")
    t_start = time.perf_counter()
    start = _machine()

    def log(text: str) -> None:
        cfg.log(f"[{time.perf_counter() - t_start:6.1f} s] {text}")

    with tempfile.TemporaryDirectory(prefix="cavatar-bench-") as tmpdir:
        tmp = Path(tmpdir)
        if cfg.data:
            for b in cfg.bundles:  # refuse before the slow parts
                require_weights(Path(b), _manifest(Path(b)))
            log(f"loading the {cfg.split} tracks of {', '.join(cfg.data)}")
        groups = load_eval_tracks(cfg.data, cfg.split) if cfg.data else {}
        variants: list[Variant] = []
        ref = None
        for i, b in enumerate(cfg.bundles):
            log(f"bundle {b}: loading, exporting its fp32 twin")
            vs, net, twin, manifest = bundle_variants(b, tmp / f"bundle-{i}", need_weights=bool(cfg.data), seed=cfg.seed)
            taken = {v.name for v in variants}
            for v in vs:
                if v.name in taken:
                    v.name = f"{v.name} ({Path(b).name})"
            variants += vs
            if ref is None:
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

        evaluation: dict[str, Any] = {"status": "not evaluated", "reason": "no --data given (speed only)"}
        if groups:
            log("the mean-pose baseline on the same frames")
            evaluation = {"status": "evaluated", "split": cfg.split, "frame_stride": cfg.stride, "grids": {
                f"{g[0]}x{g[1]}": {"data": grp["data"], "pitch_m": grp["pitch_m"], "tracks": len(grp["tracks"]),
                                   "subjects": grp["subjects"], "baseline_mean_pose": baseline_error(ref["manifest"], grp, cfg.stride)
                                   if g == grid else None} for g, grp in groups.items()}}
    log("done")
    front = pareto(rows)
    end = _machine()
    return {
        "schema": SCHEMA, "benchmark": "speed_error", "command": command, "date": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "git_revision": git_revision(),
        "machine": {**start, "load_average_1_5_15_min_at_end": end["load_average_1_5_15_min"],
                    "onnxruntime": ort.__version__, "torch": torch.__version__},
        "method": {
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
        },
        "evaluation": evaluation,
        "variants": rows,
        "pareto_front": front,
        "ratios": ratios,
        "elapsed_s": round(time.perf_counter() - t_start, 1),
    }


def pareto(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The front over every evaluated (variant, threads) point: median latency vs MPJPE."""
    pts = [(r["name"], s["threads"], s["median_ms"], r["error"]["mpjpe_cm"]) for r in rows
           if r["error"]["status"] == "evaluated" for s in r["speed"]]
    return [{"variant": pts[i][0], "threads": pts[i][1], "median_ms": pts[i][2], "mpjpe_cm": pts[i][3]}
            for i in pareto_front([(p[2], p[3]) for p in pts])]


# ---------------------------------------------------------------------------------------------- outputs
def _num(v: Any, digits: int = 2) -> str:
    return "—" if v is None else f"{v:.{digits}f}"


def _error_cells(e: dict[str, Any]) -> list[str]:
    if e["status"] == "evaluated":
        return [_num(e.get(k)) for k in ERROR_KEYS]
    return [e["status"]] * len(ERROR_KEYS)


def variant_table(result: dict[str, Any]) -> list[str]:
    lines = ["| variant | weights | threads | median ms | p99 ms | frames/s | peak MiB | size MB | MPJPE cm | PA-MPJPE cm | "
             "heading >90° % | PVE cm | transl cm |", "|---" * 13 + "|"]
    for r in result["variants"]:
        for s in r["speed"]:
            lines.append("| " + " | ".join([r["name"], r["weights"].split(" (")[0], str(s["threads"]), _num(s["median_ms"]),
                                            _num(s["p99_ms"]), f"{s['frames_per_s']:.0f}", f"{s['peak_rss_mb']:.1f}",
                                            f"{r['size_bytes']['total'] / 1e6:.2f}", *_error_cells(r["error"])]) + " |")
    return lines


def interval_sentence(e2e: dict[str, Any]) -> str:
    """The runtime's per-frame cost against the frame interval, in words (per scene when measured per scene)."""
    def one(r: dict[str, Any]) -> str:
        p99 = f", p99 {_num(r['frame_p99_ms'])} ms" + (f" = {100 * r['fraction_p99']:.1f} %" if r.get("fraction_p99") else "")
        return f"median {_num(r['frame_median_ms'])} ms = {100 * r['fraction_median']:.1f} %{p99}"

    if e2e.get("scenes"):
        body = "; ".join(f"{r['people']} {'person' if r['people'] == 1 else 'people'}: {one(r)}" for r in e2e["scenes"])
    else:
        body = one(e2e)
    return f"Runtime per frame against the {e2e['interval_ms']:.1f} ms frame interval at 14 Hz: {body}. Source: {e2e['source']}."


def ratio_lines(result: dict[str, Any]) -> list[str]:
    rt = result["ratios"]
    lines = ["| ratio | a | b | a ms | b ms | ratio a/b (median) | IQR | rounds |", "|---|---|---|---|---|---|---|---|"]
    for key in ("onnxruntime_vs_torch_eager", "feature_cache", "body_mesh_vs_joints"):
        r = rt[key]
        lines.append(f"| {key} | {r['a']} | {r['b']} | {_num(r['a_ms'], 3)} | {_num(r['b_ms'], 3)} | "
                     f"{r['ratio']['median']:.2f}× | {r['ratio']['p25']:.2f}–{r['ratio']['p75']:.2f} | {r['ratio']['rounds']} |")
    sa = rt["scene_adaptive"]
    for part in ("model_time", "frame_time"):
        r, q = sa[part], sa[part]["ratio"]
        lines.append(f"| scene_adaptive {part.replace('_', ' ')} (per frame) | {sa['a']} | {sa['b']} | "
                     f"{_num(r['a_ms_per_frame'], 3)} | {_num(r['b_ms_per_frame'], 3)} | {q['median']:.2f}× | "
                     f"{q['p25']:.2f}–{q['p75']:.2f} | {q['rounds']} |")
    inf, day = sa["inferences"], sa["day"]
    e2e = rt["runtime_vs_frame_interval"]
    lines += ["", f"Simulated day: {day['frames']} frames ({day['seconds']} s at {day['rate_hz']:g} Hz): "
              f"{100 * day['fraction']['empty']:.0f} % empty, {100 * day['fraction']['still']:.0f} % one still person, "
              f"{100 * day['fraction']['active']:.0f} % activity ({day['two_person_frames']} frames with two people). "
              f"Inferences (encoder runs): always-infer {inf['always_infer']['encoder_runs']}, scene-adaptive "
              f"{inf['scene_adaptive']['encoder_runs']} (still reuses {inf['scene_adaptive']['still_reuses']}, frames "
              f"without inference {inf['scene_adaptive']['frames_empty'] + inf['scene_adaptive']['frames_unconfirmed']}).",
              "", interval_sentence(e2e)]
    return lines


def markdown(result: dict[str, Any]) -> str:
    m = result["machine"]
    ev = result["evaluation"]
    if ev["status"] == "evaluated":
        where = "; ".join(f"{g}: {', '.join(x['data'])} ({x['tracks']} tracks, subjects {', '.join(x['subjects'])})"
                          for g, x in ev["grids"].items())
        errors = f"Errors on the {ev['split']} split, every {ev['frame_stride']}th frame: {where}."
        for g, x in ev["grids"].items():
            if x.get("baseline_mean_pose"):
                b = x["baseline_mean_pose"]
                errors += (f" Mean-pose baseline ({g}): MPJPE {b['mpjpe_cm']:.2f}, PVE {b['pve_cm']:.2f}, "
                           f"translation {b['transl_cm']:.2f} cm.")
    else:
        errors = f"Errors not evaluated: {ev['reason']}."
    front = ", ".join(f"{p['variant']} ({p['threads']} thr)" for p in result["pareto_front"]) or "none (no evaluated variant)"
    lines = ["# Speed against error", "",
             f"`{result['command']}` on {result['date']}, git {result['git_revision'][:12]}; {m['cpu_model']}, "
             f"{m['cpu_count']} cores, load average {', '.join(f'{x:.2f}' for x in m['load_average_1_5_15_min'])} at start; "
             f"onnxruntime {m['onnxruntime']}, torch {m['torch']}. Generated from bench/results/speed_error.json.", "",
             "Latency = encoder (batch 1, the new frame) + head (batch 1, the 40-frame window of cached features), per "
             "published frame. Untrained variants (random weights) are timed only: their error is never plotted. "
             + errors, "", *variant_table(result), "", f"Pareto front (latency, MPJPE): {front}.", "",
             "![latency per frame vs MPJPE](pareto.png)", "", "## Ratios, measured side by side", "",
             "Median and interquartile range of the per-round ratio (both sides in every round, alternating order).", "",
             *ratio_lines(result), ""]
    return "\n".join(lines)


def plot(result: dict[str, Any], path: str | Path) -> Path:
    """Latency per frame vs MPJPE: evaluated points labelled, the Pareto front drawn; speed-only variants
    on a strip below (never on the error axis). Marker shape = onnxruntime threads."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.ticker import FormatStrFormatter, LogLocator

    evaluated = [r for r in result["variants"] if r["error"]["status"] == "evaluated"]
    speed_only = [r for r in result["variants"] if r["error"]["status"] != "evaluated"]
    fig, (ax, strip) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True,
                                    gridspec_kw={"height_ratios": [3.2, 0.4 + 0.3 * max(len(speed_only), 1)]})
    markers = {1: "o", 2: "s"}
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, r in enumerate(evaluated):
        y = r["error"]["mpjpe_cm"]
        for s in r["speed"]:
            ax.scatter(s["median_ms"], y, marker=markers.get(s["threads"], "^"), s=45, color=colours[i % len(colours)], zorder=3)
        x0 = min(s["median_ms"] for s in r["speed"])
        ax.annotate(r["name"], (x0, y), textcoords="offset points", xytext=(-4, 7), fontsize=8, ha="left")
    front = result["pareto_front"]
    if front:
        ax.step([p["median_ms"] for p in front], [p["mpjpe_cm"] for p in front], where="post", color="tab:red", lw=1.3,
                zorder=2)
    else:
        why = result["evaluation"].get("reason", "no trained variant")
        ax.text(0.5, 0.5, f"errors not evaluated: {why}", transform=ax.transAxes, ha="center", va="center", fontsize=10,
                color="0.3")
    handles = [Line2D([], [], marker=m, ls="", color="0.3", label=f"{t} thread{'s' if t > 1 else ''}") for t, m in markers.items()]
    handles.append(Line2D([], [], color="tab:red", lw=1.3, label="Pareto front"))
    ax.legend(handles=handles, loc="upper right", fontsize=8)
    ax.set_ylabel("MPJPE (cm), unseen subjects")
    ax.set_title("Latency per published frame (encoder batch 1 + head over the window) vs error", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    labels = [r["name"] for r in speed_only]
    for y, r in enumerate(speed_only):
        for s in r["speed"]:
            strip.scatter(s["median_ms"], y, marker=markers.get(s["threads"], "^"), s=35, color="0.4", zorder=3)
    strip.set_yticks(range(len(labels)))
    strip.set_yticklabels([f"{r['name']} ({r['error']['status']})" for r in speed_only], fontsize=8)
    strip.set_ylim(-0.7, max(len(labels), 1) - 0.3)
    strip.set_title("speed only: no error on the axis above", fontsize=9)
    strip.set_xlabel("latency per frame, median (ms)")
    strip.grid(True, axis="x", which="both", alpha=0.3)
    xs = [s["median_ms"] for r in result["variants"] for s in r["speed"]]
    if xs and max(xs) / min(xs) > 5:
        strip.set_xscale("log")
        strip.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        strip.xaxis.set_major_formatter(FormatStrFormatter("%g"))
        strip.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_outputs(result: dict[str, Any], json_path: str | Path, markdown_path: str | Path, plot_path: str | Path) -> None:
    for p in (json_path, markdown_path):
        Path(p).parent.mkdir(parents=True, exist_ok=True)
    Path(json_path).write_text(json.dumps(result, indent=1) + "\n")
    Path(markdown_path).write_text(markdown(result))
    plot(result, plot_path)


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

"""What a variant costs per published frame: latency (encoder batch 1 + head over the window), peak memory
in a fresh subprocess, and the model-side ratios measured side by side (onnxruntime vs PyTorch eager, the
feature cache vs re-encoding the window, the full mesh vs joints only)."""

from __future__ import annotations

import itertools
import json
import os
import subprocess
import sys
import time
from typing import Any, Callable

import numpy as np

from bench import BenchmarkError
from bench.stats import latency_stats, side_by_side
from bench.variants import Variant


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

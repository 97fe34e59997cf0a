"""Statistics of timed rounds: latency percentiles, side-by-side ratios, the Pareto front."""

from __future__ import annotations

import time
from typing import Any, Callable

import numpy as np


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


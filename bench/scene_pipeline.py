"""Per-frame cost of the scene step (validate + fill + filters + contacts + grouping/tracking)
on 96×96 frames, one thread, for empty, 1-, 2- and 3-person scenes, and tracking quality
(identity switches, missed people) on simulated 2- and 3-person walks.
Writes bench/results/scene_pipeline.json.

    OMP_NUM_THREADS=1 python -m bench.scene_pipeline
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from pathlib import Path

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import numpy as np  # noqa: E402
import scipy  # noqa: E402

from edge.scene import SceneTracker, score_tracking  # noqa: E402
from sim.footsteps import FootstepCarpet  # noqa: E402

FRAMES = 600
NOISE_KPA = 0.05
SALT = 5
# FootstepCarpet walkers that start < 0.6 m apart never move; these seeds start apart.
TRACK_SCENES = {2: [1, 3, 4, 5, 6], 3: [7, 20, 24, 27, 30]}


def frames(people: int, seed: int, n: int):
    carpet = FootstepCarpet(96, 96, people, seed)
    rng = np.random.default_rng(seed + 1000)
    for i in range(n):
        carpet(i)
        p = carpet.pressure_kpa().astype(np.float32) + rng.normal(0, NOISE_KPA, (96, 96)).astype(np.float32)
        p[rng.integers(0, 96, SALT), rng.integers(0, 96, SALT)] += rng.uniform(5, 20, SALT).astype(np.float32)
        yield i * carpet.dt_s, p, {k: w.pos_m.copy() for k, w in enumerate(carpet._walkers)}


def stats(values_ms: list[float]) -> dict:
    a = np.asarray(values_ms)
    return {"median_ms": round(float(np.median(a)), 4), "p99_ms": round(float(np.percentile(a, 99)), 4)}


def timing(people: int, seed: int, repeats: int = 1) -> dict:
    """Stage medians of the fastest of ``repeats`` runs over the same frames (a shared machine's speed
    drifts run to run; the fastest run is the one least disturbed), with every run's total median."""
    runs = [_timing_once(people, seed) for _ in range(max(1, repeats))]
    best = min(runs, key=lambda r: r["stages"]["total"]["median_ms"])
    return {**best, "repeats": len(runs), "total_median_ms_per_repeat": [r["stages"]["total"]["median_ms"] for r in runs]}


def _timing_once(people: int, seed: int) -> dict:
    data = [(t, p) for t, p, _ in frames(people, seed, FRAMES)]
    st = SceneTracker(96, 96, 0.01905)
    for t, p in data[:30]:  # warm-up (noise estimate, tracks confirmed)
        st.update(p, t)
    per_stage: dict[str, list[float]] = {}
    outer = []
    for t, p in data[30:]:
        t0 = time.perf_counter()
        st.update(p, t + 1000.0)  # times continue after the warm-up
        outer.append((time.perf_counter() - t0) * 1e3)
        for k, v in st.last_timings_ms.items():
            per_stage.setdefault(k, []).append(v)
    return {"people": people, "seed": seed, "frames": len(outer), "stages": {k: stats(v) for k, v in per_stage.items()},
            "update_call": stats(outer)}


def tracking(people: int, seed: int, n: int = 840) -> dict:
    st = SceneTracker(96, 96, 0.01905)
    truth, reported = [], []
    for t, p, true in frames(people, seed, n):
        out = st.update(p, t)
        truth.append(true)
        reported.append({q.track_id: q.cop_m for q in out.people})
    return {"people": people, "seed": seed, "seconds": round(n / 14, 1), **score_tracking(truth, reported, 0.5).to_dict()}


def main(argv: list[str] | None = None) -> int:
    import argparse

    ap = argparse.ArgumentParser(description="scene step cost and tracking quality")
    ap.add_argument("--out", type=Path, default=Path(__file__).parent / "results" / "scene_pipeline.json")
    ap.add_argument("--before", type=Path, help="a result of this bench on earlier code, kept beside as 'before'")
    ap.add_argument("--before-code", default="d34ed20 (edge/scene before the body-aware grouping)")
    ap.add_argument("--repeats", type=int, default=5, help="timed runs per scene; the fastest is reported (default 5)")
    args = ap.parse_args(argv)
    timings = [timing(0, 0, args.repeats), timing(1, 1, args.repeats), timing(2, 1, args.repeats), timing(3, 24, args.repeats)]
    tracks = [tracking(k, s) for k, seeds in TRACK_SCENES.items() for s in seeds]
    totals = {}
    for k in (2, 3):
        rows = [r for r in tracks if r["people"] == k]
        keys = ("frames", "true_people", "missed", "false_positives", "id_switches")
        totals[f"{k}_people"] = {key: sum(r[key] for r in rows) for key in keys}
        totals[f"{k}_people"]["missed_fraction"] = round(totals[f"{k}_people"]["missed"] / totals[f"{k}_people"]["true_people"], 4)
    out = {
        "benchmark": "scene_pipeline",
        "command": f"OMP_NUM_THREADS=1 python -m bench.scene_pipeline --repeats {args.repeats}",
        "machine": {"platform": platform.platform(), "processor": platform.processor(), "cpus": os.cpu_count(),
                    "python": platform.python_version(), "numpy": np.__version__, "scipy": scipy.__version__,
                    "blas_threads": os.environ.get("OMP_NUM_THREADS"), "load_average_1_5_15_at_end": None},
        "method": (f"96×96 frames from sim.footsteps.FootstepCarpet true pressure + white noise σ {NOISE_KPA} kPa + {SALT} salt "
                   f"spikes per frame; default SceneConfig (noise estimated online); {FRAMES - 30} timed frames after 30 "
                   "warm-up frames; per-stage times from SceneTracker.last_timings_ms (perf_counter), 'update_call' timed "
                   "around the call; each scene timed --repeats times on fresh trackers, the run with the lowest "
                   "median total reported (every run's total in total_median_ms_per_repeat). Calibration apply is "
                   "not included (done by calibration/)."),
        "goal": "filter + segment + track ≤ 3 ms per 96×96 frame on one core",
        "timing": timings,
        "tracking": {"gate_m": 0.5, "note": "CLEAR-MOT style counts (edge.scene.metrics); truth = walker body centre, "
                     "reported = one-euro centre of pressure; 60 s per scene", "scenes": tracks, "totals": totals},
    }
    out["machine"]["load_average_1_5_15_at_end"] = [round(x, 2) for x in os.getloadavg()]
    if args.before:
        old = json.loads(args.before.read_text())
        out["before"] = {"code": args.before_code, "timing": old["timing"], "tracking_totals": old["tracking"]["totals"],
                         "machine": old["machine"]}
        out["command"] += f" --before {args.before}"
    path = args.out
    path.write_text(json.dumps(out, indent=1) + "\n")
    for r in timings:
        stages = ", ".join(f"{k} {v['median_ms']}/{v['p99_ms']}" for k, v in r["stages"].items())
        print(f"{r['people']} people: {stages} ms (median/p99)")
    for k, v in totals.items():
        print(k, v)
    print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

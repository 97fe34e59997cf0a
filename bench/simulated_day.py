"""A simulated day on the carpet (empty, still, active; one or two people) through the runtime's own
FrameStages, scene-adaptive and always-infer, and the runtime's per-frame cost against the frame interval."""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from bench.stats import spread

RATE_HZ = 14.0

# The simulated day, in order: (kind, fraction of the day, people). "still" holds one simulated pose (sensor
# noise stays live): the simulator's own standing sways, and the scene calls only ~30 % of those frames still.
DAY = (("empty", 0.20, 0), ("active", 0.04, 1), ("still", 0.12, 1), ("active", 0.03, 1), ("empty", 0.20, 0),
       ("active", 0.05, 2), ("still", 0.13, 1), ("active", 0.03, 1), ("empty", 0.20, 0))
ACTIVE_1 = ("walking", "stepping", "squat", "lunge", "turning", "raising_arms")
ACTIVE_2 = ("walking", "stepping")
STILL = ("standing", "sitting")


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
    # chunks of exactly chunk_s (extend=False): the day's segments are cut by frame count
    active = {1: LiveCarpet(grid[0], grid[1], 1, seed + 1, pitch_mm=pitch_mm, activities=ACTIVE_1, chunk_s=longest["active", 1],
                            extend=False),
              2: LiveCarpet(grid[0], grid[1], 2, seed + 2, pitch_mm=pitch_mm, activities=ACTIVE_2, chunk_s=longest["active", 2],
                            extend=False)}
    still = LiveCarpet(grid[0], grid[1], 1, seed + 3, pitch_mm=pitch_mm, activities=STILL, chunk_s=1.0, extend=False)
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

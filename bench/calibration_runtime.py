"""Runtime calibration cost per 96×96 frame on one thread: apply, apply + crosstalk inverse,
baseline tracking, the full calibration step, and calibration + scene (filter, segment, track).

Frames: two people walking (``sim.footsteps``) through a randomised simulated carpet at
14 Hz (generated before timing). Each call is timed alone, so p99 shows the once-a-second
baseline update. Issue 5's goal: calibrate + filter + segment + track ≤ 3 ms per frame.

Usage: python -m bench.calibration_runtime  → bench/results/calibration_runtime.json
"""

from __future__ import annotations

import json
import os
import platform
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from bench import machine  # noqa: E402
from calibration import Applier  # noqa: E402
from calibration.baseline import BaselineTracker  # noqa: E402
from calibration.from_truth import calibration_from_truth  # noqa: E402
from calibration.runtime import CalibratedFrames  # noqa: E402
from sim.footsteps import FootstepCarpet  # noqa: E402
from sim.sensor import CarpetSensor  # noqa: E402

RATE_HZ = 14.0
GOAL_MS = 3.0



def frames(seconds: float = 30.0, seed: int = 0):
    """(calibration from the carpet's truth, counts per frame, times)."""
    sensor = CarpetSensor.random(seed, grid=96)
    cal = calibration_from_truth(sensor, 0.0)
    world = FootstepCarpet(96, 96, people=2, seed=seed)
    out, ts = [], []
    for k in range(int(seconds * RATE_HZ)):
        world(k)
        t = k / RATE_HZ
        out.append(sensor.counts(world.pressure_kpa(), t))
        ts.append(t)
    return cal, float(sensor.temperature_c(0.0)), out, ts


def stats(ms: list[float]) -> dict:
    a = np.asarray(ms)
    return {"median_ms": round(float(np.median(a)), 4), "p99_ms": round(float(np.percentile(a, 99)), 4),
            "mean_ms": round(float(a.mean()), 4), "max_ms": round(float(a.max()), 4), "frames": int(a.size)}


def run_case(make, counts, ts, repeats: int) -> tuple[dict, list[float]]:
    """Time ``fn(counts, t)`` per frame with a fresh ``fn = make()`` per repeat. Each statistic is
    the lowest over the repeats (the machine is shared: other processes only ever add time);
    also returns the per-frame times of the repeat with the lowest median."""
    runs: list[list[float]] = []
    for _ in range(repeats):
        fn = make()
        ms = []
        for c, t in zip(counts, ts):
            t0 = time.perf_counter()
            fn(c, t)
            ms.append((time.perf_counter() - t0) * 1e3)
        runs.append(ms)
    each = [stats(ms) for ms in runs]
    best = {k: min(st[k] for st in each) for k in each[0]}
    return {**best, "repeats": repeats}, runs[int(np.argmin([st["median_ms"] for st in each]))]


def main(repeats: int = 5) -> None:
    try:
        os.sched_setaffinity(0, {sorted(os.sched_getaffinity(0))[0]})  # one core
    except (AttributeError, OSError):
        pass
    cal, temp, counts, ts = frames()
    results: dict[str, dict] = {}

    def applier(crosstalk):
        a = Applier(cal, crosstalk=crosstalk)
        return lambda c, t: a.apply(c, temp)

    results["apply"], _ = run_case(lambda: applier(False), counts, ts, repeats)
    results["apply_crosstalk"], _ = run_case(lambda: applier(True), counts, ts, repeats)

    # baseline tracking alone: accumulate every frame, update once a second
    def tracker():
        tr = BaselineTracker(cal)
        return tr.add

    results["baseline_tracking"], ms = run_case(tracker, counts, ts, repeats)
    every = int(RATE_HZ)  # frames 0, 14, 28, … run the update (time starts at 0, interval 1 s)
    results["baseline_update_once_per_second"] = stats([m for k, m in enumerate(ms) if k % every == 0])

    def full():
        step = CalibratedFrames(cal)
        return lambda c, t: step.process(c, t, temp)

    results["full_step"], _ = run_case(full, counts, ts, repeats)

    scene_note = None
    try:
        from edge.scene import SceneTracker

        seen: list[int] = []

        def with_scene():
            step = CalibratedFrames(cal)
            scene = SceneTracker(96, 96, pitch_m=cal.pitch_m)  # default SceneConfig (online noise estimate)
            seen.clear()

            def both(c, t):
                p, _, masked, _ = step.process(c, t, temp)
                seen.append(len(scene.update(p, t, masks=masked).people))
            return both

        pre = CalibratedFrames(cal)
        calibrated = [pre.process(c, t, temp) for c, t in zip(counts, ts)]

        def scene_only():
            scene = SceneTracker(96, 96, pitch_m=cal.pitch_m)
            by_t = {t: out for t, out in zip(ts, calibrated)}
            return lambda c, t: scene.update(by_t[t].pressure_kpa, t, masks=by_t[t].masked)

        results["scene_update_only"], _ = run_case(scene_only, counts, ts, repeats)
        results["full_step_plus_scene"], _ = run_case(with_scene, counts, ts, repeats)
        results["full_step_plus_scene"].update(goal_ms=GOAL_MS, median_people_tracked=float(np.median(seen[int(2 * RATE_HZ):])))
    except Exception as exc:  # the scene package may still be in progress
        scene_note = f"edge.scene not benchmarked: {type(exc).__name__}: {exc}"

    out = {
        "benchmark": "calibration_runtime", "grid": "96x96", "rate_hz": RATE_HZ,
        "goal": f"calibrate + filter + segment + track ≤ {GOAL_MS} ms per 96×96 frame on one core (issue 5)",
        "frames": "30 s of two people walking (sim.footsteps) on CarpetSensor.random(0), 14 Hz, generated before timing; "
                  "each call timed alone; 5 repeats, each statistic the lowest over the repeats (a shared machine)",
        "command": "python -m bench.calibration_runtime", "date": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "machine": {"platform": platform.platform(), "cpu_model": machine.cpu_model(), "cpu_count": os.cpu_count(),
                    "python": platform.python_version(), "numpy": np.__version__, "threads": 1,
                    "load_average": os.getloadavg()},
        "results": results,
    }
    if scene_note:
        out["note"] = scene_note
    path = Path(__file__).resolve().parent / "results" / "calibration_runtime.json"
    path.write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(results, indent=2))
    if scene_note:
        print(scene_note)


if __name__ == "__main__":
    main()

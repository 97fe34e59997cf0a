"""Sensor-model cost per 96×96 frame on one core (goal ≤ 2 ms), with and without faults and ghosting.

Usage: python bench/sim_sensor.py  → bench/results/sim_sensor.json
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from pathlib import Path

os.environ.setdefault("OMP_NUM_THREADS", "1")
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

import numpy as np  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))
from bench import machine  # noqa: E402
from sim.sensor import CarpetSensor  # noqa: E402


def time_frames(sensor: CarpetSensor, repeats: int = 7, frames: int = 100) -> dict:
    p = np.zeros(sensor.shape)
    p[30:55, 20:30] = 30.0
    p[60:70, 60:66] = 6.0
    for k in range(20):
        sensor.counts(p, k / 14)
    per_frame = []
    for rep in range(repeats):
        t0 = time.perf_counter()
        for k in range(frames):
            sensor.counts(p, 2 + rep * 10 + k / 14)
        per_frame.append((time.perf_counter() - t0) / frames * 1e3)
    return {"ms_per_frame_median": round(float(np.median(per_frame)), 3), "ms_per_frame_min": round(min(per_frame), 3),
            "ms_per_frame_max": round(max(per_frame), 3), "repeats": repeats, "frames_per_repeat": frames}


def main() -> None:
    cases = {
        "default_random_carpet": CarpetSensor.random(0),
        "all_fault_kinds": CarpetSensor.random(0, faults=True, fault_rates={"stuck": 1.0, "noisy": 1.0, "short": 1.0}),
        "floating_readout_ghosting": CarpetSensor.random(0, readout="floating"),
    }
    results = {name: time_frames(s) for name, s in cases.items()}
    out = {
        "benchmark": "sim_sensor", "goal_ms_per_frame": 2.0, "grid": "96x96",
        "command": "python bench/sim_sensor.py", "date": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "machine": {"platform": platform.platform(), "cpu_model": machine.cpu_model(), "cpu_count": os.cpu_count(),
                    "python": platform.python_version(), "numpy": np.__version__, "load_average": os.getloadavg()},
        "results": results,
    }
    path = Path(__file__).resolve().parent / "results" / "sim_sensor.json"
    path.write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(results, indent=2))


if __name__ == "__main__":
    main()

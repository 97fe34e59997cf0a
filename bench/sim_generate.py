"""Dataset generation speed: frames per second on this machine, and the projected time
of a training-size dataset (≥ 100,000 frames, ≥ 12 subjects; goal ≤ 20 min on 2 cores).

Usage: python -m bench.sim_generate [--subjects 12] [--seconds-per-activity 3] [--workers 2]
→ bench/results/sim_generate.json. The dataset is written to a temporary folder and removed.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import sys
import tempfile
import time
from pathlib import Path


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--subjects", type=int, default=12)
    ap.add_argument("--seconds-per-activity", type=float, default=3.0)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--people", default="1..1")
    args = ap.parse_args()
    lo, _, hi = args.people.partition("..")
    os.environ["OMP_NUM_THREADS"] = os.environ["OPENBLAS_NUM_THREADS"] = "1"
    from sim.dataset import Dataset
    from sim.dataset.generate import generate

    tmp = Path(tempfile.mkdtemp(prefix="cavatar-bench-"))
    try:
        t0 = time.monotonic()
        generate(tmp / "ds", subjects=args.subjects, seconds_per_activity=args.seconds_per_activity,
                 people=(int(lo), int(hi or lo)), workers=args.workers, seed=0, progress=False)
        elapsed = time.monotonic() - t0
        ds = Dataset(tmp / "ds")
        frames = len(ds)
        skipped = len(ds.manifest.get("skipped_scenes", []))
        size_mb = sum(f.stat().st_size for f in (tmp / "ds").iterdir()) / 1e6
    finally:
        shutil.rmtree(tmp, ignore_errors=True)
    fps = frames / elapsed
    out = {
        "benchmark": "sim_generate", "goal": "100,000 frames, 12 subjects, in <= 20 min on 2 cores",
        "command": "python -m bench.sim_generate " + " ".join(sys.argv[1:]), "date": time.strftime("%Y-%m-%dT%H:%M:%S%z"),
        "machine": {"platform": platform.platform(), "cpu_count": os.cpu_count(), "python": platform.python_version(),
                    "load_average_at_end": os.getloadavg()},
        "settings": vars(args), "frames": frames, "skipped_scenes": skipped, "elapsed_s": round(elapsed, 1), "frames_per_s": round(fps, 1),
        "dataset_mb": round(size_mb, 1), "mb_per_1000_frames": round(size_mb / frames * 1000, 2),
        "projected_minutes_for_100k_frames": round(100_000 / fps / 60, 1),
        "includes": "process start-up, model loading, motion, posing, contact physics, sensor model, stream faults, compression, hashing",
    }
    path = Path(__file__).resolve().parent / "results" / "sim_generate.json"
    path.write_text(json.dumps(out, indent=2) + "\n")
    print(json.dumps(out, indent=2))


if __name__ == "__main__":
    main()

"""The fall detector's cost in the runtime, side by side: the per-frame pipeline with and without events.

    OMP_NUM_THREADS=1 python bench/falls_events.py [--frames 420]

Frames as in bench/runtime_latency.py (``sim://?people=1&seed=7`` recorded once through the real
protocol, decoded by the runtime's timed reader, then FrameStages on one thread with the shipped
bundle and the seed's true calibration). Each pass runs every frame through FrameStages and, in the
"events" passes, the runtime's EventStage on the SceneFrame it made (body features + the detector);
passes alternate off / on / off / on on fresh state, so both see the same load on a shared machine.
The frame total is decode + FrameStages' frame + events. The goal (issue 16): the runtime stays
≤ 7 ms per frame for one person with events on. Writes bench/results/falls_events.json.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")


ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from bench import machine  # noqa: E402
from bench.runtime_latency import SEED, FrameClock, decode, record, stats  # noqa: E402

GOAL_MS = 7.0


def one_pass(frames, info, bundle, calibration, events: bool) -> list[dict[str, float]]:
    from calibration.runtime import CalibratedFrames
    from edge.runtime.config import RuntimeConfig
    from edge.runtime.counters import Counters
    from edge.runtime.events import EventStage
    from edge.runtime.stages import FrameStages
    from edge.scene import SceneTracker

    cfg = RuntimeConfig()
    clock = FrameClock()
    stages = FrameStages(CalibratedFrames(calibration, info, baseline=cfg.calibration.baseline),
                         SceneTracker(int(info.rows), int(info.cols), calibration.pitch_m, cfg.scene), bundle,
                         device="bench", times=clock, counters=Counters(), heartbeat_s=cfg.runtime.heartbeat_s)
    stage = EventStage(cfg.events, "bench", calibration.pitch_m, clock) if events else None
    out = []
    for frame in frames:
        clock.now = {}
        o = stages.process(frame)
        if stage is not None:
            stage.frame(o, stages.scene_frame, time.time())
        clock.now["people"] = float(o.kind == "people")
        out.append(clock.now)
    return out


def main() -> int:
    from calibration.from_truth import calibration_from_truth
    from edge.infer import ModelBundle
    from edge.runtime.config import default_bundle_path
    from sim.live import live_sensor

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=420)
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "falls_events.json")
    a = ap.parse_args()
    bundle = ModelBundle.load(default_bundle_path(), threads=1)
    calibration = calibration_from_truth(live_sensor(SEED, 96), device_id=f"sim-{SEED}")
    with tempfile.TemporaryDirectory(prefix="cavatar-falls-") as tmp:
        capture = Path(tmp) / "sim-1p.bin"
        record(f"sim://?people=1&seed={SEED}&speed=0", capture, a.frames)
        frames, decode_ms, info = decode(capture)
    one_pass(frames, info, bundle, calibration, True)  # warm-up
    runs = {"off": [], "on": []}
    for mode in ("off", "on", "off", "on"):
        runs[mode] += one_pass(frames, info, bundle, calibration, mode == "on")
    dec = decode_ms * 2
    res = {}
    for mode, per in runs.items():
        totals = [d + f["frame"] + f.get("events", 0.0) for d, f in zip(dec, per)]
        res[mode] = {"frame_total": stats(totals),
                     "frame_total_frames_with_people": stats([t for t, f in zip(totals, per) if f["people"]]),
                     "scene": stats([f["scene"] for f in per if "scene" in f])}
        if mode == "on":
            res[mode]["events"] = stats([f["events"] for f in per if "events" in f])
    added = res["on"]["frame_total"]["median_ms"] - res["off"]["frame_total"]["median_ms"]
    try:
        rev = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True, timeout=10).stdout.strip()
    except OSError:
        rev = None
    out = {"benchmark": "falls_events", "command": "OMP_NUM_THREADS=1 python bench/falls_events.py"
           + ("" if a.frames == 420 else f" --frames {a.frames}"), "git_revision": rev,
           "machine": {**machine.describe(), "omp_num_threads": os.environ.get("OMP_NUM_THREADS")},
           "method": __doc__.split("\n\n", 2)[2].strip().replace("\n", " "),
           "source": f"sim://?people=1&seed={SEED} recorded, {len(frames)} frames",
           "goal_ms_per_frame_one_person": GOAL_MS, "results": res,
           "events_added_median_ms": round(float(added), 3),
           "passed": res["on"]["frame_total"]["median_ms"] <= GOAL_MS}
    out["machine"]["load_average_1_5_15_at_end"] = [round(x, 2) for x in os.getloadavg()]
    a.out.write_text(json.dumps(out, indent=1) + "\n")
    print(f"events off: frame {res['off']['frame_total']['median_ms']} ms median; on: "
          f"{res['on']['frame_total']['median_ms']} ms (events stage {res['on']['events']['median_ms']} / "
          f"p99 {res['on']['events']['p99_ms']} ms); wrote {a.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

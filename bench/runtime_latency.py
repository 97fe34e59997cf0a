"""Per-frame latency of the runtime by stage, on ONE thread, for the shipped model bundle:
decode, calibrate, scene, encoder, head, record, publish, and the frame total against the
71.4 ms frame interval at 14 Hz. Writes bench/results/runtime_latency.json.

    OMP_NUM_THREADS=1 python -m bench.runtime_latency [--bundle DIR] [--frames 420]

Frames come from recordings, so the simulator's cost is not measured: ``sim://?people=P&seed=7``
(P = 1 and 2) is recorded once into a capture file through the real protocol (as `cavatar
record` does); decode is the runtime's own instrumentation (TimedCarpetSource: protocol decoding
+ frame assembly per frame) replaying those bytes; then every frame goes through the runtime's
FrameStages (calibrate → scene → encoder → head → record, the calibration the seed-7 virtual
carpet's true one) and each record is handed to a JSON-lines sink (publish), all in this one
thread; onnxruntime with one intra-op thread (the runtime's default, ``[model] threads``), no
spinning. The recording is run once untimed (warm-up), then timed on fresh state ``--repeats``
times (default 3); the pass with the lowest median frame total is reported, every pass's median
beside it (this shared machine's speed drifts up to 2× between passes). encoder and
head are per frame that ran them (one batched call for all people whose pressure changed; a
still person reuses their result, so some frames run neither); the frame total is per frame:
decode + the pipeline (calibrate … record, as the runtime's "frame" stage: it also holds the
model-input preparation and track book-keeping, "pipeline_other") + publish.

The reader and publisher are threads in `cavatar run`; on a 2-core board they overlap the
pipeline, on one core they add up as here. The goal (issue 7): real time ×10 or better,
≤ 7 ms per frame for one person.
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
from typing import Any

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import numpy as np  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]

from bench import machine  # noqa: E402

SEED = 7
RATE_HZ = 14.0
INTERVAL_MS = 1000.0 / RATE_HZ
GOAL_RTF, GOAL_MS_ONE_PERSON = 10.0, 7.0
STAGES = ("decode", "calibrate", "scene", "encoder", "head", "record", "publish")


class FrameClock:
    """Stands in for the runtime's StageTimes: keeps every stage time of the current frame."""

    def __init__(self) -> None:
        self.now: dict[str, float] = {}

    def add(self, stage: str, ms: float) -> None:
        self.now[stage] = self.now.get(stage, 0.0) + float(ms)


class AllTimes:
    """Stands in for StageTimes in the reader: every value, in order."""

    def __init__(self) -> None:
        self.ms: dict[str, list[float]] = {}

    def add(self, stage: str, ms: float) -> None:
        self.ms.setdefault(stage, []).append(float(ms))


def record(url: str, path: Path, frames: int) -> None:
    """Record ``frames`` whole frames of ``url`` into ``path`` (the bytes as `cavatar record` writes them)."""
    from edge.sources import open_source

    with open(path, "wb") as fh:
        source = open_source(url, record_to=fh, queue_frames=frames + 16)
        source.start()
        try:
            got = 0
            for _ in source.frames(timeout_s=30):
                got += 1
                if got >= frames:
                    break
        finally:
            source.stop()
    if got < frames:
        raise SystemExit(f"only {got} of {frames} frames recorded from {url}")


def decode(path: Path) -> tuple[list, list[float], Any]:
    """Every frame of the capture through the runtime's timed reader; (frames, decode ms per frame, board info)."""
    from edge.runtime.reader import open_timed_source

    times = AllTimes()
    source = open_timed_source(f"replay://{path}?speed=0", times, queue_frames=1 << 20)  # never full: no waiting
    source.start()
    try:
        frames = list(source.frames(timeout_s=10))
    finally:
        source.stop()
    return frames, times.ms["decode"][: len(frames)], source.info


def run_stages(frames: list, info: Any, bundle: Any, calibration: Any, sink: Any | None) -> list[dict[str, float]]:
    """FrameStages over ``frames`` on fresh state; per frame the stage milliseconds (publish when a record came)."""
    from calibration.runtime import CalibratedFrames
    from edge.runtime.config import RuntimeConfig
    from edge.runtime.counters import Counters
    from edge.runtime.stages import FrameStages
    from edge.scene import SceneTracker

    cfg = RuntimeConfig()
    clock, counters = FrameClock(), Counters()
    stages = FrameStages(CalibratedFrames(calibration, info, baseline=cfg.calibration.baseline),
                         SceneTracker(int(info.rows), int(info.cols), calibration.pitch_m, cfg.scene), bundle,
                         device="bench", times=clock, counters=counters, heartbeat_s=cfg.runtime.heartbeat_s)
    out = []
    for frame in frames:
        clock.now = {}
        o = stages.process(frame)
        if o.record is not None and sink is not None:
            t0 = time.perf_counter()
            sink.publish_bodies(o.record)
            clock.now["publish"] = (time.perf_counter() - t0) * 1e3
        clock.now["kind"] = o.kind  # type: ignore[assignment]
        out.append(clock.now)
    out.append(counters.snapshot())  # type: ignore[arg-type]
    return out


def stats(values: list[float]) -> dict[str, Any]:
    if not values:
        return {"median_ms": None, "p99_ms": None, "n": 0}
    a = np.asarray(values)
    return {"median_ms": round(float(np.median(a)), 3), "p99_ms": round(float(np.percentile(a, 99)), 3), "n": len(values)}


def timed_run(capture: Path, people: int, bundle: Any, calibration: Any, tmp: Path) -> tuple[list, dict, list, list]:
    """One timed pass over a recording on fresh state: (per-frame stage ms, counters, frames, frame totals)."""
    from edge.sinks import open_sink

    frames, decode_ms, info = decode(capture)
    sink = open_sink(f"jsonl://{tmp}/bodies-{people}p.jsonl", device="bench")
    try:
        per = run_stages(frames, info, bundle, calibration, sink)
    finally:
        sink.close()
    counters = per.pop()
    for f, d in zip(per, decode_ms):
        f["decode"] = d
    return per, counters, frames, [f["decode"] + f["frame"] + f.get("publish", 0.0) for f in per]


def measure(people: int, frames_n: int, bundle: Any, calibration: Any, tmp: Path, repeats: int = 1) -> dict[str, Any]:
    """The recording's stages and frame total; of ``repeats`` timed passes the one with the lowest median frame
    total (a shared machine's speed drifts from pass to pass; the fastest is the least disturbed)."""
    capture = tmp / f"sim-{people}p.bin"
    record(f"sim://?people={people}&seed={SEED}&speed=0", capture, frames_n)
    frames, _, info = decode(capture)
    run_stages(frames, info, bundle, calibration, None)  # warm-up
    runs = [timed_run(capture, people, bundle, calibration, tmp) for _ in range(max(1, repeats))]
    per, counters, frames, totals = min(runs, key=lambda r: float(np.median(r[3])))
    with_people = [t for t, f in zip(totals, per) if f["kind"] == "people"]
    med, p99 = float(np.median(totals)), float(np.percentile(totals, 99))
    return {
        "people": people, "source": f"sim://?people={people}&seed={SEED} recorded, {len(frames)} frames, "
                                    f"{capture.stat().st_size} bytes",
        "stages": {s: stats([f[s] for f in per if s in f]) for s in STAGES},
        "pipeline_calibrate_to_record": stats([f["frame"] for f in per]),
        "pipeline_other": stats([f["frame"] - sum(f.get(s, 0.0) for s in STAGES[1:6]) for f in per]),
        "frame_total": stats(totals), "frame_total_frames_with_people": stats(with_people),
        "frame_total_median_ms_per_repeat": [round(float(np.median(r[3])), 3) for r in runs],
        "interval_ms": round(INTERVAL_MS, 2),
        "real_time_factor": {"median": round(INTERVAL_MS / med, 1), "p99": round(INTERVAL_MS / p99, 1)},
        "frames_over_interval": int(sum(t > INTERVAL_MS for t in totals)),
        "work": {k: counters.get(k, 0) for k in ("frames_people", "frames_empty", "frames_unconfirmed", "person_frames",
                                                 "encoder_runs", "head_runs", "still_reuses")},
    }


def _shown(path: Path) -> str:
    """A path inside the repository relative to it (the results are committed), others as given."""
    try:
        return str(path.resolve().relative_to(ROOT))
    except ValueError:
        return str(path)


def main() -> int:
    from calibration.from_truth import calibration_from_truth
    from edge.infer import ModelBundle
    from edge.runtime.config import default_bundle_path
    from sim.live import live_sensor

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--bundle", type=Path, default=default_bundle_path(), help="model bundle (default: the shipped one)")
    ap.add_argument("--frames", type=int, default=420, help="frames per recording (default 420 = 30 s, three scenes)")
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "runtime_latency.json")
    ap.add_argument("--repeats", type=int, default=3, help="timed passes per recording; the fastest is reported (default 3)")
    args = ap.parse_args()
    bundle = ModelBundle.load(args.bundle, threads=1)
    calibration = calibration_from_truth(live_sensor(SEED, 96), device_id=f"sim-{SEED}")
    with tempfile.TemporaryDirectory(prefix="cavatar-latency-") as tmp:
        results = [measure(p, args.frames, bundle, calibration, Path(tmp), args.repeats) for p in (1, 2)]
    try:
        rev = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True, timeout=10).stdout.strip()
    except OSError:
        rev = None
    m = bundle.manifest
    one = results[0]
    out = {
        "benchmark": "runtime_latency",
        "command": "OMP_NUM_THREADS=1 python -m bench.runtime_latency"
                   + ("" if args.bundle.resolve() == default_bundle_path().resolve() else f" --bundle {args.bundle}")
                   + ("" if args.frames == 420 else f" --frames {args.frames}")
                   + ("" if args.repeats == 3 else f" --repeats {args.repeats}"),
        "git_revision": rev,
        "machine": {**machine.describe(), "omp_num_threads": os.environ.get("OMP_NUM_THREADS"), "onnxruntime_intra_op": 1},
        "bundle": {"path": _shown(args.bundle), "name": m.get("name"), "version": bundle.version, "created": m.get("created"),
                   "export_git_revision": m.get("git_revision"), "quantization": m.get("quantization")},
        "method": __doc__.split("\n\n", 2)[2].strip().replace("\n", " "),
        "goal": {"real_time_factor": GOAL_RTF, "ms_per_frame_one_person": GOAL_MS_ONE_PERSON},
        "results": results,
        "passed": one["frame_total"]["median_ms"] <= GOAL_MS_ONE_PERSON and one["real_time_factor"]["median"] >= GOAL_RTF,
    }
    out["machine"]["load_average_1_5_15_at_end"] = [round(x, 2) for x in os.getloadavg()]
    args.out.write_text(json.dumps(out, indent=1) + "\n")
    for r in results:
        print(f"{r['people']} person(s): " + ", ".join(f"{s} {v['median_ms']}/{v['p99_ms']}" for s, v in r["stages"].items())
              + f" ms (median/p99); frame total {r['frame_total']['median_ms']}/{r['frame_total']['p99_ms']} ms, "
              f"real time ×{r['real_time_factor']['median']} (p99 ×{r['real_time_factor']['p99']})")
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

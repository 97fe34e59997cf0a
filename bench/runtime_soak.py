"""Soak of the runtime: many frames as fast as the pipeline takes them, memory and queues watched.
Writes bench/results/runtime_soak.json.

    OMP_NUM_THREADS=1 python -m bench.runtime_soak [--frames 50000]

The in-process :class:`edge.runtime.Runtime` (pipeline thread, publisher thread, monitor
writing the status file every second) runs on frames of the virtual carpet
(``sim://?people=1&seed=7``, 300 frames made once before timing, played forwards then
backwards so the person never jumps; each 10-s scene of the simulator is a new place and
activity, so tracks start and end) into a rotated JSON-lines file. The source is the real
:class:`~edge.runtime.reader.TimedCarpetSource` (handshake with the virtual board, its bounded
frame queue, not paced: the reader waits for the pipeline, nothing is dropped) whose reading
loop hands out those pre-decoded frames with increasing seq and time instead of decoding
bytes, so the soak measures the runtime, not the simulator or the decoder
(bench/decoder_throughput.py measures that).

Measured: resident memory (VmRSS) after WARMUP frames and at the end, both queues' depths
after every frame against their bounds, and records written (lines in every rotated file)
against the runtime's own count. tests/edge/runtime_integration/test_integration_soak.py runs
the same function on 5,000 frames with the same assertions.
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

ROOT = Path(__file__).resolve().parents[1]

from edge.frames import RawFrame  # noqa: E402
from edge.runtime.reader import TimedCarpetSource  # noqa: E402

SEED = 7
PEOPLE = 1
PREMADE = 300
RATE_HZ = 14.0
WARMUP = 2000
GOALS = {"rss_growth_mb": 10.0}


class CyclingSource(TimedCarpetSource):
    """The real source (handshake, bounded queue, frames(), stop) whose reader loop puts pre-made frames
    ``frames[k]`` (k = 0, 1, …, ping-pong over the list) with frame seq k and time k / rate."""

    def __init__(self, link: Any, counts: list, **kwargs: Any) -> None:
        super().__init__(link, speed=0.0, **kwargs)
        self.counts = counts

    def _run(self) -> None:
        n = len(self.counts)
        period = 2 * n - 2
        k = 0
        while not self._stop.is_set():
            j = k % period
            counts = self.counts[j if j < n else period - j].copy()
            self._put(RawFrame(counts, frame_seq=k, index=k, t_s=k / RATE_HZ, host_time_s=time.time()), block=True)
            k += 1


def rss_kb() -> int:
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise RuntimeError("no VmRSS in /proc/self/status")


def premade_counts(n: int = PREMADE, people: int = PEOPLE) -> list:
    from sim.live import LiveCarpet

    carpet = LiveCarpet(96, 96, people, SEED)
    return [carpet(k) for k in range(n)]


def soak(frames: int, out: Path, calibration: Path, counts: list, warmup: int = WARMUP,
         rotate_mb: float = 1.0) -> dict[str, Any]:
    """Run ``frames`` frames through the runtime into ``out``; the measurements (see the module docstring)."""
    from edge.runtime import Runtime, RuntimeConfig
    from edge.sources import open_link

    cfg = RuntimeConfig().with_overrides(
        source=f"sim://?people=0&seed={SEED}&speed=0", calibration=str(calibration),
        sinks=[f"jsonl://{out}/bodies.jsonl?rotate_mb={rotate_mb:g}&keep=0"], status_file=str(out / "status.json"))
    rt = Runtime(cfg, say=lambda text: None)
    # the handshake is the virtual board's own (so the calibration of sim://?seed=7 fits); then pre-made frames
    rt.source = CyclingSource(open_link(cfg.source.url), counts, times=rt.times, queue_frames=cfg.source.queue_frames)
    seen = {"frames": 0, "max_frames_queue": 0, "max_records_queue": 0, "rss_kb": {}}
    marks = sorted({warmup, frames} | set(range(warmup, frames, max(1, (frames - warmup) // 20))))

    def watch(outcome: Any) -> None:  # the pipeline thread, after every frame
        seen["frames"] += 1
        d = rt.queue_depths()
        seen["frames_bound"], seen["records_bound"] = d["frames"][1], d["records"][1]
        seen["max_frames_queue"] = max(seen["max_frames_queue"], d["frames"][0])
        seen["max_records_queue"] = max(seen["max_records_queue"], d["records"][0])
        if seen["frames"] in marks:
            seen["rss_kb"][seen["frames"]] = rss_kb()
            if seen["frames"] == warmup:
                seen["t_warm"] = time.perf_counter()

    rt.on_outcome.append(watch)
    rt.setup()
    rss_start_kb = rss_kb()
    t0 = time.perf_counter()
    final = rt.run_for(frames=frames, timeout_s=3600)
    seconds = time.perf_counter() - t0
    rss_end_kb = rss_kb()
    files = sorted(out.glob("bodies*.jsonl"))
    lines = 0
    for f in files:
        with open(f, "rb") as fh:
            lines += sum(1 for _ in fh)
    pub, fr, work = final["publish"], final["frames"], final["work"]
    sink = next(iter(pub["sinks"].values()))
    curve = seen["rss_kb"]
    at_warm = curve.get(warmup, rss_start_kb)
    at_end = curve.get(frames, rss_end_kb)
    return {
        "frames": fr["frames_in"], "warmup_frames": warmup, "seconds": round(seconds, 2),
        "frames_per_s": round(fr["frames_in"] / seconds, 1),
        "frames_per_s_after_warmup": round((fr["frames_in"] - warmup) / (time.perf_counter() - seen.get("t_warm", t0)), 1)
        if "t_warm" in seen else None,
        "rss_mb": {"before_start": round(rss_start_kb / 1024, 1), "after_warmup": round(at_warm / 1024, 1),
                   "at_last_frame": round(at_end / 1024, 1), "after_stop": round(rss_end_kb / 1024, 1),
                   "growth_after_warmup": round((at_end - at_warm) / 1024, 2),
                   "curve": {str(k): round(v / 1024, 1) for k, v in sorted(curve.items())}},
        "queues": {"frames_max": seen["max_frames_queue"], "frames_bound": seen.get("frames_bound"),
                   "records_max": seen["max_records_queue"], "records_bound": seen.get("records_bound")},
        "records": {"counted": pub["records"] + pub["heartbeats"], "published": pub["published"],
                    "queue_dropped": pub["queue_dropped"], "sink_sent": sink.get("sent"), "sink_dropped": sink.get("dropped"),
                    "sink_errors": pub["sink_errors"], "lines_written": lines, "files": len(files)},
        "work": {"frames_people": fr["frames_people"], "frames_failed": fr["frames_failed"],
                 "frames_invalid": fr["frames_invalid"], "encoder_runs": work["encoder_runs"],
                 "still_reuses": work["still_reuses"], "tracks_started": work["tracks_started"],
                 "tracks_freed": work["tracks_freed"], "tracks_open": work["tracks_open"]},
        "dropped_slow_consumer": final["source"]["queue"].get("dropped_slow_consumer", 0),
        "state": final["state"],
        "stages_ms_last_window": {k: final["stages_ms"][k] for k in ("frame", "encoder", "head", "publish")},
    }


def main() -> int:
    from bench import machine
    from calibration.from_truth import calibration_from_truth
    from sim.live import live_sensor

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--frames", type=int, default=50_000)
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "runtime_soak.json")
    args = ap.parse_args()
    counts = premade_counts()
    with tempfile.TemporaryDirectory(prefix="cavatar-soak-") as tmp:
        tmp = Path(tmp)
        cal = tmp / f"calibration-sim-{SEED}.npz"
        calibration_from_truth(live_sensor(SEED, 96), device_id=f"sim-{SEED}").save(cal)
        out = tmp / "out"
        out.mkdir()
        r = soak(args.frames, out, cal, counts)
    try:
        rev = subprocess.run(["git", "rev-parse", "HEAD"], cwd=ROOT, capture_output=True, text=True, timeout=10).stdout.strip()
    except OSError:
        rev = None
    result = {
        "benchmark": "runtime_soak",
        "command": "OMP_NUM_THREADS=1 python -m bench.runtime_soak"
                   + ("" if args.frames == 50_000 else f" --frames {args.frames}"),
        "git_revision": rev,
        "machine": machine.describe(),
        "method": __doc__.split("\n\n", 2)[2].strip().replace("\n", " "),
        "goals": GOALS,
        **r,
        "passed": {"rss": r["rss_mb"]["growth_after_warmup"] < GOALS["rss_growth_mb"],
                   "queues": r["queues"]["frames_max"] <= r["queues"]["frames_bound"]
                   and r["queues"]["records_max"] <= r["queues"]["records_bound"],
                   "records": r["records"]["lines_written"] == r["records"]["counted"] == r["records"]["published"]},
    }
    args.out.write_text(json.dumps(result, indent=1) + "\n")
    print(f"{r['frames']} frames in {r['seconds']} s ({r['frames_per_s']} /s); RSS {r['rss_mb']['after_warmup']} → "
          f"{r['rss_mb']['at_last_frame']} MB after the {WARMUP}-frame warm-up (growth {r['rss_mb']['growth_after_warmup']} MB); "
          f"queues max {r['queues']}; records {r['records']}")
    print(f"wrote {args.out}")
    return 0 if all(result["passed"].values()) else 1


if __name__ == "__main__":
    sys.exit(main())

"""Decoder throughput on one core, as a multiple of the carpet's real-time byte rate.

A realistic device stream — INFO, then per frame 96 ROWs + FRAME_END, a STATUS once a
second; 96×96 samples near mid-scale with noise, 14 Hz — is encoded once per packing
(packed12, u8, u16) and fed to a fresh ``StreamDecoder`` in fixed-size reads (4096 bytes
by default, what a serial or USB read typically returns), timed over several runs.

    python bench/decoder_throughput.py                 # writes bench/results/decoder_throughput.json
    python bench/decoder_throughput.py --profile       # and prints where the time goes (cProfile)

"× real time" = the stream's duration at 14 Hz / the CPU time this thread spent decoding it
(``time.thread_time``: the decoder is single-threaded, so this is one core's work, and time
the scheduler gives to other processes on a busy machine does not count). Wall-clock
multiples are reported beside it. The goal is ≥ 50×.
"""

from __future__ import annotations

import argparse
import cProfile
import datetime as dt
import io
import json
import os
import platform
import pstats
import statistics
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from firmware_protocol import codec  # noqa: E402

GOAL = 50.0
FULL_SCALE = {"u8": 255, "packed12": 4095, "u16": 4095}  # u16 carries a 12-bit ADC, as the default board


def carpet_stream(packing: str, seconds: float, rows: int = 96, cols: int = 96, rate_hz: float = 14.0,
                  seed: int = 1) -> tuple[bytes, float, int]:
    """(wire bytes, duration in s, packets) of ``seconds`` of streaming."""
    rng = np.random.default_rng(seed)
    code = codec.PACKING[packing]
    full = FULL_SCALE[packing]
    frames = round(seconds * rate_hz)
    period_us = round(1e6 / rate_hz)
    row_us = period_us * 8 // (10 * rows)  # the scan takes 80 % of the period
    seq = 0
    out = [codec.encode(codec.Info(seq, codec.PROTOCOL_VERSION, codec.DEFINITION_HASH, 1, 0, 0, "bench-carpet", rows, cols,
                                   1, 1, 12, code, -1, round(rate_hz * 1000), 3))]
    seq += 1
    t0 = 3_000_000_000  # the device clock wraps during a long run
    for f in range(frames):
        vals = np.clip(rng.normal(full / 2, full / 100, size=(rows, cols)).round(), 0, full).astype(np.uint16)
        t_frame = (t0 + f * period_us) & 0xFFFFFFFF
        for r in range(rows):
            out.append(codec.encode(codec.make_row(seq, f, (t_frame + r * row_us) & 0xFFFFFFFF, r, vals[r].tolist(), code)))
            seq += 1
        scan = (rows - 1) * row_us
        crc = codec.frame_crc32([vals.astype("<u2").tobytes()])
        out.append(codec.encode(codec.FrameEnd(seq & 0xFFFF, f, (t_frame + scan) & 0xFFFFFFFF, rows, scan, crc)))
        seq += 1
        if f % round(rate_hz) == 0:
            out.append(codec.encode(codec.Status(seq & 0xFFFF, t_frame, f // 14, f, 0, 0, 0, 0, 0, 2315, 65535)))
            seq += 1
        seq &= 0xFFFF
    return b"".join(out), frames / rate_hz, len(out)


def decode_once(chunks: list[bytes]) -> tuple[float, float, codec.StreamDecoder]:
    """(CPU seconds of this thread, wall seconds, decoder) for one pass over ``chunks``."""
    dec = codec.StreamDecoder()
    feed = dec.feed
    c0, w0 = time.thread_time(), time.perf_counter()
    for c in chunks:
        feed(c)
    return time.thread_time() - c0, time.perf_counter() - w0, dec


def measure(packing: str, seconds: float, chunk: int, repeats: int) -> dict:
    data, duration, n_packets = carpet_stream(packing, seconds)
    chunks = [data[i : i + chunk] for i in range(0, len(data), chunk)]
    *_, dec = decode_once(chunks)  # warm-up, and a correctness check
    assert dec.stats.packets == n_packets and not dec.stats.dropped and dec.stats.missed == 0, dec.stats
    rate = len(data) / duration
    runs = [decode_once(chunks)[:2] for _ in range(repeats)]
    cpu, wall = [r[0] for r in runs], [r[1] for r in runs]
    multiples = sorted(duration / t for t in cpu)
    wall_multiples = sorted(duration / t for t in wall)
    med_t = statistics.median(cpu)
    return {
        "packing": packing,
        "chunk_bytes": chunk,
        "stream_seconds": duration,
        "stream_bytes": len(data),
        "packets": n_packets,
        "real_time_bytes_per_s": round(rate),
        "decode_cpu_s": {"median": round(med_t, 4), "min": round(min(cpu), 4), "max": round(max(cpu), 4)},
        "decode_wall_s": {"median": round(statistics.median(wall), 4), "min": round(min(wall), 4), "max": round(max(wall), 4)},
        "decoder_bytes_per_s_median": round(len(data) / med_t),
        "packets_per_s_median": round(n_packets / med_t),
        "us_per_packet_median": round(1e6 * med_t / n_packets, 2),
        "x_real_time": {
            "median": round(statistics.median(multiples), 1),
            "min": round(multiples[0], 1),
            "max": round(multiples[-1], 1),
            "iqr": round(float(np.percentile(multiples, 75) - np.percentile(multiples, 25)), 1),
            "runs": [round(m, 1) for m in multiples],
        },
        "x_real_time_wall": {
            "median": round(statistics.median(wall_multiples), 1),
            "min": round(wall_multiples[0], 1),
            "max": round(wall_multiples[-1], 1),
        },
        "meets_goal": statistics.median(multiples) >= GOAL,
    }


def machine() -> dict:
    cpu = "unknown"
    try:
        cpu = next(line.split(":", 1)[1].strip() for line in open("/proc/cpuinfo") if line.startswith("model name"))
    except (OSError, StopIteration):
        pass
    return {
        "platform": platform.platform(),
        "machine": platform.machine(),
        "cpu_model": cpu,
        "cpu_count": os.cpu_count(),
        "python": platform.python_version(),
        "python_implementation": platform.python_implementation(),
        "numpy": np.__version__,
        "load_average_1_5_15_min": [round(x, 2) for x in os.getloadavg()] if hasattr(os, "getloadavg") else None,
    }


def pin_to_one_core() -> int | None:
    """Run on one core (the decoder is single-threaded; pinning steadies the numbers)."""
    if not hasattr(os, "sched_setaffinity"):
        return None
    core = max(os.sched_getaffinity(0))
    os.sched_setaffinity(0, {core})
    return core


def profile(packing: str, seconds: float, chunk: int, top: int = 15) -> str:
    data, _, _ = carpet_stream(packing, seconds)
    chunks = [data[i : i + chunk] for i in range(0, len(data), chunk)]
    prof = cProfile.Profile()
    prof.enable()
    decode_once(chunks)
    prof.disable()
    buf = io.StringIO()
    pstats.Stats(prof, stream=buf).sort_stats("tottime").print_stats(top)
    return buf.getvalue()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seconds", type=float, default=10.0, help="seconds of carpet stream per run (default 10 s = 140 frames)")
    ap.add_argument("--repeats", type=int, default=9, help="timed runs per case (default 9)")
    ap.add_argument("--chunk", type=int, default=4096, help="bytes per feed() call (default 4096)")
    ap.add_argument("--packings", default="packed12,u8,u16", help="comma-separated (default packed12,u8,u16)")
    ap.add_argument("--extra-chunk", type=int, default=64,
                    help="also time packed12 in reads of this size (0: skip; default 64, one USB full-speed packet)")
    ap.add_argument("--out", type=Path, default=ROOT / "bench" / "results" / "decoder_throughput.json")
    ap.add_argument("--profile", action="store_true", help="print a cProfile of one packed12 run")
    ap.add_argument("--pin", action="store_true", help="pin the process to one core (os.sched_setaffinity)")
    args = ap.parse_args(argv)

    core = pin_to_one_core() if args.pin else None
    cases = [(p, args.chunk) for p in args.packings.split(",")]
    if args.extra_chunk:
        cases.append(("packed12", args.extra_chunk))
    results = []
    for packing, chunk in cases:
        r = measure(packing, args.seconds, chunk, args.repeats)
        results.append(r)
        x = r["x_real_time"]
        print(
            f"{packing:>8} reads of {chunk:>5} B: {x['median']:6.1f}× real time (min {x['min']}, max {x['max']}; "
            f"wall-clock median {r['x_real_time_wall']['median']}×), "
            f"{r['decoder_bytes_per_s_median'] / 1e6:.2f} MB/s, {r['us_per_packet_median']} µs/packet, "
            f"real time {r['real_time_bytes_per_s']:,} B/s"
        )
    report = {
        "benchmark": "decoder_throughput",
        "goal_x_real_time": GOAL,
        "command": " ".join(["python", "bench/decoder_throughput.py", *(argv if argv is not None else sys.argv[1:])]),
        "date": dt.datetime.now(dt.timezone.utc).isoformat(timespec="seconds"),
        "machine": {**machine(), "pinned_to_core": core},
        "timing": "x_real_time = stream duration / CPU time of the decoding thread (time.thread_time); "
                  "x_real_time_wall uses wall-clock time",
        "stream": "INFO, then per frame 96 ROWs (96 samples, mid-scale ± 1 % noise) + FRAME_END, STATUS once a second; 96×96 at 14 Hz",
        "results": results,
    }
    args.out.parent.mkdir(parents=True, exist_ok=True)
    args.out.write_text(json.dumps(report, indent=2, ensure_ascii=False) + "\n", encoding="utf-8")
    print(f"wrote {args.out.relative_to(ROOT) if args.out.is_relative_to(ROOT) else args.out}")
    if args.profile:
        print(profile("packed12", args.seconds, args.chunk))
    return 0 if all(r["meets_goal"] for r in results if r["chunk_bytes"] == args.chunk) else 1


if __name__ == "__main__":
    sys.exit(main())

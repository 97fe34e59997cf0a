"""`cavatar inspect`: what a capture holds — INFO, frames, rate, error counters."""

from __future__ import annotations

import argparse
import json

import numpy as np

from edge.cli import CliError, command_name


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        command_name(__name__),
        help="summarise a capture: device INFO, frame count, rate, error counters",
        description="Decode a capture written by `cavatar record` as fast as possible and summarise it.",
    )
    p.add_argument("capture", help="capture file")
    p.add_argument("--json", action="store_true", help="print the summary as JSON")
    p.set_defaults(func=run)


def summarise(path: str) -> dict:
    from edge.sources import CarpetSource, SourceError
    from edge.sources.replay import ReplayLink

    source = CarpetSource(ReplayLink(path), speed=0, queue_frames=64)
    try:
        source.start()
    except SourceError as exc:
        raise CliError(str(exc)) from None
    t_s, seqs, mins, maxs = [], [], [], []
    for frame in source.frames():
        t_s.append(frame.t_s)
        seqs.append(frame.frame_seq)
        mins.append(int(frame.counts.min()))
        maxs.append(int(frame.counts.max()))
    source.stop()
    info = source.info
    rate = (len(t_s) - 1) / (t_s[-1] - t_s[0]) if len(t_s) > 1 and t_s[-1] > t_s[0] else None
    return {
        "file": path,
        "info": {f.name: getattr(info, f.name) for f in info.DEF.fields},
        "frames": len(t_s),
        "first_frame_seq": seqs[0] if seqs else None,
        "last_frame_seq": seqs[-1] if seqs else None,
        "duration_s": round(t_s[-1] - t_s[0], 4) if t_s else 0.0,
        "rate_hz": round(rate, 3) if rate else None,
        "counts_range": [min(mins), max(maxs)] if mins else None,
        "frame_interval_ms_p50_p99": (
            [round(float(x), 3) for x in np.percentile(np.diff(t_s) * 1e3, [50, 99])] if len(t_s) > 2 else None
        ),
        "counters": source.stats(),
    }


def run(args: argparse.Namespace) -> int:
    summary = summarise(args.capture)
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    info = summary["info"]
    print(f"{summary['file']}")
    print(
        f"  device {info['device_id']!r} firmware {info['fw_major']}.{info['fw_minor']}.{info['fw_patch']}, "
        f"protocol v{info['protocol_version']}, {info['rows']}x{info['cols']} ({info['tile_rows']}x{info['tile_cols']} tiles), "
        f"{info['adc_bits']}-bit, sign {info['sign']:+d}, nominal {info['rate_mhz'] / 1000:g} Hz"
    )
    print(f"  frames {summary['frames']} over {summary['duration_s']} s, measured rate {summary['rate_hz']} Hz, "
          f"interval p50/p99 {summary['frame_interval_ms_p50_p99']} ms, counts {summary['counts_range']}")
    c = summary["counters"]
    print(f"  decoder: {c['decoder']['packets']} packets, dropped {c['decoder']['dropped'] or 0}, missed {c['decoder']['missed']}")
    print(f"  frames: {c.get('frames', {})}")
    if c["source"].get("board_mismatch"):  # another board's INFO in the capture: its frames were held back
        print(f"  another board answered {c['source']['board_mismatch']} time(s), "
              f"{c['source'].get('packets_board_mismatch', 0)} of its packets not used"
              + (f"; at the end: {c['board_mismatch']}" if c.get("board_mismatch") else ""))
    return 0

"""`cavatar stream`: show frames arriving from a source, with a one-line summary per second."""

from __future__ import annotations

import argparse
import time

import numpy as np

from edge.cli import CliError, command_name


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        command_name(__name__),
        help="read frames from a source and print what arrives, once a second",
        description="Open a source, stream frames through the protocol decoder and frame assembly, "
        "and print a summary each second: frame rate, active sensels, error counters.",
    )
    p.add_argument("--source", default="sim://?people=2&seed=7", help="source URL (default: the virtual carpet)")
    p.add_argument("--seconds", type=float, default=10.0, help="stop after this long (default 10; 0 = until Ctrl-C)")
    p.set_defaults(func=run)


def active_sensels(counts: np.ndarray) -> int:
    """Sensels far from the frame's typical reading (uncalibrated: a rough sign of load)."""
    c = counts.astype(np.float32)
    med = np.median(c)
    spread = 1.4826 * np.median(np.abs(c - med))
    return int((np.abs(c - med) > max(40.0, 8.0 * spread)).sum())


def run(args: argparse.Namespace) -> int:
    from edge.sources import SourceError, open_source

    try:
        source = open_source(args.source)
        source.start()
    except (SourceError, ValueError) as exc:
        raise CliError(str(exc)) from None
    info = source.info
    print(f"{args.source}: device {info.device_id!r}, {info.rows}x{info.cols}, {info.adc_bits}-bit, "
          f"nominal {info.rate_mhz / 1000:g} Hz")
    start = last = time.monotonic()
    n, n_total, frame = 0, 0, None
    try:
        for frame in source.frames(timeout_s=10.0):
            n += 1
            n_total += 1
            now = time.monotonic()
            if now - last >= 1.0:
                loaded = active_sensels(frame.counts)
                st = source.stats()
                dropped = st["decoder"]["dropped_total"]
                torn = st["frames"].get("torn_dropped", 0) + st["frames"].get("crc_mismatch", 0)
                print(f"t={frame.t_s:6.1f}s seq={frame.frame_seq:<6d} {n / (now - last):5.1f} fps  "
                      f"active sensels {loaded:4d}  packets dropped {dropped}  frames lost {torn}")
                n, last = 0, now
            if args.seconds and now - start >= args.seconds:
                break
    except KeyboardInterrupt:
        pass
    finally:
        source.stop()
    if frame is None:
        raise CliError(f"no frame arrived from {args.source}")
    elapsed = time.monotonic() - start
    st = source.stats()
    dec, fr = st["decoder"], st.get("frames", {})
    print(f"{n_total} frames in {elapsed:.1f} s ({n_total / elapsed:.1f} fps)")
    print(f"  decoder: {dec['packets']} packets, {dec['bytes_in']} bytes, dropped {dec['dropped'] or 0}, missed {dec['missed']}")
    print(f"  frames: torn {fr.get('torn_dropped', 0)}, crc mismatch {fr.get('crc_mismatch', 0)}, "
          f"missed {fr.get('missed_frames', 0)}, duplicate {fr.get('duplicate_frames', 0)}")
    board = st.get("board_status")
    if board:
        temp = "none" if board["temperature_cdeg"] == -32768 else f"{board['temperature_cdeg'] / 100:.1f} °C"
        print(f"  board: scanned {board['frames_scanned']}, dropped {board['frames_dropped']}, temperature {temp}")
    return 0

"""Helpers for building wire packets of whole frames in tests (not a test module)."""

from __future__ import annotations

import zlib

import numpy as np

from firmware_protocol import codec


def frame_packets(counts: np.ndarray, frame_seq: int, t_us: int, packing: int, seq0: int = 0,
                  skip_rows=(), crc_override=None, row_dt_us: int = 500) -> list:
    """ROW packets for every row (except ``skip_rows``) and the FRAME_END, of a (rows, cols) frame."""
    rows, cols = counts.shape
    pkts, seq = [], seq0
    for r in range(rows):
        if r in skip_rows:
            continue
        pkts.append(codec.make_row(seq & 0xFFFF, frame_seq, (t_us + r * row_dt_us) % 2**32, r, counts[r].tolist(), packing))
        seq += 1
    crc = zlib.crc32(counts.astype("<u2").tobytes()) if crc_override is None else crc_override
    pkts.append(codec.FrameEnd(seq & 0xFFFF, frame_seq, (t_us + (rows - 1) * row_dt_us) % 2**32, rows - len(skip_rows),
                               (rows - 1) * row_dt_us, crc))
    return pkts


def info(rows: int = 8, cols: int = 6, packing: int = 1, bits: int = 12, rate_hz: float = 14.0, device_id: str = "test-01"):
    return codec.Info(0, codec.PROTOCOL_VERSION, codec.DEFINITION_HASH, 1, 2, 3, device_id, rows, cols, 1, 1, bits,
                      packing, -1, int(rate_hz * 1000), 0)

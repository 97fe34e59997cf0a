"""What a virtual board scans and puts on the wire: frame rows, the frame being sent, packet bytes.

A frame source is ``frames(frame_index) -> rows`` (each row an iterable of int samples, a
numpy row will do); :func:`scan_rows` checks its shape and clamps it to the ADC range.
:func:`unloaded_frame` is the default source, an empty carpet.
"""

from __future__ import annotations

import binascii
import dataclasses
import random
import sys
from array import array
from typing import Any, Callable, Iterable

from firmware_protocol import cobs, codec

FrameSource = Callable[[int], Iterable[Iterable[int]]]


@dataclasses.dataclass
class FrameInFlight:
    """A frame being sent row by row."""

    index: int
    seq: int
    t0_s: float
    rows: list  # list of rows, each a list of int samples
    crc32: int
    missing: frozenset
    duplicate: bool
    next_row: int = 0
    t_us_first: int = 0
    sent: list = dataclasses.field(default_factory=list)  # packets, for duplicate_next_frame


def scan_rows(frames: FrameSource, index: int, rows: int, cols: int, full_scale: int) -> list[list[int]]:
    """Frame ``index`` of ``frames`` as ``rows`` lists of ``cols`` ints in 0..full_scale; ValueError on a wrong shape."""
    data = frames(index)
    out = []
    for r, row in enumerate(data):
        vals = row.tolist() if hasattr(row, "tolist") else list(row)
        if len(vals) != cols:
            raise ValueError(f"frames({index}) row {r} has {len(vals)} samples; the board has {cols} columns")
        if vals and not isinstance(vals[0], int):
            vals = [int(v) for v in vals]
        if vals and (min(vals) < 0 or max(vals) > full_scale):
            fs = full_scale
            vals = [0 if v < 0 else fs if v > fs else v for v in vals]
        out.append(vals)
    if len(out) != rows:
        raise ValueError(f"frames({index}) gave {len(out)} rows; the board has {rows} rows of {cols}")
    return out


def u16le(vals: list[int]) -> bytes:
    """Samples as u16 little-endian bytes (what FRAME_END's CRC-32 covers)."""
    a = array("H", vals)
    if sys.byteorder == "big":
        a.byteswap()
    return a.tobytes()


def unloaded_frame(index: int, *, seed: int, adc_bits: int, rows: int, cols: int) -> list[list[int]]:
    """Mid-scale with ±3 counts of seeded noise: an unloaded carpet."""
    rng = random.Random(seed * 1_000_003 + index)
    mid = 1 << (adc_bits - 1)
    return [[mid + b % 7 - 3 for b in rng.randbytes(cols)] for _ in range(rows)]


def packet_wire_bytes(pkt: Any, definition_hash: int) -> bytes:
    """``pkt`` framed for the wire by a board of ``definition_hash`` (another definition seeds its CRC differently)."""
    if definition_hash == codec.DEFINITION_HASH or pkt.DEF.seed == "fixed":
        return codec.encode(pkt)
    body = codec.pack(pkt)[:-2]
    crc = binascii.crc_hqx(body, definition_hash)
    return cobs.encode(body + crc.to_bytes(2, "little")) + b"\x00"

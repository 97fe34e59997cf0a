"""Samples in a ROW: the three packings (u8, packed12, u16) and FRAME_END's CRC-32 over a frame.

packed12 puts two 12-bit samples in three bytes: ``a`` low byte, ``a`` high nibble with
``b`` low nibble, ``b`` high byte; an odd last sample takes two bytes.
"""

from __future__ import annotations

import struct
from typing import Any, Iterable

from firmware_protocol.packets import PACKING, PACKING_NAMES, Row


def packed_size(count: int, packing: int) -> int:
    """Bytes taken by ``count`` samples in ``packing`` (ValueError for an unknown packing)."""
    if packing == PACKING["u8"]:
        return count
    if packing == PACKING["packed12"]:
        return (3 * count + 1) // 2
    if packing == PACKING["u16"]:
        return 2 * count
    raise ValueError(f"unknown packing code {packing}; known: {PACKING}")


def pack_samples(values: Iterable[int], packing: int) -> bytes:
    """Lay out samples for a ROW. ValueError when a sample does not fit the packing."""
    vals = [int(v) for v in values]
    limit = {PACKING["u8"]: 0xFF, PACKING["packed12"]: 0xFFF, PACKING["u16"]: 0xFFFF}.get(packing)
    if limit is None:
        raise ValueError(f"unknown packing code {packing}; known: {PACKING}")
    if vals and (min(vals) < 0 or max(vals) > limit):
        raise ValueError(f"samples must be 0..{limit} for packing {PACKING_NAMES[packing]}; got {min(vals)}..{max(vals)}")
    if packing == PACKING["u8"]:
        return bytes(vals)
    if packing == PACKING["u16"]:
        return struct.pack(f"<{len(vals)}H", *vals)
    out = bytearray()
    for i in range(0, len(vals) - 1, 2):
        a, b = vals[i], vals[i + 1]
        out += bytes((a & 0xFF, (a >> 8) | ((b & 0x0F) << 4), b >> 4))
    if len(vals) % 2:
        a = vals[-1]
        out += bytes((a & 0xFF, a >> 8))
    return bytes(out)


def unpack_samples(data: bytes, packing: int, count: int) -> list[int]:
    """Inverse of :func:`pack_samples` (stdlib; the runtime unpacks whole frames with numpy)."""
    if len(data) != packed_size(count, packing):
        raise ValueError(f"{len(data)} bytes do not hold {count} samples in packing {PACKING_NAMES.get(packing, packing)}")
    if packing == PACKING["u8"]:
        return list(data)
    if packing == PACKING["u16"]:
        return list(struct.unpack(f"<{count}H", data))
    out = []
    for i in range(0, count - 1, 2):
        b0, b1, b2 = data[3 * i // 2 : 3 * i // 2 + 3]
        out += (b0 | (b1 & 0x0F) << 8, (b1 >> 4) | (b2 << 4))
    if count % 2:
        b0, b1 = data[-2], data[-1]
        out.append(b0 | (b1 & 0x0F) << 8)
    return out


def make_row(seq: int, frame_seq: int, t_us: int, row: int, values: Iterable[int], packing: int) -> Any:
    """A ROW packet from sample values."""
    vals = list(values)
    return Row(seq, frame_seq, t_us, row, len(vals), packing, pack_samples(vals, packing))


def frame_crc32(rows_u16le: Iterable[bytes]) -> int:
    """FRAME_END's CRC-32: zlib CRC over every sample as u16 little-endian, rows in ascending index."""
    import zlib

    crc = 0
    for chunk in rows_u16le:
        crc = zlib.crc32(chunk, crc)
    return crc

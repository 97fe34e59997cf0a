"""Consistent Overhead Byte Stuffing (Cheshire & Baker, 1999).

COBS removes every 0x00 from a packet at a cost of one byte per 254, so a single
0x00 can delimit packets and a receiver resynchronises at the next delimiter after
any damage. Layout: the packet is cut at each zero into blocks; each block is sent
as ``code, data...`` where ``code = len(data) + 1`` and the zero is implied. A block
of 254 non-zero bytes is sent as ``0xFF`` + 254 bytes with no implied zero.

This encoder always ends with the code of the (possibly empty) last block, so a
packet whose length is a multiple of 254 with no zeros ends in ``0x01``; the C
reference does the same, byte for byte.
"""

from __future__ import annotations


def encode(data: bytes) -> bytes:
    """COBS-encode ``data`` (no delimiter added). len(out) <= len(data) + len(data)//254 + 1."""
    out = bytearray()
    for block in bytes(data).split(b"\x00"):
        while len(block) >= 254:
            out.append(0xFF)
            out += block[:254]
            block = block[254:]
        out.append(len(block) + 1)
        out += block
    return bytes(out)


def decode(encoded: bytes) -> bytes | None:
    """Invert :func:`encode`; None when ``encoded`` is not valid COBS (a zero, or a block past the end)."""
    n = len(encoded)
    if n == 0:
        return None
    first = encoded[0]
    if first == n and first != 0xFF and 0 not in encoded:  # fast path: a packet with no zero bytes
        return bytes(encoded[1:])
    out = bytearray()
    i = 0
    while i < n:
        code = encoded[i]
        if code == 0:
            return None
        j = i + code
        if j > n:
            return None
        out += encoded[i + 1 : j]
        if code != 0xFF and j < n:
            out.append(0)
        i = j
    if 0 in encoded:
        return None
    return bytes(out)

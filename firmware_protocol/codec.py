"""Python codec for the carpet wire protocol: the encoder, and the one import for the whole codec.

The packet classes live in :mod:`~firmware_protocol.packets`, the sample packings in
:mod:`~firmware_protocol.samples`, the streaming decoder in
:mod:`~firmware_protocol.stream_decoder`; their public names are re-exported here, so
``from firmware_protocol import codec`` gives all of it.

Every packet on the wire::

    ┌──────────── COBS-encoded ─────────────┐
    │ type u8 │ seq u16 │ payload │ crc16 u16 │ 0x00
    └─────────────────────────────────────────┘

``crc16`` is CRC-16/CCITT-FALSE over type+seq+payload, seeded with the definition hash
(or 0xFFFF for INFO and GET_INFO). Packet layouts come from protocol.toml; the classes
are built from it, so the spec file is the only place a field is defined.

The decoder takes bytes in any chunking, never raises on line noise, resynchronises
at the next 0x00 and counts every drop by reason (see :class:`DecoderStats`).
"""

from __future__ import annotations

import binascii
import struct
from typing import Any

from firmware_protocol import cobs
from firmware_protocol.packets import (
    CRC16,
    DEFINITION_HASH,
    NAK_REASON,
    NAK_REASON_NAMES,
    PACKET_CLASSES,
    PACKING,
    PACKING_NAMES,
    PROTOCOL_VERSION,
    SIGN,
    SPEC,
    Ack,
    ForeignInfo,
    FrameEnd,
    GetInfo,
    Info,
    Nak,
    Ping,
    Row,
    SetGain,
    SetRate,
    Start,
    Status,
    Stop,
)
from firmware_protocol.samples import frame_crc32, make_row, pack_samples, packed_size, unpack_samples
from firmware_protocol.stream_decoder import DROP_REASONS, DecoderStats, StreamDecoder

__all__ = [
    "SPEC", "PROTOCOL_VERSION", "DEFINITION_HASH", "PACKING", "PACKING_NAMES", "NAK_REASON", "NAK_REASON_NAMES",
    "SIGN", "PACKET_CLASSES", "Info", "Row", "FrameEnd", "Status", "Ack", "Nak", "GetInfo", "Start",
    "Stop", "SetRate", "SetGain", "Ping", "ForeignInfo", "packed_size", "pack_samples", "unpack_samples",
    "make_row", "frame_crc32", "DROP_REASONS", "DecoderStats", "StreamDecoder", "ProtocolError",
    "ProtocolMismatchError", "pack", "encode", "check_compatible", "MAX_GRID", "info_range_problems",
    "encode_command",
]


class ProtocolError(Exception):
    """Base of the protocol's exceptions (never raised by the decoder on line noise)."""


class ProtocolMismatchError(ProtocolError):
    """The device speaks another protocol version or definition than this host."""


# ------------------------------------------------------------------ encoding


def pack(packet: Any) -> bytes:
    """The packet's bytes before COBS: header, payload, CRC-16."""
    pdef = packet.DEF
    values = [getattr(packet, f.name) for f in pdef.fields]
    for i, f in enumerate(pdef.fields):
        if f.type == "char16":
            v = values[i]
            values[i] = v.encode("ascii") if isinstance(v, str) else bytes(v)
            if len(values[i]) > 16:  # struct's "16s" would cut it short silently
                raise ValueError(f"{pdef.name}: {f.name} is {len(values[i])} bytes; at most 16 fit")
    try:
        body = pdef.struct.pack(pdef.id, packet.seq & 0xFFFF, *values)
    except struct.error as exc:
        raise ValueError(f"{pdef.name}: a field does not fit its type ({exc})") from None
    if pdef.tail is not None:
        tail = bytes(getattr(packet, pdef.tail.name))
        if pdef.name == "ROW" and len(tail) != packed_size(packet.count, packet.packing):
            raise ValueError(f"ROW: {len(tail)} sample bytes do not hold count={packet.count} in packing {packet.packing}")
        body += tail
    if len(body) + 2 > SPEC.max_packet_bytes:
        raise ValueError(f"{pdef.name}: {len(body) + 2} bytes exceed max_packet_bytes={SPEC.max_packet_bytes}")
    return body + CRC16.pack(binascii.crc_hqx(body, SPEC.seed_for(pdef)))


def encode(packet: Any) -> bytes:
    """Wire bytes of one packet: COBS(pack(packet)) followed by the 0x00 delimiter."""
    return cobs.encode(pack(packet)) + b"\x00"


def check_compatible(info: Any) -> None:
    """Raise :class:`ProtocolMismatchError` naming both versions unless ``info`` is ours."""
    if isinstance(info, ForeignInfo) or info.protocol_version != PROTOCOL_VERSION or info.definition_hash != DEFINITION_HASH:
        raise ProtocolMismatchError(
            f"the device speaks {SPEC.name} protocol v{info.protocol_version} (definition 0x{info.definition_hash:04X}), "
            f"this host speaks v{PROTOCOL_VERSION} (definition 0x{DEFINITION_HASH:04X}): "
            "flash firmware built from this host's firmware_protocol/protocol.toml, or install the host release that matches the firmware"
        )


MAX_GRID = 512  # rows or cols a host accepts (the default carpet is 96×96; 512×512 u16 frames are 0.5 MB)
_PACKING_BITS = {PACKING["u8"]: 8, PACKING["packed12"]: 12, PACKING["u16"]: 16}


def info_range_problems(info: Any) -> list[str]:
    """What makes a decoded INFO insane for a host to act on (empty: none). The wire format can carry
    any value; a host must not size buffers or scale readings by them unchecked."""
    problems = []
    for key in ("rows", "cols"):
        value = getattr(info, key)
        if not 1 <= value <= MAX_GRID:
            problems.append(f"{key} {value} (1..{MAX_GRID})")
    if not 8 <= info.adc_bits <= 16:
        problems.append(f"adc_bits {info.adc_bits} (8..16)")
    if info.sign not in SIGN.values():
        problems.append(f"sign {info.sign} (one of {sorted(SIGN.values())})")
    capacity = _PACKING_BITS.get(info.packing)
    if capacity is None:
        problems.append(f"packing {info.packing} (one of {sorted(_PACKING_BITS)})")
    elif info.adc_bits > capacity:
        problems.append(f"adc_bits {info.adc_bits} do not fit packing {PACKING_NAMES[info.packing]} ({capacity} bits)")
    return problems


def encode_command(name: str, seq: int, **fields: Any) -> bytes:
    """Wire bytes of a host→device command, e.g. ``encode_command("SET_RATE", 3, rate_mhz=14000)``."""
    cls = PACKET_CLASSES[name]
    if cls.DEF.direction != "host_to_device":
        raise ValueError(f"{name} is not a host→device command")
    return encode(cls(seq, **fields))

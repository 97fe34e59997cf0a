"""Python codec for the carpet wire protocol: packet classes, encoder, streaming decoder.

Every packet on the wire::

    ┌──────────── COBS-encoded ─────────────┐
    │ type u8 │ seq u16 │ payload │ crc16 u16 │ 0x00
    └─────────────────────────────────────────┘

``crc16`` is CRC-16/CCITT-FALSE over type+seq+payload, seeded with the definition hash
(or 0xFFFF for INFO and GET_INFO). Packet layouts come from protocol.toml; the classes
below are built from it, so the spec file is the only place a field is defined.

The decoder takes bytes in any chunking, never raises on line noise, resynchronises
at the next 0x00 and counts every drop by reason (see :class:`DecoderStats`).
"""

from __future__ import annotations

import binascii
import struct
from collections import Counter
from dataclasses import dataclass, field, make_dataclass
from typing import Any, Iterable, Iterator

from firmware_protocol import cobs
from firmware_protocol import spec as _spec

SPEC = _spec.load()
PROTOCOL_VERSION = SPEC.version
DEFINITION_HASH = SPEC.definition_hash
PACKING = SPEC.enums["packing"]  # name -> code
NAK_REASON = SPEC.enums["nak_reason"]
SIGN = SPEC.enums["sign"]  # name -> value
PACKING_NAMES = {v: k for k, v in PACKING.items()}
NAK_REASON_NAMES = {v: k for k, v in NAK_REASON.items()}
_CRC = struct.Struct("<H")
_INFO_PREFIX = struct.Struct("<BHHH")  # type, seq, protocol_version, definition_hash: frozen forever


class ProtocolError(Exception):
    """Base of the protocol's exceptions (never raised by the decoder on line noise)."""


class ProtocolMismatchError(ProtocolError):
    """The device speaks another protocol version or definition than this host."""


# Drop reasons counted by the decoder (see SPEC.md § Receiving).
DROP_REASONS = (
    "bad_cobs",  # a zero-free chunk that is not valid COBS
    "too_short",  # shorter than type + seq + crc
    "too_long",  # longer than max_packet_bytes before a delimiter came
    "bad_crc",  # CRC mismatch (noise, or a peer of another definition)
    "unknown_type",  # CRC fine, but no packet has this id
    "bad_length",  # payload length does not fit the packet's layout
    "insane",  # fields out of their documented range (e.g. unknown packing)
)


def _packet_class(pdef: _spec.PacketDef) -> type:
    names = [("seq", int)] + [(f.name, Any) for f in pdef.fields]
    if pdef.tail is not None:
        names.append((pdef.tail.name, bytes))
    cls = make_dataclass(
        "".join(part.title() for part in pdef.name.split("_")),
        names,
        frozen=True,
        slots=True,
        namespace={"NAME": pdef.name, "TYPE": pdef.id, "DEF": pdef, "STRUCT": pdef.struct, "__module__": __name__},
    )
    cls.__doc__ = f"{pdef.name} (0x{pdef.id:02X}, {pdef.direction.replace('_', ' ')}): {pdef.doc}"
    return cls


# Any: the classes are made from the spec at import, so their fields are known at run time only.
PACKET_CLASSES: dict[str, Any] = {p.name: _packet_class(p) for p in SPEC.packets}
_BY_ID: dict[int, type] = {cls.TYPE: cls for cls in PACKET_CLASSES.values()}
_SEED: dict[int, int] = {cls.TYPE: SPEC.seed_for(cls.DEF) for cls in PACKET_CLASSES.values()}  # CRC seed by id

Info = PACKET_CLASSES["INFO"]
Row = PACKET_CLASSES["ROW"]
FrameEnd = PACKET_CLASSES["FRAME_END"]
Status = PACKET_CLASSES["STATUS"]
Ack = PACKET_CLASSES["ACK"]
Nak = PACKET_CLASSES["NAK"]
GetInfo = PACKET_CLASSES["GET_INFO"]
Start = PACKET_CLASSES["START"]
Stop = PACKET_CLASSES["STOP"]
SetRate = PACKET_CLASSES["SET_RATE"]
SetGain = PACKET_CLASSES["SET_GAIN"]
Ping = PACKET_CLASSES["PING"]


@dataclass(frozen=True, slots=True)
class ForeignInfo:
    """An INFO whose CRC is good but whose definition is not ours (its layout may differ too)."""

    seq: int
    protocol_version: int
    definition_hash: int


# ------------------------------------------------------------------ samples


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
    return body + _CRC.pack(binascii.crc_hqx(body, SPEC.seed_for(pdef)))


def encode(packet: Any) -> bytes:
    """Wire bytes of one packet: COBS(pack(packet)) followed by the 0x00 delimiter."""
    return cobs.encode(pack(packet)) + b"\x00"


# ------------------------------------------------------------------ decoding


@dataclass
class DecoderStats:
    """What a decoder saw. ``dropped`` counts packets by reason; ``missed`` counts seq gaps."""

    bytes_in: int = 0
    packets: int = 0
    dropped: Counter = field(default_factory=Counter)
    dropped_bytes: int = 0
    missed: int = 0  # packets the sender numbered but we never accepted (seq gaps)
    repeated: int = 0  # packets whose seq repeated the previous one
    by_type: Counter = field(default_factory=Counter)
    consecutive_bad_crc: int = 0  # well-framed packets failing CRC since the last good one

    def as_dict(self) -> dict:
        return {
            "bytes_in": self.bytes_in,
            "packets": self.packets,
            "dropped": dict(self.dropped),
            "dropped_total": sum(self.dropped.values()),
            "dropped_bytes": self.dropped_bytes,
            "missed": self.missed,
            "repeated": self.repeated,
            "by_type": dict(self.by_type),
        }


class StreamDecoder:
    """Bytes in any chunking → packets. Never raises on line noise.

    ``feed(data)`` returns the packets completed by ``data``. ``direction`` picks which
    packets are accepted ("device_to_host" for a host, "host_to_device" for a device);
    packets of the other direction count as ``unknown_type``.
    """

    def __init__(self, direction: str = "device_to_host") -> None:
        if direction not in ("device_to_host", "host_to_device"):
            raise ValueError("direction must be 'device_to_host' or 'host_to_device'")
        self.direction = direction
        self.stats = DecoderStats()
        self._buf = bytearray()
        self._discarding = False  # inside an over-long chunk: skip to the next delimiter
        self._last_seq: int | None = None
        # the longest COBS chunk whose packet fits max_packet_bytes (COBS adds n // 254 + 1)
        self._max_encoded = SPEC.max_packet_bytes + SPEC.max_packet_bytes // 254 + 1
        self._accept = {pid: cls for pid, cls in _BY_ID.items() if cls.DEF.direction == direction}

    def reset(self) -> None:
        """Forget partial data and sequence state (after a reconnect); keeps the counters."""
        self._buf.clear()
        self._discarding = False
        self._last_seq = None

    def feed(self, data: bytes) -> list[Any]:
        st = self.stats
        st.bytes_in += len(data)
        if 0 not in data:
            self._buf += data
            if len(self._buf) > self._max_encoded:
                self._drop("too_long", len(self._buf), count=not self._discarding)
                self._buf.clear()
                self._discarding = True
            return []
        self._buf += data
        chunks = self._buf.split(b"\x00")
        self._buf = bytearray(chunks.pop())
        out = []
        for chunk in chunks:
            if self._discarding:  # tail of an over-long chunk, already counted
                self._discarding = False
                st.dropped_bytes += len(chunk) + 1
                continue
            if not chunk:  # idle delimiters are allowed (senders may flush with 0x00)
                continue
            pkt = self._decode_chunk(chunk)
            if pkt is not None:
                out.append(pkt)
        return out

    def feed_iter(self, chunks: Iterable[bytes]) -> Iterator[Any]:
        for chunk in chunks:
            yield from self.feed(chunk)

    # -- internals

    def _drop(self, reason: str, nbytes: int, count: bool = True) -> None:
        if count:
            self.stats.dropped[reason] += 1
        self.stats.dropped_bytes += nbytes

    def _decode_chunk(self, chunk: bytes) -> Any | None:
        st = self.stats
        if len(chunk) > self._max_encoded:
            self._drop("too_long", len(chunk) + 1)
            return None
        raw = cobs.decode(chunk)
        if raw is None:
            self._drop("bad_cobs", len(chunk) + 1)
            return None
        if len(raw) < 5:
            self._drop("too_short", len(chunk) + 1)
            return None
        body, crc = raw[:-2], _CRC.unpack_from(raw, len(raw) - 2)[0]
        ptype = body[0]
        if binascii.crc_hqx(body, _SEED.get(ptype, DEFINITION_HASH)) != crc:
            self._drop("bad_crc", len(chunk) + 1)
            st.consecutive_bad_crc += 1
            return None
        st.consecutive_bad_crc = 0
        cls = self._accept.get(ptype)
        if cls is None:
            self._drop("unknown_type", len(chunk) + 1)
            return None
        pkt = self._unpack(cls, body)
        if pkt is None:
            return None
        self._count_seq(pkt.seq)
        st.packets += 1
        st.by_type[cls.NAME] += 1
        return pkt

    def _unpack(self, cls: type, body: bytes) -> Any | None:
        pdef = cls.DEF
        s = cls.STRUCT
        nbytes = len(body) + 3
        if cls is Info and (len(body) != s.size):
            if len(body) >= _INFO_PREFIX.size:  # another definition's INFO: keep what is frozen
                _, seq, version, dhash = _INFO_PREFIX.unpack_from(body)
                return ForeignInfo(seq, version, dhash)
            self._drop("bad_length", nbytes)
            return None
        if len(body) < s.size or (pdef.tail is None and len(body) != s.size):
            self._drop("bad_length", nbytes)
            return None
        _, seq, *values = s.unpack_from(body)
        if pdef.tail is not None:
            tail = body[s.size :]
            if cls is Row:
                packing, count = values[4], values[3]
                if packing not in PACKING_NAMES:
                    self._drop("insane", nbytes)
                    return None
                if len(tail) != packed_size(count, packing):
                    self._drop("bad_length", nbytes)
                    return None
            values.append(bytes(tail))
        if cls is Info:
            if values[0] != PROTOCOL_VERSION or values[1] != DEFINITION_HASH:
                return ForeignInfo(seq, values[0], values[1])
            values[5] = values[5].rstrip(b"\x00").decode("ascii", "replace")
            if values[11] not in PACKING_NAMES or values[12] not in (-1, 1):
                self._drop("insane", nbytes)
                return None
        return cls(seq, *values)

    def _count_seq(self, seq: int) -> None:
        last = self._last_seq
        if last is not None:
            gap = (seq - last - 1) & 0xFFFF
            if gap == 0xFFFF:
                self.stats.repeated += 1
            elif gap < 0x8000:
                self.stats.missed += gap
        self._last_seq = seq


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

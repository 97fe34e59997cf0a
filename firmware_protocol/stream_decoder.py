"""The streaming decoder: bytes in any chunking → packets, with every drop counted by reason.

It never raises on line noise: a chunk between 0x00 delimiters that is not valid COBS,
too short or too long, fails its CRC, has no packet of this direction, or has the wrong
length or insane fields is dropped and counted (:class:`DecoderStats`), and decoding
resumes at the next delimiter. Sequence gaps count as ``missed``, repeats as ``repeated``.
"""

from __future__ import annotations

import binascii
from collections import Counter
from dataclasses import dataclass, field
from typing import Any, Iterable, Iterator

from firmware_protocol import cobs
from firmware_protocol.packets import (
    BY_ID,
    CRC16,
    DEFINITION_HASH,
    INFO_PREFIX,
    PACKING_NAMES,
    PROTOCOL_VERSION,
    SEED,
    SPEC,
    ForeignInfo,
    Info,
    Row,
)
from firmware_protocol.samples import packed_size

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
        self._accept = {pid: cls for pid, cls in BY_ID.items() if cls.DEF.direction == direction}

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
        body, crc = raw[:-2], CRC16.unpack_from(raw, len(raw) - 2)[0]
        ptype = body[0]
        if binascii.crc_hqx(body, SEED.get(ptype, DEFINITION_HASH)) != crc:
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
            if len(body) >= INFO_PREFIX.size:  # another definition's INFO: keep what is frozen
                _, seq, version, dhash = INFO_PREFIX.unpack_from(body)
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

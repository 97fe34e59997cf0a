"""Shared test vectors: packets with their decoded fields and exact wire bytes.

    python -m firmware_protocol.vectors            # rewrite vectors/vectors.jsonl
    python -m firmware_protocol.vectors --check    # exit 1 if the committed file is stale

Everything here is produced by the Python codec, the reference behaviour; the C
reference (firmware_protocol/c) and the codec itself are tested against the file.
One JSON object per line, of two kinds:

* a packet: ``{"name", "type": "ROW", "direction", "fields": {"seq": .., ...}, "wire": hex}``
  with ROW samples as a list of ints (``count`` and ``packing`` as on the wire) and INFO's
  ``device_id`` as a string. A FRAME_END built from rows also lists them in ``frame_rows``.
* a command stream (host→device, often invalid): ``{"name", "type": null, "direction",
  "wire": hex, "expect": {"events": [...], "missed": n, "repeated": n}}`` where each event is
  ``{"drop": reason}`` or ``{"packet": TYPE, "fields": {...}}`` in the order a decoder
  meets them, as the Python StreamDecoder reports them.
"""

from __future__ import annotations

import binascii
import json
import random
import struct
import sys
from pathlib import Path
from typing import Any, Iterator

from firmware_protocol import cobs, codec, generated

VECTORS_PATH = Path(__file__).with_name("vectors") / "vectors.jsonl"
P = codec.PACKING
U32_MAX = 0xFFFFFFFF


# ------------------------------------------------------------------ helpers


def _fields(pkt: Any) -> dict:
    out = {"seq": pkt.seq}
    for f in pkt.DEF.fields:
        out[f.name] = getattr(pkt, f.name)
    if pkt.NAME == "ROW":
        out["samples"] = codec.unpack_samples(pkt.samples, pkt.packing, pkt.count)
    return out


def packet_vector(name: str, pkt: Any, **extra: Any) -> dict:
    """A vector for one packet, encoded by the codec."""
    return {"name": name, "type": pkt.NAME, "direction": pkt.DEF.direction, "fields": _fields(pkt),
            "wire": codec.encode(pkt).hex(), **extra}


def python_events(wire: bytes) -> tuple[list[dict], codec.DecoderStats]:
    """What the Python decoder makes of a host→device byte stream, event by event."""
    dec = codec.StreamDecoder("host_to_device")
    events: list[dict] = []
    start = 0
    while start < len(wire):
        end = wire.find(b"\x00", start)
        end = len(wire) if end < 0 else end + 1
        before = dec.stats.dropped.copy()
        for pkt in dec.feed(wire[start:end]):
            events.append({"packet": pkt.NAME, "fields": _fields(pkt)})
        events += [{"drop": reason} for reason in (dec.stats.dropped - before).elements()]
        start = end
    return events, dec.stats


def stream_vector(name: str, wire: bytes, drops: list[str] | None = None) -> dict:
    """A command-stream vector; ``drops``, when given, is what the vector was built to cause."""
    events, stats = python_events(wire)
    if drops is not None:
        got = [e["drop"] for e in events if "drop" in e]
        assert got == drops, f"{name}: built to cause {drops}, the Python decoder reports {got}"
    return {"name": name, "type": None, "direction": "host_to_device", "wire": wire.hex(),
            "expect": {"events": events, "missed": stats.missed, "repeated": stats.repeated}}


def _raw_packet(ptype: int, seq: int, payload: bytes, seed: int | None = None) -> bytes:
    body = struct.pack("<BH", ptype, seq) + payload
    if seed is None:  # the seed the codec would use for this type
        known = next((cls for cls in codec.PACKET_CLASSES.values() if cls.TYPE == ptype), None)
        seed = codec.SPEC.seed_for(known.DEF) if known else codec.DEFINITION_HASH
    return body + struct.pack("<H", binascii.crc_hqx(body, seed))


def _wire(raw: bytes) -> bytes:
    return cobs.encode(raw) + b"\x00"


def _cmd(name: str, seq: int, **fields: Any) -> bytes:
    return codec.encode_command(name, seq, **fields)


# ------------------------------------------------------------------ device → host


def _info_vectors() -> Iterator[dict]:
    base = dict(protocol_version=codec.PROTOCOL_VERSION, definition_hash=codec.DEFINITION_HASH)
    yield packet_vector("info_typical", codec.Info(
        0, **base, fw_major=1, fw_minor=2, fw_patch=3, device_id="carpet-0001", rows=96, cols=96, tile_rows=1,
        tile_cols=1, adc_bits=12, packing=P["packed12"], sign=-1, rate_mhz=14000, flags=0b101))
    yield packet_vector("info_max_values", codec.Info(
        65535, **base, fw_major=255, fw_minor=255, fw_patch=255, device_id="ABCDEFGHIJKLMNOP", rows=65535,
        cols=65535, tile_rows=255, tile_cols=255, adc_bits=16, packing=P["u16"], sign=1, rate_mhz=U32_MAX, flags=0xFF))
    yield packet_vector("info_zeros_empty_id", codec.Info(
        1, **base, fw_major=0, fw_minor=0, fw_patch=0, device_id="", rows=0, cols=0, tile_rows=0, tile_cols=0,
        adc_bits=8, packing=P["u8"], sign=-1, rate_mhz=0, flags=0))


def _row_vectors() -> Iterator[dict]:
    row = codec.make_row
    yield packet_vector("row_u8_typical", row(10, 1, 1000, 0, [10, 20, 30, 40, 50, 60, 70, 80], P["u8"]))
    yield packet_vector("row_u8_extremes_odd", row(11, 1, 1010, 1, [0, 255, 0, 255, 1], P["u8"]))
    yield packet_vector("row_u8_count0", row(12, 1, 1020, 2, [], P["u8"]))
    yield packet_vector("row_packed12_even", row(13, 2, 2000, 0, [0, 4095, 1, 2048, 0xABC, 0x123], P["packed12"]))
    yield packet_vector("row_packed12_odd", row(14, 2, 2010, 1, [4095, 0, 4095, 0x801, 0x7FE, 15, 4095], P["packed12"]))
    yield packet_vector("row_packed12_count1", row(15, 2, 2020, 2, [4095], P["packed12"]))
    yield packet_vector("row_packed12_count0", row(16, 2, 2030, 3, [], P["packed12"]))
    yield packet_vector("row_u16_extremes", row(17, 3, 3000, 0, [0, 65535, 1, 0x8000, 0x00FF, 0xFF00], P["u16"]))
    yield packet_vector("row_u16_odd", row(18, 3, 3010, 1, [65535, 0, 65535], P["u16"]))
    yield packet_vector("row_u16_count0", row(19, 3, 3020, 2, [], P["u16"]))
    yield packet_vector("row_seq_65535", row(65535, 4, 4000, 0, [1, 2, 3], P["u8"]))
    yield packet_vector("row_seq_wrapped_to_0", row(0, 4, 4010, 1, [4, 5, 6], P["u8"]))
    yield packet_vector("row_frame_seq_t_us_max", row(20, U32_MAX, U32_MAX, 65535, [7, 8], P["packed12"]))
    yield packet_vector("row_frame_seq_t_us_near_max", row(21, U32_MAX - 1, U32_MAX - 70, 95, [9], P["u16"]))
    yield packet_vector("row_frame_seq_t_us_wrapped", row(22, 0, 28, 0, [10], P["u16"]))

    # 530 bytes with no zero at all: two 0xFF COBS blocks, then the rest.
    vals = [0x0101 + 0x0101 * (i % 254) for i in range(0x0101)]
    pkt = row(0x0102, 0x01020304, 0x05060708, 0x0101, vals, P["u16"])
    assert 0 not in codec.pack(pkt)[:-2] and len(codec.pack(pkt)) > 2 * 254
    yield packet_vector("row_u16_530_bytes_no_zeros", pkt)

    # The last 254 bytes (samples + CRC) are one zero-free run: 0xFF block, then a final 0x01.
    for t_us in range(1000):
        pkt = row(23, 5, t_us, 0, [(i % 255) + 1 for i in range(252)], P["u8"])
        raw = codec.pack(pkt)
        if 0 not in raw[-2:]:
            break
    assert raw[-255] == 0 and 0 not in raw[-254:] and codec.encode(pkt).endswith(b"\x01\x00")
    yield packet_vector("row_u8_final_block_exactly_254", pkt)

    # count 0x0100 puts a zero just before [count hi, packing]; 126 zero-free samples make that
    # block exactly 254 bytes, and the next sample's low byte is zero.
    vals = [0x1111] * 126 + [0x0100] + [(i * 37) & 0xFFFF for i in range(129)]
    pkt = row(24, 6, 6000, 1, vals, P["u16"])
    assert b"\x00" + bytes([0x01, P["u16"]]) + b"\x11" * 252 + b"\x00" in codec.pack(pkt)
    yield packet_vector("row_u16_block_254_then_zero", pkt)

    yield packet_vector("row_u16_all_zeros", row(25, 7, 7000, 2, [0] * 100, P["u16"]))
    yield packet_vector("row_u8_many_zeros", row(26, 7, 7010, 3, [0, 0, 1, 0] * 75, P["u8"]))
    yield packet_vector("row_packed12_all_zeros_odd", row(27, 7, 7020, 4, [0] * 33, P["packed12"]))

    count = (codec.SPEC.max_packet_bytes - codec.Row.DEF.struct.size - 2) // 2
    pkt = row(28, 8, 8000, 5, [(i * 32 + 1) & 0xFFFF for i in range(count)], P["u16"])
    assert len(codec.pack(pkt)) == codec.SPEC.max_packet_bytes
    yield packet_vector("row_u16_max_packet_bytes", pkt)


def _frame_vectors() -> Iterator[dict]:
    rows = [[(r * 96 + c) * 37 % 4096 for c in range(96)] for r in range(3)]
    for r, vals in enumerate(rows):
        yield packet_vector(f"frame9_row{r}_packed12", codec.make_row(30 + r, 9, 9000 + 700 * r, r, vals, P["packed12"]))
    crc = codec.frame_crc32(struct.pack(f"<{len(v)}H", *v) for v in rows)
    yield packet_vector("frame9_end", codec.FrameEnd(33, 9, 10400, 3, 1400, crc), frame_rows=rows)
    yield packet_vector("frame_end_max_values", codec.FrameEnd(65535, U32_MAX, U32_MAX, 65535, U32_MAX, U32_MAX))
    yield packet_vector("frame_end_zeros", codec.FrameEnd(0, 0, 0, 0, 0, 0))


def _status_ack_nak_vectors() -> Iterator[dict]:
    yield packet_vector("status_typical", codec.Status(40, 123456789, 3600, 50400, 2, 0, 1, 3, 0, 2350, 12))
    yield packet_vector("status_negative_temperature_max_counters", codec.Status(
        41, U32_MAX, U32_MAX, U32_MAX, U32_MAX, U32_MAX, U32_MAX, U32_MAX, U32_MAX, -4050, 0))
    yield packet_vector("status_no_sensor_no_gain", codec.Status(42, 0, 0, 0, 0, 0, 0, 0, 0, -32768, 65535))
    yield packet_vector("status_max_temperature", codec.Status(43, 1, 1, 1, 1, 1, 1, 1, 1, 32767, 1))
    yield packet_vector("ack_ping_max", codec.Ack(50, codec.Ping.TYPE, 65535, U32_MAX))
    yield packet_vector("ack_set_rate", codec.Ack(51, codec.SetRate.TYPE, 7, 14000))
    yield packet_vector("ack_start", codec.Ack(52, codec.Start.TYPE, 0, 0))
    for i, (reason, code) in enumerate(sorted(codec.NAK_REASON.items(), key=lambda kv: kv[1])):
        yield packet_vector(f"nak_{reason}", codec.Nak(60 + i, codec.SetRate.TYPE if i % 2 else 0x99, 100 + i, code))
    yield packet_vector("nak_seq_max", codec.Nak(65535, codec.SetGain.TYPE, 65535, codec.NAK_REASON["unsupported"]))


# ------------------------------------------------------------------ host → device


def _command_vectors() -> Iterator[dict]:
    yield packet_vector("cmd_get_info", codec.GetInfo(0))
    yield packet_vector("cmd_start", codec.Start(1))
    yield packet_vector("cmd_stop_seq_max", codec.Stop(65535))
    yield packet_vector("cmd_set_rate_14hz", codec.SetRate(2, 14000))
    yield packet_vector("cmd_set_rate_zero", codec.SetRate(3, 0))
    yield packet_vector("cmd_set_rate_max", codec.SetRate(4, U32_MAX))
    yield packet_vector("cmd_set_gain_zero", codec.SetGain(5, 0))
    yield packet_vector("cmd_set_gain_max", codec.SetGain(6, 65535))
    yield packet_vector("cmd_ping", codec.Ping(7, 0xDEADBEEF))
    yield packet_vector("cmd_ping_token_zero", codec.Ping(256, 0))


def _zero_free_crc(ptype: int, seq: int, filler_len: int) -> bytes:
    """A raw packet with a zero-free body of filler and a zero-free CRC."""
    for last in range(1, 256):
        raw = _raw_packet(ptype, seq, b"\x5a" * (filler_len - 1) + bytes([last]))
        if 0 not in raw:
            return raw
    raise AssertionError("no zero-free CRC found")


def _invalid_command_vectors() -> Iterator[dict]:
    h = codec.DEFINITION_HASH
    ping = _cmd("PING", 0x0102, token=0x11223344)
    yield stream_vector("bad_cobs_block_past_delimiter", b"\x06\x82\x01\x00", ["bad_cobs"])
    yield stream_vector("bad_cobs_then_ping", b"\x05\x11\x00" + ping, ["bad_cobs"])
    yield stream_vector("too_short_empty_packet", b"\x01\x00", ["too_short"])
    yield stream_vector("too_short_4_bytes", _wire(_raw_packet(0x82, 1, b"")[:4]), ["too_short"])
    yield stream_vector("bad_crc_flipped_crc", _wire(_raw_packet(0x86, 2, struct.pack("<I", 5))[:-1] + b"\x99"), ["bad_crc"])
    flipped = bytearray(_raw_packet(0x84, 3, struct.pack("<I", 14000)))
    flipped[4] ^= 0x10
    yield stream_vector("bad_crc_flipped_payload_bit", _wire(bytes(flipped)), ["bad_crc"])
    yield stream_vector("bad_crc_other_definition", _wire(_raw_packet(0x86, 4, b"\x01\x02\x03\x04", seed=h ^ 0x1234)), ["bad_crc"])
    yield stream_vector("bad_crc_get_info_definition_seed", _wire(_raw_packet(0x81, 5, b"", seed=h)), ["bad_crc"])
    yield stream_vector("bad_crc_start_fixed_seed", _wire(_raw_packet(0x82, 5, b"", seed=codec.SPEC.fixed_seed)), ["bad_crc"])
    yield stream_vector("unknown_type_0x99", _wire(_raw_packet(0x99, 6, b"\x01")), ["unknown_type"])
    yield stream_vector("unknown_type_0x00", _wire(_raw_packet(0x00, 6, b"")), ["unknown_type"])
    yield stream_vector("unknown_type_ack_sent_to_device", codec.encode(codec.Ack(7, 0x82, 1, 0)), ["unknown_type"])
    info = codec.Info(8, codec.PROTOCOL_VERSION, h, 1, 0, 0, "x", 1, 1, 1, 1, 8, 0, 1, 1, 0)
    yield stream_vector("unknown_type_info_sent_to_device", codec.encode(info), ["unknown_type"])
    yield stream_vector("bad_length_start_extra_byte", _wire(_raw_packet(0x82, 9, b"\x00")), ["bad_length"])
    yield stream_vector("bad_length_set_rate_2_bytes", _wire(_raw_packet(0x84, 10, b"\x10\x27")), ["bad_length"])
    yield stream_vector("bad_length_set_gain_4_bytes", _wire(_raw_packet(0x85, 11, b"\x01\x00\x00\x00")), ["bad_length"])
    yield stream_vector("bad_length_ping_5_bytes", _wire(_raw_packet(0x86, 12, b"\x01\x02\x03\x04\x05")), ["bad_length"])
    yield stream_vector("bad_length_get_info_1_byte", _wire(_raw_packet(0x81, 13, b"\xff")), ["bad_length"])

    # Length limits: max_packet_bytes (4096) zero-free bytes encode to exactly the longest accepted chunk.
    limit = codec.SPEC.max_packet_bytes + codec.SPEC.max_packet_bytes // 254 + 1
    at_limit, over = _zero_free_crc(0x82, 0x0101, 4096 - 5), _zero_free_crc(0x82, 0x0101, 4097 - 5)
    assert len(cobs.encode(at_limit)) == limit and len(cobs.encode(over)) == limit + 1
    yield stream_vector("long_start_at_encoded_limit_is_bad_length", _wire(at_limit), ["bad_length"])
    yield stream_vector("long_start_over_encoded_limit_is_too_long", _wire(over) + ping, ["too_long"])
    yield stream_vector("too_long_noise_then_ping", b"\x11" * (limit + 50) + b"\x00" + ping, ["too_long"])

    # Streams: idle delimiters, noise, torn packets, sequence gaps.
    start, stop = _cmd("START", 20), _cmd("STOP", 21)
    yield stream_vector("idle_delimiters_around_start", b"\x00\x00\x00" + start + b"\x00\x00", [])
    yield stream_vector("start_then_partial_without_delimiter", start + stop[:-1], [])
    rng = random.Random(2)
    noise = bytes(rng.randrange(1, 256) for _ in range(40))
    yield stream_vector("noise_then_set_rate", noise + b"\x00" + _cmd("SET_RATE", 22, rate_mhz=20000))
    yield stream_vector("torn_ping_then_ping", ping[:4] + ping + _cmd("SET_GAIN", 23, gain_step=40))
    seqs = [5, 9, 9, 65535, 0, 2, 0x8002, 0x0003]  # gaps 3, repeat, backwards, wrap, 1, 0x7FFF, 0x8000
    yield stream_vector("seq_gaps_repeats_and_wrap", b"".join(_cmd("PING", s, token=s) for s in seqs), [])
    yield stream_vector("set_gain_sent_without_cobs", _raw_packet(0x85, 0x0100, b"\x00\x01") + b"\x00")
    yield stream_vector("mixed_corrupted_stream", _mixed_stream(random.Random(7), 40))


def _mixed_stream(rng: random.Random, n: int) -> bytes:
    """n commands, about a third of them damaged (bit flip, byte lost, garbage, torn)."""
    out = bytearray()
    for seq in range(n):
        kind = rng.choice(["GET_INFO", "START", "STOP", "SET_RATE", "SET_GAIN", "PING"])
        fields = {"SET_RATE": {"rate_mhz": rng.randrange(1 << 32)}, "SET_GAIN": {"gain_step": rng.randrange(1 << 16)},
                  "PING": {"token": rng.randrange(1 << 32)}}.get(kind, {})
        wire = bytearray(_cmd(kind, seq, **fields))
        damage = rng.randrange(6)
        if damage == 0:
            wire[rng.randrange(len(wire) - 1)] ^= 1 << rng.randrange(8)
        elif damage == 1:
            del wire[rng.randrange(len(wire) - 1)]
        elif damage == 2:
            wire[:0] = bytes(rng.randrange(256) for _ in range(rng.randrange(1, 12)))
        elif damage == 3:
            wire = wire[: rng.randrange(1, len(wire))]
        out += wire
    return bytes(out)


# ------------------------------------------------------------------ file


def generate() -> list[dict]:
    return [*_info_vectors(), *_row_vectors(), *_frame_vectors(), *_status_ack_nak_vectors(),
            *_command_vectors(), *_invalid_command_vectors()]


def render(vectors: list[dict] | None = None) -> str:
    return "".join(json.dumps(v, separators=(",", ":")) + "\n" for v in (vectors or generate()))


def load(path: Path = VECTORS_PATH) -> list[dict]:
    with open(path) as fh:
        return [json.loads(line) for line in fh if line.strip()]


def main(argv: list[str] | None = None) -> int:
    return generated.main("python -m firmware_protocol.vectors", __doc__.splitlines()[0], VECTORS_PATH, render, argv,
                          summary=lambda text: f" ({text.count(chr(10))} vectors)")


if __name__ == "__main__":
    sys.exit(main())

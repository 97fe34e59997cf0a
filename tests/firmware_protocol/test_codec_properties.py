"""Property tests (hypothesis) of the Python codec: strategies are built from protocol.toml."""

from __future__ import annotations

import binascii
import random
import struct

import pytest
from hypothesis import HealthCheck, assume, example, given, settings
from hypothesis import strategies as st

from firmware_protocol import cobs, codec

SPEC = codec.SPEC
P = codec.PACKING
LIMIT = {P["u8"]: 0xFF, P["packed12"]: 0xFFF, P["u16"]: 0xFFFF}
ROW_FIXED = SPEC.by_name("ROW").struct.size + 2  # header + fields + crc16



def opts(max_examples: int = 100) -> settings:
    """Per-test settings (no global profile: other test modules keep theirs). No deadline:
    CI is a busy 2-core box, and a slow example is not a failure here."""
    return settings(max_examples=max_examples, deadline=None, suppress_health_check=[HealthCheck.too_slow])

INT_RANGES = {"u8": (0, 0xFF), "i8": (-0x80, 0x7F), "u16": (0, 0xFFFF), "i16": (-0x8000, 0x7FFF), "u32": (0, 0xFFFFFFFF),
              "i32": (-(2**31), 2**31 - 1)}
# device_id: ASCII without NUL (NUL pads it on the wire), up to 16 characters
DEVICE_IDS = st.text(alphabet=st.characters(min_codepoint=1, max_codepoint=127), max_size=16)


def field_strategy(f) -> st.SearchStrategy:
    """Any value that fits a field of protocol.toml (an enum's values when the field names one)."""
    if f.enum:
        return st.sampled_from(sorted(SPEC.enums[f.enum].values()))
    if f.type == "char16":
        return DEVICE_IDS
    lo, hi = INT_RANGES[f.type]
    return st.integers(lo, hi)


@st.composite
def row_tail(draw, fields: dict) -> dict:
    packing = draw(st.sampled_from(sorted(P.values())))
    room = SPEC.max_packet_bytes - ROW_FIXED  # ROW_FIXED counts the header, fixed fields and CRC-16
    limit = max(n for n in range(room + 1) if codec.packed_size(n, packing) <= room)
    count = draw(st.one_of(st.integers(0, 120), st.integers(0, limit)))
    if count <= 120:
        values = draw(st.lists(st.integers(0, LIMIT[packing]), min_size=count, max_size=count))
    else:  # long rows up to max_packet_bytes: values from a drawn seed (drawing thousands of ints is slow)
        rnd = random.Random(draw(st.integers(0, 2**32)))
        values = [rnd.choice((0, LIMIT[packing], rnd.randint(0, LIMIT[packing]))) for _ in range(count)]
    return {**fields, "count": count, "packing": packing, "samples": codec.pack_samples(values, packing)}


@st.composite
def packets(draw, pdef=None):
    """Any valid packet of any type (or of ``pdef``)."""
    pdef = pdef or draw(st.sampled_from(SPEC.packets))
    cls = codec.PACKET_CLASSES[pdef.name]
    fields = {f.name: draw(field_strategy(f)) for f in pdef.fields}
    if pdef.name == "INFO":  # our own INFO; other definitions are ForeignInfo (tested below)
        fields.update(protocol_version=codec.PROTOCOL_VERSION, definition_hash=codec.DEFINITION_HASH)
    if pdef.name == "ROW":
        fields = draw(row_tail(fields))
    return cls(seq=draw(st.integers(0, 0xFFFF)), **fields)


def decoder_for(pkt) -> codec.StreamDecoder:
    return codec.StreamDecoder(pkt.DEF.direction)


def is_valid(pkt) -> bool:
    """A decoded packet is valid when it re-encodes and decodes to itself."""
    if isinstance(pkt, codec.ForeignInfo):
        return all(0 <= v <= 0xFFFF for v in (pkt.seq, pkt.protocol_version, pkt.definition_hash))
    dec = decoder_for(pkt)
    return dec.feed(codec.encode(pkt)) == [pkt]


# ------------------------------------------------------------------ round trips


@pytest.mark.parametrize("pdef", SPEC.packets, ids=lambda p: p.name)
def test_every_packet_type_round_trips(pdef):
    @given(packets(pdef))
    @opts(60)
    def check(pkt):
        wire = codec.encode(pkt)
        assert wire.endswith(b"\x00") and 0 not in wire[:-1]
        assert cobs.decode(wire[:-1]) == codec.pack(pkt)
        dec = decoder_for(pkt)
        assert dec.feed(wire) == [pkt]
        assert dec.stats.packets == 1 and not dec.stats.dropped

    check()


@given(st.lists(packets(), min_size=1, max_size=8), st.lists(st.binary(max_size=40), max_size=4), st.data())
@opts(100)
def test_any_chunking_gives_the_same_packets_and_counts(pkts, garbage, data):
    device = [p for p in pkts if p.DEF.direction == "device_to_host"] or [codec.Ack(0, 0x82, 0, 0)]
    stream = b"".join(codec.encode(p) for p in device)
    for g in garbage:  # garbage anywhere, delimiters included
        at = data.draw(st.integers(0, len(stream)))
        stream = stream[:at] + g + stream[at:]
    whole = codec.StreamDecoder()
    expected = whole.feed(stream)
    cuts = sorted(data.draw(st.lists(st.integers(0, len(stream)), max_size=12)))
    pieces = [stream[a:b] for a, b in zip([0, *cuts], [*cuts, len(stream)])]
    split = codec.StreamDecoder()
    got = [p for piece in pieces for p in split.feed(piece)]
    assert got == expected
    assert split.stats.dropped == whole.stats.dropped
    assert split.stats.missed == whole.stats.missed and split.stats.packets == whole.stats.packets
    if not garbage:
        assert got == device


# ------------------------------------------------------------------ line noise


@given(st.binary(max_size=3000), st.sampled_from(["device_to_host", "host_to_device"]))
@opts(300)
@example(b"\x02\x00\x00", "device_to_host")
def test_garbage_never_raises_and_never_yields_an_invalid_packet(junk, direction):
    dec = codec.StreamDecoder(direction)
    out = dec.feed(junk) + dec.feed(b"\x00")
    assert all(is_valid(p) for p in out)
    assert dec.stats.packets == len(out)


@st.composite
def well_framed_junk(draw) -> tuple[bytes, int]:
    """A random body with a *correct* CRC: only the checks after the CRC can refuse it."""
    ptype = draw(st.one_of(st.sampled_from([p.id for p in SPEC.packets]), st.integers(0, 255)))
    body = bytes([ptype]) + draw(st.binary(min_size=2, max_size=300))
    known = next((p for p in SPEC.packets if p.id == ptype), None)
    seed = SPEC.seed_for(known) if known else SPEC.definition_hash
    raw = body + struct.pack("<H", binascii.crc_hqx(body, seed))
    return cobs.encode(raw) + b"\x00", ptype


@given(well_framed_junk(), st.sampled_from(["device_to_host", "host_to_device"]))
@opts(400)
def test_well_framed_junk_is_accepted_only_when_valid(item, direction):
    wire, ptype = item
    dec = codec.StreamDecoder(direction)
    out = dec.feed(wire)
    assert len(out) + sum(dec.stats.dropped.values()) == 1
    for p in out:
        assert is_valid(p)
        assert isinstance(p, codec.ForeignInfo) or p.TYPE == ptype
    assert set(dec.stats.dropped) <= {"unknown_type", "bad_length", "insane"}


@given(st.integers(1, 30), st.integers(1, 5000))
@opts(30)
def test_overlong_garbage_counts_too_long_once_and_memory_stays_bounded(n_reads, read_size):
    assume(n_reads * read_size > 4200)
    dec = codec.StreamDecoder()
    junk = bytes(range(1, 256)) * (read_size // 255 + 1)
    for _ in range(n_reads):
        dec.feed(junk[:read_size])
        assert len(dec._buf) <= dec._max_encoded  # bounded, whatever the line keeps sending
    ping_ack = codec.Ack(5, 0x86, 9, 123)
    assert dec.feed(b"\x00" + codec.encode(ping_ack)) == [ping_ack]  # back in step at the next delimiter
    assert dec.stats.dropped == {"too_long": 1}


# ------------------------------------------------------------------ COBS


@given(st.binary(max_size=2000))
@example(b"\x01" * 254)
@example(b"\x01" * 508 + b"\x00")
@example(b"")
@opts()
def test_cobs_round_trip_and_no_zero_in_output(data):
    enc = cobs.encode(data)
    assert 0 not in enc
    assert len(enc) <= len(data) + len(data) // 254 + 1
    assert cobs.decode(enc) == data


@given(st.binary(max_size=600))
@example(b"\x02\x00")
@example(b"\x03\x00\x01")
@opts()
def test_cobs_decode_of_anything_never_raises_and_refuses_zeros(junk):
    out = cobs.decode(junk)
    if 0 in junk or not junk:
        assert out is None
    if out is not None:
        assert cobs.decode(cobs.encode(out)) == out


# ------------------------------------------------------------------ samples


@given(st.sampled_from(sorted(P.values())), st.data())
@opts()
def test_samples_round_trip(packing, data):
    values = data.draw(st.lists(st.integers(0, LIMIT[packing]), max_size=300))
    packed = codec.pack_samples(values, packing)
    assert len(packed) == codec.packed_size(len(values), packing)
    assert codec.unpack_samples(packed, packing, len(values)) == values
    row = codec.make_row(1, 2, 3, 4, values, packing)
    assert row.count == len(values) and row.samples == packed


@given(st.sampled_from(sorted(P.values())), st.lists(st.integers(0, 0xFFFF), max_size=20),
       st.one_of(st.integers(-(2**20), -1), st.integers(1, 2**20)))
@opts()
def test_out_of_range_samples_raise_value_error(packing, values, bad):
    bad = bad if bad < 0 else LIMIT[packing] + bad
    values = [v % (LIMIT[packing] + 1) for v in values]
    for at in {0, len(values)}:
        with pytest.raises(ValueError):
            codec.pack_samples(values[:at] + [bad] + values[at:], packing)


@given(st.sampled_from(sorted(P.values())), st.integers(0, 100), st.integers(1, 5))
@opts()
def test_unpack_refuses_a_wrong_length(packing, count, extra):
    with pytest.raises(ValueError):
        codec.unpack_samples(bytes(codec.packed_size(count, packing) + extra), packing, count)


# ------------------------------------------------------------------ sequence numbers


@given(st.integers(0, 0xFFFF), st.lists(st.integers(0, 300), min_size=1, max_size=60))
@example(0xFFFF, [0])  # 65535 → 0 is the next packet, not a gap
@example(0xFFFE, [1, 0, 3])
@opts()
def test_seq_gaps_are_counted_across_wrap_around(start, gaps):
    seqs = [start]
    for g in gaps:
        seqs.append((seqs[-1] + 1 + g) & 0xFFFF)
    dec = codec.StreamDecoder()
    for s in seqs:
        dec.feed(codec.encode(codec.Ack(s, 0x86, 0, 0)))
    assert dec.stats.packets == len(seqs)
    assert dec.stats.missed == sum(gaps)
    assert dec.stats.repeated == 0


def test_a_repeated_seq_is_counted_as_repeated_not_missed():
    dec = codec.StreamDecoder()
    for s in (65535, 65535, 0):
        dec.feed(codec.encode(codec.Ack(s, 0x86, 0, 0)))
    assert (dec.stats.missed, dec.stats.repeated) == (0, 1)


# ------------------------------------------------------------------ version mismatch


@given(st.integers(0, 0xFFFF), st.integers(0, 0xFFFF), st.integers(0, 0xFFFF), st.binary(max_size=80))
@opts()
def test_foreign_info_names_both_versions(seq, version, dhash, rest):
    assume((version, dhash) != (codec.PROTOCOL_VERSION, codec.DEFINITION_HASH))
    # another definition's INFO: the frozen prefix, then anything, CRC with the fixed seed
    body = struct.pack("<BHHH", 0x01, seq, version, dhash) + rest
    wire = cobs.encode(body + struct.pack("<H", binascii.crc_hqx(body, SPEC.fixed_seed))) + b"\x00"
    (info,) = codec.StreamDecoder().feed(wire)
    assert isinstance(info, codec.ForeignInfo)
    assert (info.seq, info.protocol_version, info.definition_hash) == (seq, version, dhash)
    with pytest.raises(codec.ProtocolMismatchError) as err:
        codec.check_compatible(info)
    msg = str(err.value)
    assert f"v{version} (definition 0x{dhash:04X})" in msg
    assert f"v{codec.PROTOCOL_VERSION} (definition 0x{codec.DEFINITION_HASH:04X})" in msg


@given(packets(SPEC.by_name("INFO")))
@opts(20)
def test_our_own_info_is_compatible(info):
    (got,) = codec.StreamDecoder().feed(codec.encode(info))
    codec.check_compatible(got)  # does not raise

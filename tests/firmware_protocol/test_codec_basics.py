"""What the property and corruption tests do not cover: the definition hash, fixed facts
of the wire format, encoder refusals, and SPEC.md kept in step with protocol.toml."""

from __future__ import annotations

import binascii
import copy
import re
import tomllib

import pytest

from firmware_protocol import cobs, codec, spec

SPEC = codec.SPEC
SPEC_MD = spec.SPEC_PATH.with_name("SPEC.md")
SIZES = {"u8": 1, "i8": 1, "u16": 2, "i16": 2, "u32": 4, "i32": 4, "char16": 16}


@pytest.fixture(scope="module")
def raw() -> dict:
    with open(spec.SPEC_PATH, "rb") as fh:
        return tomllib.load(fh)


@pytest.fixture(scope="module")
def doc() -> str:
    return SPEC_MD.read_text(encoding="utf-8")


def _field(raw: dict, packet: str, field: str) -> dict:
    p = next(p for p in raw["packet"] if p["name"] == packet)
    return next(f for f in p["fields"] if f["name"] == field)


# ------------------------------------------------------------------ definition hash


def test_definition_hash_changes_with_the_wire_layout(raw):
    base = spec.parse(raw).definition_hash
    assert base == codec.DEFINITION_HASH

    changes = {
        "field type": lambda r: _field(r, "ROW", "t_us").update(type="u16"),
        "field name": lambda r: _field(r, "STATUS", "uptime_s").update(name="uptime_ms"),
        "packet id": lambda r: next(p for p in r["packet"] if p["name"] == "PING").update(id=0x87),
        "seed kind": lambda r: next(p for p in r["packet"] if p["name"] == "START").update(seed="fixed"),
        "field order": lambda r: (lambda f: f.__setitem__(slice(0, 2), f[1::-1]))(
            next(p for p in r["packet"] if p["name"] == "ACK")["fields"]),
        "enum value": lambda r: r["enums"]["packing"].update(u16=3),
        "version": lambda r: r["protocol"].update(version=2),
    }
    for what, change in changes.items():
        modified = copy.deepcopy(raw)
        change(modified)
        assert spec.parse(modified).definition_hash != base, what


def test_definition_hash_ignores_documentation(raw):
    modified = copy.deepcopy(raw)
    for p in modified["packet"]:
        p["doc"] = "rewritten " + p.get("doc", "")
        for f in p["fields"]:
            f["doc"] = "reworded"
        if "tail" in p:
            p["tail"]["doc"] = "reworded"
    for e in modified["enums"].values():
        e["doc"] = "reworded"
    for f in modified["header"]["fields"]:
        f["doc"] = "reworded"
    assert spec.parse(modified).definition_hash == codec.DEFINITION_HASH


def test_spec_parse_refuses_unknown_types_and_duplicate_ids(raw):
    bad_type = copy.deepcopy(raw)
    _field(bad_type, "ROW", "t_us")["type"] = "u24"
    with pytest.raises(ValueError, match="u24"):
        spec.parse(bad_type)
    dup = copy.deepcopy(raw)
    next(p for p in dup["packet"] if p["name"] == "PING")["id"] = 0x85
    with pytest.raises(ValueError, match="share an id"):
        spec.parse(dup)


def test_crc16_is_ccitt_false():
    assert binascii.crc_hqx(b"123456789", 0xFFFF) == 0x29B1
    assert SPEC.fixed_seed == 0xFFFF


def test_a_peer_of_another_definition_fails_the_crc_loudly():
    other_seed = codec.DEFINITION_HASH ^ 0x0101
    dec = codec.StreamDecoder()
    for seq in range(5):
        body = codec.pack(codec.Ack(seq, 0x86, seq, 7))[:-2]
        dec.feed(cobs.encode(body + binascii.crc_hqx(body, other_seed).to_bytes(2, "little")) + b"\x00")
    assert dec.stats.packets == 0
    assert dec.stats.dropped == {"bad_crc": 5} and dec.stats.consecutive_bad_crc == 5
    dec.feed(codec.encode(codec.Ack(5, 0x86, 5, 7)))
    assert dec.stats.consecutive_bad_crc == 0


def test_info_of_our_layout_but_another_version_is_foreign():
    info = codec.Info(3, codec.PROTOCOL_VERSION + 1, 0x1234, 1, 0, 0, "mat-7", 96, 96, 1, 1, 12, 1, -1, 14000, 0)
    (got,) = codec.StreamDecoder().feed(codec.encode(info))
    assert got == codec.ForeignInfo(3, codec.PROTOCOL_VERSION + 1, 0x1234)


# ------------------------------------------------------------------ encoder and decoder details


def test_encoder_refuses_what_does_not_fit():
    with pytest.raises(ValueError):
        codec.encode(codec.Ack(0, 0x86, 0, 2**32))  # u32 overflow
    with pytest.raises(ValueError):
        codec.encode(codec.Status(0, 0, 0, 0, 0, 0, 0, 0, 0, 40000, 0))  # i16 overflow
    with pytest.raises(ValueError):
        codec.encode(codec.Row(0, 0, 0, 0, 96, codec.PACKING["packed12"], bytes(143)))  # tail length
    with pytest.raises(ValueError):
        codec.encode(codec.Row(0, 0, 0, 0, 2040, codec.PACKING["u16"], bytes(4080)))  # 4098 > max_packet_bytes
    with pytest.raises(ValueError):
        codec.encode(codec.Info(0, 1, 1, 1, 1, 1, "x" * 17, 96, 96, 1, 1, 12, 1, 1, 14000, 0))  # device_id > 16
    with pytest.raises(ValueError):
        codec.pack_samples([1, 2], 7)


def test_the_largest_packet_with_the_most_cobs_overhead_is_accepted():
    biggest = codec.Row(0x0101, 0x01010101, 0x01010101, 0x0101, 2039, codec.PACKING["u16"], b"\x01" * 4078)
    assert len(codec.pack(biggest)) == SPEC.max_packet_bytes
    wire = codec.encode(biggest)
    assert len(wire) >= 4096 + 4096 // 254 + 1  # (+ up to one more if the CRC holds no zero)
    dec = codec.StreamDecoder()
    assert [p for i in range(0, len(wire), 100) for p in dec.feed(wire[i : i + 100])] == [biggest]


def test_seq_wraps_in_the_encoder():
    assert codec.pack(codec.Start(0x10001))[1:3] == b"\x01\x00"


def test_decoder_direction_selects_packets():
    cmd = codec.encode_command("SET_RATE", 3, rate_mhz=10000)
    host, device = codec.StreamDecoder("device_to_host"), codec.StreamDecoder("host_to_device")
    assert host.feed(cmd) == [] and host.stats.dropped == {"unknown_type": 1}
    assert device.feed(cmd) == [codec.SetRate(3, 10000)]
    with pytest.raises(ValueError):
        codec.encode_command("ROW", 0)
    with pytest.raises(ValueError):
        codec.StreamDecoder("sideways")


def test_idle_delimiters_are_not_drops_and_reset_forgets_partial_data():
    dec = codec.StreamDecoder()
    ack = codec.Ack(1, 0x82, 1, 0)
    assert dec.feed(b"\x00\x00" + codec.encode(ack) + b"\x00") == [ack]
    assert not dec.stats.dropped
    dec.feed(codec.encode(ack)[:5])
    dec.reset()
    ack2 = codec.Ack(900, 0x82, 2, 0)
    assert dec.feed(codec.encode(ack2)) == [ack2]
    assert dec.stats.missed == 0  # reset forgot the last seq


@pytest.mark.parametrize(
    "raw_packet, reason",
    [
        (b"\x05\x01\x00\x00", "too_short"),
        (b"\x02\x01\x00" + bytes(12) + b"\x07" + bytes(4), "insane"),  # ROW, count 0, packing 7
        (b"\x03\x01\x00" + bytes(5), "bad_length"),  # FRAME_END far too short
        (b"\x7f\x01\x00", "unknown_type"),
    ],
)
def test_drop_reasons_after_a_good_crc(raw_packet, reason):
    seed = codec.DEFINITION_HASH
    wire = cobs.encode(raw_packet + binascii.crc_hqx(raw_packet, seed).to_bytes(2, "little"))
    if reason == "too_short":
        wire = cobs.encode(raw_packet)
    dec = codec.StreamDecoder()
    assert dec.feed(wire + b"\x00") == []
    assert dec.stats.dropped == {reason: 1}


def test_bad_cobs_is_counted():
    dec = codec.StreamDecoder()
    dec.feed(b"\x09\x01\x02\x00")  # code 9 points past the end of the chunk
    assert dec.stats.dropped == {"bad_cobs": 1}


def test_frame_crc32_is_zlib_over_u16_samples():
    import zlib

    rows = [bytes([1, 0, 2, 0]), bytes([3, 0])]
    assert codec.frame_crc32(rows) == zlib.crc32(b"".join(rows))


# ------------------------------------------------------------------ SPEC.md in step with protocol.toml


def expected_heading(p: spec.PacketDef) -> str:
    d = "device → host" if p.direction == "device_to_host" else "host → device"
    seed = f"CRC seed 0x{SPEC.fixed_seed:04X} (fixed)" if p.seed == "fixed" else "CRC seed = definition hash"
    return f"#### `{p.name}` 0x{p.id:02X} · {d} · {seed}"


def expected_rows(p: spec.PacketDef) -> list[tuple[str, str, str, str]]:
    """(offset, size, field, type) for every row of the packet's table in SPEC.md."""
    rows = [("0", "1", "type", "u8"), ("1", "2", "seq", "u16")]
    off = 3
    for f in p.fields:
        rows.append((str(off), str(SIZES[f.type]), f.name, f.type))
        off += SIZES[f.type]
    assert off == p.struct.size
    if p.tail is not None:
        rows += [(str(off), "N", p.tail.name, p.tail.type), (f"{off}+N", "2", "crc16", "u16")]
    else:
        rows.append((str(off), "2", "crc16", "u16"))
    return rows


def table_after(doc: str, heading: str) -> list[tuple[str, ...]]:
    """The first markdown table after ``heading``: its body rows, first four cells, backticks removed."""
    lines = doc[doc.index(heading) :].splitlines()
    start = next(i for i, line in enumerate(lines) if line.startswith("|"))
    rows = []
    for line in lines[start + 2 :]:
        if not line.startswith("|"):
            break
        cells = [c.strip().strip("`") for c in line.strip().strip("|").split("|")]
        rows.append(tuple(cells[:4]))
    return rows


def _render(p: spec.PacketDef) -> str:
    lines = [expected_heading(p), "", "| offset | size | field | type | meaning |", "|---:|---:|---|---|---|"]
    lines += [f"| {o} | {s} | `{n}` | {t} | … |" for o, s, n, t in expected_rows(p)]
    return "\n".join(lines)


@pytest.mark.parametrize("pdef", SPEC.packets, ids=lambda p: p.name)
def test_spec_md_has_every_packet_with_the_right_offsets(doc, pdef):
    heading = expected_heading(pdef)
    assert doc.count(heading) == 1, f"SPEC.md needs exactly one section headed:\n{heading}\nwith this table:\n{_render(pdef)}"
    got = table_after(doc, heading)
    assert got == expected_rows(pdef), f"SPEC.md's table for {pdef.name} is out of date; it should read:\n{_render(pdef)}"
    if pdef.tail is None:
        n = pdef.struct.size + 2
        assert f"{n} bytes before COBS, {n + 2} on the wire." in doc[doc.index(heading) :].split("\n#")[0]


def test_spec_md_has_no_packet_that_protocol_toml_lacks(doc):
    documented = set(re.findall(r"^#### `([A-Z_]+)` 0x", doc, flags=re.M))
    assert documented == {p.name for p in SPEC.packets}


def test_spec_md_lists_every_enum_value_and_drop_reason(doc):
    for name, values in SPEC.enums.items():
        for key, value in values.items():
            assert re.search(rf"^\| {value} \| `{key}` \|", doc, flags=re.M), f"SPEC.md: enum {name}: {key} = {value} missing"
    for reason in codec.DROP_REASONS:
        assert re.search(rf"^\| `{reason}` \|", doc, flags=re.M), f"SPEC.md § Receiving: drop reason {reason} missing"


def test_spec_md_canonical_text_and_hash(doc, raw):
    canon = spec.canonical_text(raw)
    assert f"```\n{canon}```" in doc, f"SPEC.md § 4.1: the canonical text should read:\n{canon}"
    assert f"Definition hash of protocol v{SPEC.version}: **0x{SPEC.definition_hash:04X}**." in doc
    assert f"definition hash 0x{SPEC.definition_hash:04X}" in doc  # the worked ROW example says which seed


def test_spec_md_worked_examples(doc):
    get_info = codec.GetInfo(1)
    row = codec.make_row(2, 1, 1000, 0, [0x123, 0x456, 0x789], codec.PACKING["packed12"])
    for pkt in (get_info, row):
        assert f"packet:   {codec.pack(pkt).hex(' ')}" in doc, f"SPEC.md § 2.2: {pkt!r} before COBS"
        assert f"wire:     {codec.encode(pkt).hex(' ')}\n" in doc, f"SPEC.md § 2.2: {pkt!r} on the wire"
    assert codec.pack_samples([0x123, 0x456, 0x789], codec.PACKING["packed12"]).hex(" ") == "23 61 45 89 07"
    assert "`0x123, 0x456, 0x789` → `23 61 45 89 07`" in doc


def bandwidth(packing: str, rows: int = 96, cols: int = 96, rate_hz: int = 14) -> dict[str, float]:
    """Bytes on the wire for a rows×cols carpet: per ROW, per frame, per second (+1 STATUS/s)."""
    row = len(codec.encode(codec.make_row(0, 0, 0, 0, [1] * cols, codec.PACKING[packing])))
    frame_end = len(codec.encode(codec.FrameEnd(0, 0, 0, rows, 0, 0)))
    status = len(codec.encode(codec.Status(0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0)))
    frame = rows * row + frame_end
    per_s = rate_hz * frame + status
    samples = rows * cols * rate_hz * {"u8": 1, "packed12": 1.5, "u16": 2}[packing]
    return {"row": row, "frame": frame, "samples": samples, "per_s": per_s, "uart": per_s / 200_000, "usb": per_s / 1_216_000}


@pytest.mark.parametrize("packing", sorted(codec.PACKING))
def test_spec_md_bandwidth_table_matches_the_encoder(doc, packing):
    b = bandwidth(packing)
    line = next((line for line in doc.splitlines() if line.startswith(f"| `{packing}` | ") and "%" in line), None)
    assert line is not None, f"SPEC.md § 7: no bandwidth row for {packing}"
    cells = [c.strip().replace(",", "").rstrip(" %") for c in line.strip("|").split("|")][1:]
    want = [b["row"], b["frame"], b["samples"], b["per_s"], round(100 * b["uart"]), round(100 * b["usb"])]
    assert [float(c) for c in cells] == [float(w) for w in want], f"SPEC.md § 7, {packing}: should read {want}"


def test_twelve_bit_96x96_does_not_fit_a_2_mbaud_uart():
    assert bandwidth("packed12")["uart"] > 1 > bandwidth("u8")["uart"]
    assert bandwidth("u16")["usb"] < 0.5

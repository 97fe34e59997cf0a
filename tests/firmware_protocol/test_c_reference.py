"""The C reference (firmware_protocol/c) and the Python codec against the shared vectors.

The C is built twice with the system compiler — warnings as errors with address and
undefined-behaviour sanitizers, and plain -O2 — and its harness (c/test_vectors.c) checks
every vector byte for byte. A missing compiler fails these tests: the C reference is part
of the product, not an optional extra.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections import Counter
from pathlib import Path

import pytest

from firmware_protocol import codec, gen_c, vectors

C_DIR = Path(gen_c.__file__).with_name("c")
CC = os.environ.get("CC", "gcc")
STRICT = ["-std=c99", "-Wall", "-Wextra", "-Werror", "-pedantic"]
SANITIZE = ["-fsanitize=address,undefined", "-fno-sanitize-recover=all", "-fno-omit-frame-pointer", "-g"]
SANITIZER_MARKS = ("AddressSanitizer", "LeakSanitizer", "runtime error:", "UndefinedBehaviorSanitizer")
VECTORS = vectors.load()
FROZEN_INFO_FIELDS = ("protocol_version", "definition_hash")  # written by the C encoder from its build


# ------------------------------------------------------------------ the harness's input


def _command_value(fields: dict) -> int:
    return fields.get("rate_mhz", fields.get("gain_step", fields.get("token", 0)))


def _event_tokens(event: dict) -> list[str]:
    if "drop" in event:
        return ["X", event["drop"]]
    f = event["fields"]
    return ["P", str(codec.PACKET_CLASSES[event["packet"]].TYPE), str(f["seq"]), str(_command_value(f))]


def _encode_line(v: dict) -> str:
    f = v["fields"]
    tokens = ["E", v["name"], v["type"], str(f["seq"])]
    for fdef in codec.PACKET_CLASSES[v["type"]].DEF.fields:
        if v["type"] == "INFO" and fdef.name in FROZEN_INFO_FIELDS:
            continue
        value = f[fdef.name]
        tokens.append(value.encode("ascii").ljust(16, b"\0").hex() if fdef.type == "char16" else str(value))
    tokens += [str(s) for s in f.get("samples", [])]
    return " ".join(tokens + [v["wire"]])


def harness_input(vecs: list[dict]) -> str:
    """The line-oriented form test_vectors.c reads (see the comment at its top)."""
    lines = []
    for v in vecs:
        assert " " not in v["name"]
        if v["direction"] == "device_to_host":
            lines.append(_encode_line(v))
        else:
            expect = v.get("expect") or {"events": [{"packet": v["type"], "fields": v["fields"]}], "missed": 0, "repeated": 0}
            tokens = ["D", v["name"], v["wire"], str(expect["missed"]), str(expect["repeated"]), str(len(expect["events"]))]
            lines.append(" ".join(tokens + [t for e in expect["events"] for t in _event_tokens(e)]))
        if "frame_rows" in v:
            rows = v["frame_rows"]
            tokens = ["F", v["name"] + "_crc32", str(v["fields"]["frame_crc32"]), str(len(rows))]
            lines.append(" ".join(tokens + [t for r in rows for t in [str(len(r)), *map(str, r)]]))
    return "\n".join(lines) + "\n"


# ------------------------------------------------------------------ building and running


def build(out: Path, *flags: str) -> Path:
    cc = shutil.which(CC)
    assert cc, f"C compiler {CC!r} not found: install gcc (Debian: apt-get install gcc) to test the C reference"
    cmd = [cc, *STRICT, *flags, "-o", str(out), str(C_DIR / "test_vectors.c"), str(C_DIR / "cavatar_protocol.c")]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    assert proc.returncode == 0, f"{' '.join(cmd)}\n{proc.stdout}{proc.stderr}"
    return out


def run_harness(exe: Path, stdin: str, *args: str) -> subprocess.CompletedProcess:
    env = dict(os.environ, ASAN_OPTIONS="detect_leaks=1:halt_on_error=1", UBSAN_OPTIONS="print_stacktrace=1")
    proc = subprocess.run([str(exe), *args], input=stdin, capture_output=True, text=True, env=env, timeout=300)
    noise = [m for m in SANITIZER_MARKS if m in proc.stderr]
    assert not noise, f"sanitizer report ({', '.join(noise)}):\n{proc.stderr[-4000:]}"
    return proc


@pytest.fixture(scope="module")
def sanitized(tmp_path_factory) -> Path:
    return build(tmp_path_factory.mktemp("c") / "test_vectors_asan", *SANITIZE)


@pytest.fixture(scope="module")
def optimised(tmp_path_factory) -> Path:
    return build(tmp_path_factory.mktemp("c") / "test_vectors_o2", "-O2")


@pytest.mark.parametrize("build_name", ["sanitized", "optimised"])
def test_c_reference_matches_every_vector(build_name, request):
    exe = request.getfixturevalue(build_name)
    proc = run_harness(exe, harness_input(VECTORS))
    assert proc.returncode == 0, f"{proc.stdout[-4000:]}\n{proc.stderr[-4000:]}"
    n_enc = sum(v["direction"] == "device_to_host" for v in VECTORS)
    assert f"{n_enc} encoder," in proc.stdout and "; 0 failures" in proc.stdout, proc.stdout


def test_c_reference_has_no_globals_and_no_heap(tmp_path):
    """Firmware rules: no writable static data, nothing from the C library beyond memset/memcpy."""
    obj = tmp_path / "cavatar_protocol.o"
    cmd = [shutil.which(CC) or CC, *STRICT, "-O2", "-fno-pic", "-c", "-o", str(obj), str(C_DIR / "cavatar_protocol.c")]
    assert subprocess.run(cmd, capture_output=True).returncode == 0
    nm = shutil.which("nm")
    assert nm, "nm (binutils, installed with gcc) not found"
    symbols = [line.split()[-2:] for line in subprocess.run([nm, str(obj)], capture_output=True, text=True).stdout.splitlines()]
    writable = [name for kind, name in symbols if kind in "BbCDdGgSsVv"]
    imported = {name for kind, name in symbols if kind == "U"}
    assert writable == [] and imported <= {"memset", "memcpy"}, (writable, imported)


def test_harness_reports_a_wrong_vector(sanitized):
    """The harness is not vacuous: one changed wire byte or drop reason is a failure."""
    enc = next(v for v in VECTORS if v["type"] == "STATUS")
    bad_enc = dict(enc, wire=enc["wire"][:6] + ("00" if enc["wire"][6:8] != "00" else "01") + enc["wire"][8:])
    dec = next(v for v in VECTORS if v["name"] == "bad_crc_flipped_crc")
    bad_dec = dict(dec, expect=dict(dec["expect"], events=[{"drop": "bad_cobs"}]))
    proc = run_harness(sanitized, harness_input([bad_enc, bad_dec]))
    assert proc.returncode == 1 and "; 2 failures" in proc.stdout, proc.stdout


def test_definition_mismatch_fails_loudly(tmp_path):
    """Firmware built from another definition: every packet fails its CRC except INFO,
    which stays readable and names both versions."""
    other_hash = codec.DEFINITION_HASH ^ 0x5A5A
    exe = build(tmp_path / "test_vectors_other", *SANITIZE, "-DCAV_PROTOCOL_VERSION_OVERRIDE=2",
                f"-DCAV_DEFINITION_HASH_OVERRIDE=0x{other_hash:04X}")
    device_vectors = [v for v in VECTORS if v["direction"] == "device_to_host"]
    proc = run_harness(exe, harness_input(device_vectors), "--emit")
    assert proc.returncode == 0, proc.stderr
    emitted = dict(line.split(" ") for line in proc.stdout.splitlines())
    assert set(emitted) == {v["name"] for v in device_vectors}
    for v in device_vectors:
        dec = codec.StreamDecoder()
        packets = dec.feed(bytes.fromhex(emitted[v["name"]]))
        if v["type"] != "INFO":
            assert packets == [] and dec.stats.dropped == Counter(bad_crc=1), v["name"]
            continue
        assert packets == [codec.ForeignInfo(v["fields"]["seq"], 2, other_hash)], v["name"]
        with pytest.raises(codec.ProtocolMismatchError) as err:
            codec.check_compatible(packets[0])
        msg = str(err.value)
        assert "v2" in msg and f"v{codec.PROTOCOL_VERSION}" in msg
        assert f"0x{other_hash:04X}" in msg and f"0x{codec.DEFINITION_HASH:04X}" in msg


# ------------------------------------------------------------------ generated files are current


def test_generated_header_is_current():
    assert gen_c.HEADER_PATH.read_text() == gen_c.render(), "run `python -m firmware_protocol.gen_c`"


def test_vectors_file_is_current():
    assert vectors.VECTORS_PATH.read_text() == vectors.render(), "run `python -m firmware_protocol.vectors`"


def test_check_commands_exit_zero():
    for module in ("firmware_protocol.gen_c", "firmware_protocol.vectors"):
        proc = subprocess.run([sys.executable, "-m", module, "--check"], capture_output=True, text=True, cwd=C_DIR.parents[1])
        assert proc.returncode == 0, proc.stderr


# ------------------------------------------------------------------ the Python codec on the same vectors


def _packet_from(v: dict):
    cls = codec.PACKET_CLASSES[v["type"]]
    fields = dict(v["fields"])
    if v["type"] == "ROW":
        samples = fields.pop("samples")
        assert fields["count"] == len(samples)
        fields["samples"] = codec.pack_samples(samples, fields["packing"])
    return cls(**fields)


@pytest.mark.parametrize("v", VECTORS, ids=[v["name"] for v in VECTORS])
def test_python_codec_round_trips(v):
    wire = bytes.fromhex(v["wire"])
    if v["type"] is not None:
        assert codec.encode(_packet_from(v)) == wire
        expected = [{"packet": v["type"], "fields": v["fields"]}]
        missed = repeated = 0
    else:
        expected, missed, repeated = v["expect"]["events"], v["expect"]["missed"], v["expect"]["repeated"]
    for chunking in ([wire], [wire[i : i + 1] for i in range(len(wire))]):
        dec = codec.StreamDecoder(v["direction"])
        packets = [p for chunk in chunking for p in dec.feed(chunk)]
        got = [{"packet": p.NAME, "fields": vectors._fields(p)} for p in packets]
        assert got == [e for e in expected if "packet" in e]
        assert dec.stats.dropped == Counter(e["drop"] for e in expected if "drop" in e)
        assert (dec.stats.missed, dec.stats.repeated) == (missed, repeated)
    if "frame_rows" in v:
        rows_le = (b"".join(s.to_bytes(2, "little") for s in row) for row in v["frame_rows"])
        assert codec.frame_crc32(rows_le) == v["fields"]["frame_crc32"]


def test_vectors_cover_the_protocol():
    packets = [v for v in VECTORS if v["type"] is not None]
    rows = [v["fields"] for v in packets if v["type"] == "ROW"]
    assert {v["type"] for v in packets} == set(codec.PACKET_CLASSES)
    assert {r["packing"] for r in rows} == set(codec.PACKING.values())
    for packing, top in ((0, 0xFF), (1, 0xFFF), (2, 0xFFFF)):
        mine = [r for r in rows if r["packing"] == packing]
        assert any(r["count"] == 0 for r in mine) and any(r["count"] % 2 for r in mine)
        assert any(top in r["samples"] for r in mine) and any(0 in r["samples"] for r in mine)
    by_name = {v["name"]: v for v in VECTORS}
    assert by_name["row_u16_530_bytes_no_zeros"]["wire"].startswith("ff")  # a full 254-byte COBS block
    assert by_name["row_u8_final_block_exactly_254"]["wire"].endswith("0100")
    assert "row_u16_block_254_then_zero" in by_name
    seqs = {v["fields"]["seq"] for v in packets}
    assert {0, 65535} <= seqs
    assert any(r["frame_seq"] == 0xFFFFFFFF and r["t_us"] == 0xFFFFFFFF for r in rows)
    assert any(v["fields"].get("temperature_cdeg", 0) < 0 for v in packets)
    assert {v["fields"]["reason"] for v in packets if v["type"] == "NAK"} == set(codec.NAK_REASON.values())
    drops = {e["drop"] for v in VECTORS if v["type"] is None for e in v["expect"]["events"] if "drop" in e}
    assert drops == set(codec.DROP_REASONS) - {"insane"}  # no command field has a range to violate

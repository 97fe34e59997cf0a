"""The JSON-lines sink touches only its own files: it refuses a file it did not write and rotation deletes
only its own rotated files (issue 18, finding 6)."""

import json

import pytest
from sink_helpers import DEVICE, body_record

from edge.sinks import SinkError, open_sink


def record_line(seq: int, device: str = DEVICE) -> bytes:
    return json.dumps(body_record(seq, device=device), separators=(",", ":")).encode() + b"\n"


@pytest.mark.parametrize("content", [
    b"my thesis, chapter 3, no newline at the end",              # would have been truncated to nothing
    b"line one\nline two without its newline",                   # would have lost its last line
    b'{"not": "a record"}\n',
    record_line(0, device="carpet-99"),                            # another device's stream
], ids=["text", "text_two_lines", "json", "other_device"])
def test_a_file_it_did_not_write_is_refused_and_left_as_it_was(tmp_path, content):
    path = tmp_path / "bodies.jsonl"
    path.write_bytes(content)
    with pytest.raises(SinkError, match="did not write it|not the start of a record") as err:
        open_sink(f"jsonl://{path}", device=DEVICE)
    assert "\n" not in str(err.value)
    assert path.read_bytes() == content


def test_its_own_file_with_foreign_bytes_at_the_end_is_left_alone(tmp_path):
    path = tmp_path / "bodies.jsonl"
    content = record_line(0) + record_line(1) + b"appended by someone else"
    path.write_bytes(content)
    with pytest.raises(SinkError, match="not the start of a record"):
        open_sink(f"jsonl://{path}", device=DEVICE)
    assert path.read_bytes() == content


def test_a_symlink_is_not_followed(tmp_path):
    target = tmp_path / "passwd"
    target.write_bytes(b"root:x:0:0")
    link = tmp_path / "bodies.jsonl"
    link.symlink_to(target)
    with pytest.raises(SinkError, match="symbolic link"):
        open_sink(f"jsonl://{link}", device=DEVICE)
    assert target.read_bytes() == b"root:x:0:0"


def test_rotation_prunes_only_its_own_rotated_files(tmp_path):
    path = tmp_path / "bodies.jsonl"
    others = {"bodies-important.jsonl": b"keep me\n", "bodies-2024-01-01.jsonl": b"keep me too",
              "bodies-20240101T000000.000000Z-00.jsonl.bak": b"and me"}
    for name, data in others.items():
        (tmp_path / name).write_bytes(data)
    one = len(record_line(0))
    sink = open_sink(f"jsonl://{path}?rotate_mb={one * 2.5 / 1e6}&keep=1", device=DEVICE)
    for seq in range(20):
        sink.publish_bodies(body_record(seq))
    rotated = sink.rotated_files()
    sink.close()
    assert len(rotated) == 1 and sink.rotations >= 5
    for name, data in others.items():
        assert (tmp_path / name).read_bytes() == data, name


def test_its_own_torn_tail_is_still_repaired(tmp_path):
    path = tmp_path / "bodies.jsonl"
    path.write_bytes(record_line(0) + record_line(1)[:40])
    sink = open_sink(f"jsonl://{path}", device=DEVICE)
    assert sink.stats()["repaired"] == 1
    sink.publish_bodies(body_record(1))
    sink.close()
    assert path.read_bytes() == record_line(0) + record_line(1)

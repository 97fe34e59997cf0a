"""jsonl:// files (rotation by size and time, flush policy, crash safety) and jsonl:- (stdout)."""

import json
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from sink_helpers import DEVICE, body_record

from edge.record import check_record
from edge.sinks import open_sink

REPO = Path(__file__).resolve().parents[3]


def read_lines(*paths):
    out = []
    for p in paths:
        data = Path(p).read_bytes()
        assert data == b"" or data.endswith(b"\n"), f"{p} ends in a partial line"
        out += [json.loads(line) for line in data.splitlines()]
    return out


def test_every_record_is_one_line_written_at_once(tmp_path):
    path = tmp_path / "out" / "bodies.jsonl"  # parent folders are created
    sink = open_sink(f"jsonl://{path}", device=DEVICE)
    for seq in range(5):
        sink.publish_bodies(body_record(seq, people=seq % 3))
        assert len(path.read_bytes().splitlines()) == seq + 1  # flush_ms=0: on disk before publish returns
    sink.publish_info({"model": "test-bundle@0123456789ab"})
    stats = sink.stats()
    sink.close()
    recs = read_lines(path)
    assert [r["seq"] for r in recs] == list(range(5))
    for r in recs:
        check_record(r)
    assert json.loads((tmp_path / "out" / "bodies.info.json").read_text())["model"] == "test-bundle@0123456789ab"
    assert stats["sent"] == 5 and stats["queued"] == 0 and stats["dropped"] == 0


def test_flush_ms_gathers_records_then_writes_them_together(tmp_path):
    path = tmp_path / "bodies.jsonl"
    sink = open_sink(f"jsonl://{path}?flush_ms=150", device=DEVICE)
    sink.publish_bodies(body_record(0))
    sink.publish_bodies(body_record(1))
    assert path.read_bytes() == b"" and sink.stats()["queued"] == 2
    time.sleep(0.2)
    sink.publish_bodies(body_record(2))  # the oldest waited > 150 ms: all three go out
    assert len(read_lines(path)) == 3 and sink.stats()["queued"] == 0
    sink.publish_bodies(body_record(3))
    sink.close()  # close writes what is gathered
    assert [r["seq"] for r in read_lines(path)] == [0, 1, 2, 3]


def test_rotation_by_size_keeps_whole_lines_and_prunes(tmp_path):
    path = tmp_path / "bodies.jsonl"
    one = len(json.dumps(body_record(0), separators=(",", ":"))) + 1
    sink = open_sink(f"jsonl://{path}?rotate_mb={one * 5.5 / 1e6}&keep=3", device=DEVICE)
    for seq in range(40):
        sink.publish_bodies(body_record(seq))
    rotated = sink.rotated_files()
    stats = sink.stats()
    sink.close()
    assert len(rotated) == 3 and stats["rotations"] >= 6  # ~5 records a file; older files deleted
    for p in rotated + [path]:
        assert p.stat().st_size <= one * 5.5
    seqs = [r["seq"] for r in read_lines(*rotated, path)]
    assert seqs == list(range(seqs[0], 40)) and 12 <= len(seqs) <= 22


def test_rotation_by_time(tmp_path):
    path = tmp_path / "bodies.jsonl"
    sink = open_sink(f"jsonl://{path}?rotate_s=0.3&keep=0", device=DEVICE)
    t0 = time.monotonic()
    seq = 0
    while time.monotonic() - t0 < 1.0:
        sink.publish_bodies(body_record(seq))
        seq += 1
        time.sleep(1 / 28)
    sink.close()
    rotated = sorted(tmp_path.glob("bodies-*.jsonl"))
    assert 2 <= len(rotated) <= 4
    assert [r["seq"] for r in read_lines(*rotated, path)] == list(range(seq))


WRITER = textwrap.dedent("""
    import sys
    sys.path.insert(0, {helpers!r})
    from sink_helpers import body_record
    from edge.sinks import open_sink
    sink = open_sink({url!r}, device="carpet-01")
    seq = 0
    while True:
        sink.publish_bodies(body_record(seq, people=1 + seq % 4))
        seq += 1
        if seq == 50:
            print("ready", flush=True)
""")


@pytest.mark.parametrize("flush_ms", [0, 5])
def test_no_partial_line_when_the_writer_is_killed(tmp_path, flush_ms):
    path = tmp_path / "bodies.jsonl"
    url = f"jsonl://{path}?flush_ms={flush_ms}&rotate_mb=0.2&keep=0"  # keep every rotated file: all seqs are checked
    proc = subprocess.Popen([sys.executable, "-c", WRITER.format(helpers=str(Path(__file__).parent), url=url)],
                            stdout=subprocess.PIPE, text=True, cwd=REPO)
    try:
        assert proc.stdout.readline().strip() == "ready"
        time.sleep(0.4)  # writing flat out, rotating every ~100 records
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=5)
    finally:
        if proc.poll() is None:
            proc.kill()
    files = sorted(tmp_path.glob("bodies-*.jsonl")) + [path]
    recs = read_lines(*files)  # every file ends with a newline; every line is JSON
    for r in recs:
        check_record(r)
    seqs = [r["seq"] for r in recs]
    assert len(seqs) > 50 and seqs == list(range(len(seqs)))


def test_a_torn_tail_left_by_a_power_cut_is_cut_off_on_reopen(tmp_path):
    path = tmp_path / "bodies.jsonl"
    sink = open_sink(f"jsonl://{path}", device=DEVICE)
    for seq in range(3):
        sink.publish_bodies(body_record(seq))
    sink.close()
    with open(path, "ab") as f:
        f.write(b'{"schema":"cavatar.bodies/1","device":"carpet-01","seq":3,"ti')  # the machine died here
    sink = open_sink(f"jsonl://{path}", device=DEVICE)
    assert sink.stats()["repaired"] == 1
    sink.publish_bodies(body_record(3))
    sink.close()
    assert [r["seq"] for r in read_lines(path)] == [0, 1, 2, 3]


def test_stdout_sink_writes_one_record_per_line(capsys):
    sink = open_sink("jsonl:-", device=DEVICE)
    for seq in range(3):
        sink.publish_bodies(body_record(seq, people=2))
    sink.publish_info({"model": "x@0123456789ab"})  # not on stdout: the stream is records only
    sink.close()
    out = capsys.readouterr().out
    lines = out.splitlines()
    assert len(lines) == 3 and out.endswith("\n")
    assert [json.loads(x)["seq"] for x in lines] == [0, 1, 2]


def test_stdout_sink_in_a_pipe():
    code = ("import sys; sys.path.insert(0, %r)\n"
            "from sink_helpers import body_record\nfrom edge.sinks import open_sink\n"
            "s = open_sink('jsonl:-', device='carpet-01')\n"
            "[s.publish_bodies(body_record(i)) for i in range(4)]\ns.close()\n") % str(Path(__file__).parent)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, cwd=REPO)
    assert proc.returncode == 0, proc.stderr
    assert [json.loads(x)["seq"] for x in proc.stdout.splitlines()] == [0, 1, 2, 3]


def test_jsonl_url_errors_show_the_accepted_form(tmp_path):
    for url in [f"jsonl://{tmp_path}/b.jsonl?rotate=1", "jsonl:-?rotate_mb=5", f"jsonl://{tmp_path}/b.jsonl?keep=-1",
                "jsonl://", "jsonlines:///x"]:
        with pytest.raises(ValueError) as err:
            open_sink(url, device=DEVICE)
        assert "jsonl:///path/bodies.jsonl" in str(err.value), url


def test_a_closed_sink_refuses_more_records(tmp_path):
    sink = open_sink(f"jsonl://{tmp_path}/b.jsonl", device=DEVICE)
    sink.close()
    sink.close()  # idempotent
    with pytest.raises(Exception, match="closed"):
        sink.publish_bodies(body_record(0))

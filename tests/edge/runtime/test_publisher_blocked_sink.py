"""A blocked sink holds back only itself: the other sinks, status, and shutdown go on (issue 18, finding 2)."""

from __future__ import annotations

import os
import sys
import threading
import time

import pytest

from edge.record import make_record
from edge.runtime.counters import PUBLISH_COUNTERS, Counters, StageTimes
from edge.runtime.publisher import Publisher
from edge.sinks.jsonl import JsonlSink


class BlockedSink:
    """Blocks in every publish until released (a pipe nobody reads, a hung broker)."""

    def __init__(self) -> None:
        self.release = threading.Event()
        self.entered = threading.Event()
        self.closed = False

    def describe(self) -> str:
        return "blocked://"

    def publish_status(self, online: bool) -> None:
        pass

    def publish_bodies(self, record) -> None:
        self.entered.set()
        self.release.wait(60)

    def publish_info(self, info) -> None:
        self.release.wait(60)

    def publish_presence(self, count, activities) -> None:
        self.release.wait(60)

    def close(self) -> None:
        self.closed = True


class ListSink(BlockedSink):
    def __init__(self) -> None:
        super().__init__()
        self.seqs: list[int] = []
        self.infos = 0

    def describe(self) -> str:
        return "list://"

    def publish_bodies(self, record) -> None:
        self.seqs.append(record["seq"])

    def publish_info(self, info) -> None:
        self.infos += 1

    def publish_presence(self, count, activities) -> None:
        pass


def _record(seq: int) -> dict:
    return make_record("carpet-01", seq, 1.0 + seq, "m@000000000000", [])


def test_a_blocked_sink_does_not_hold_back_the_others_nor_close():
    counters, times = Counters(PUBLISH_COUNTERS), StageTimes(64)
    blocked, good = BlockedSink(), ListSink()
    pub = Publisher([blocked, good], counters=counters, times=times, queue_records=8)
    pub.start()
    try:
        waited = 0.0
        for seq in range(40):
            t0 = time.monotonic()
            pub.put_record(_record(seq), time.time())
            waited = max(waited, time.monotonic() - t0)
            deadline = time.monotonic() + 10
            while len(good.seqs) <= seq and time.monotonic() < deadline:  # the good sink keeps up
                time.sleep(0.001)
        pub.put_info({"state": "running"})
        assert waited < 0.5  # the producer never waits on a sink
        assert blocked.entered.wait(10)
        deadline = time.monotonic() + 10
        while good.infos < 1 and time.monotonic() < deadline:
            time.sleep(0.01)
        assert good.seqs == list(range(40)) and good.infos == 1
        t0 = time.monotonic()
        pub.close(timeout_s=1.0)
        assert time.monotonic() - t0 < 3.0
        assert good.closed and not blocked.closed  # the stuck one is abandoned, the good one closed
        # the blocked sink's queue (8) overflowed: its oldest were dropped and counted; none reached every sink
        assert counters.get("queue_dropped") == 40 - 1 - 8
        assert pub.dropped_by_sink() == {"blocked://": 31, "list://": 0}
        assert counters.get("published") == 0
    finally:
        blocked.release.set()


def test_published_counts_records_every_sink_handled():
    counters, times = Counters(PUBLISH_COUNTERS), StageTimes(64)
    a, b = ListSink(), ListSink()
    pub = Publisher([a, b], counters=counters, times=times)
    pub.start()
    for seq in range(25):
        pub.put_record(_record(seq), time.time())
    pub.close(timeout_s=10.0)
    assert a.seqs == b.seqs == list(range(25)) and a.closed and b.closed
    assert counters.get("published") == 25 and pub.last_seq == 24 and counters.get("queue_dropped") == 0


def test_jsonl_stdout_blocked_on_a_full_pipe_still_answers_stats(monkeypatch):
    r, w = os.pipe()
    out = os.fdopen(w, "w")
    monkeypatch.setattr(sys, "stdout", out)
    sink = JsonlSink(None, "carpet-01")
    done = threading.Event()

    def write_a_lot() -> None:
        for seq in range(2000):  # ~200 KB: far beyond a pipe's 64 KB
            sink.publish_bodies(_record(seq))
        done.set()

    writer = threading.Thread(target=write_a_lot, daemon=True)
    writer.start()
    try:
        time.sleep(0.3)
        assert not done.is_set()  # the writer is blocked on the pipe
        got: list = []
        asker = threading.Thread(target=lambda: got.append(sink.stats()), daemon=True)
        asker.start()
        asker.join(2.0)
        assert got, "stats() waited on a blocked write"
        assert got[0]["queued"] >= 1
    finally:
        reader = threading.Thread(target=lambda: [None for _ in iter(lambda: os.read(r, 65536), b"")], daemon=True)
        reader.start()
        writer.join(10)
        monkeypatch.undo()
        out.close()
        reader.join(10)
        os.close(r)


def test_sigterm_finishes_while_jsonl_stdout_is_blocked_and_the_other_sink_keeps_going(tmp_path, sim_calibration):
    """The attack: `cavatar run --sink jsonl:- | sleep 600` (a reader that never reads), then SIGTERM."""
    import json
    import signal
    import subprocess

    from runtime_helpers import read_jsonl, sim_url

    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "edge", "run", "--source", sim_url(1), "--calibration", str(sim_calibration),
           "--sink", "jsonl:-", "--sink", f"jsonl://{out}/bodies.jsonl", "--status-file", str(out / "status.json"),
           "--quiet"]
    r, w = os.pipe()  # stdout: a pipe nobody reads (64 KB, ~60 records)
    proc = subprocess.Popen(cmd, cwd=tmp_path, stdout=w, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"})
    os.close(w)
    try:
        deadline = time.monotonic() + 90
        file_sink = out / "bodies.jsonl"
        while time.monotonic() < deadline:  # well past what the pipe holds: the file sink did not wait for stdout
            if file_sink.exists() and file_sink.read_bytes().count(b"\n") >= 100:
                break
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.2)
        else:
            pytest.fail("the file sink got fewer than 100 records within 90 s")
        status = json.loads((out / "status.json").read_text())
        assert time.time() - status["updated"] < 10  # the status file is still being written
        proc.send_signal(signal.SIGTERM)
        t0 = time.monotonic()
        _, err = proc.communicate(timeout=60)
        took = time.monotonic() - t0
    finally:
        if proc.poll() is None:
            proc.kill()
        os.close(r)
    assert proc.returncode == 0, err
    assert took < 20, f"SIGTERM took {took:.1f} s"  # a stuck sink is abandoned after 2 s; generous under load
    assert "jsonl:- still busy" in err and "Traceback" not in err
    records = read_jsonl(out / "bodies.jsonl")
    assert [r["seq"] for r in records] == list(range(len(records)))

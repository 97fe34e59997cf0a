"""The on-disk spool: FIFO, bounded (oldest dropped and counted), survives a restart of the runtime."""

import json
import time

from sink_helpers import DEVICE, Gate, body_record, wait_until

from edge.sinks import open_sink
from edge.sinks.spool import Spool, min_bytes


def line(seq: int) -> str:
    return json.dumps(body_record(seq))


def drain(spool):
    out = []
    while (got := spool.claim()) is not None:
        seg, lines = got
        out += [json.loads(x)["seq"] for x in lines]
        spool.remove(seg)
    return out


def test_fifo_in_segments(tmp_path):
    spool = Spool(tmp_path, max_bytes=10**6, segment_records=4)
    for i in range(10):
        assert spool.append(line(i))
    assert len(spool) == 10 and spool.open_records() == 2
    spool.seal()
    assert drain(spool) == list(range(10)) and len(spool) == 0
    assert not list(tmp_path.glob("*.spool"))


def test_bound_drops_the_oldest_and_counts_them(tmp_path):
    size = len(line(0)) + 1
    spool = Spool(tmp_path, max_bytes=min_bytes(5), segment_records=5)
    fit = min_bytes(5) // size
    for i in range(3 * fit):
        spool.append(line(i))
    spool.seal()
    kept = drain(spool)
    assert spool.dropped == 3 * fit - len(kept) and fit - 10 <= len(kept) <= fit
    assert kept == list(range(3 * fit - len(kept), 3 * fit))  # the newest survive, in order


def test_survives_a_restart_and_skips_a_torn_line(tmp_path):
    spool = Spool(tmp_path, max_bytes=10**6, segment_records=100)
    for i in range(7):
        spool.append(line(i))
    # the process dies here (no seal, no close); the power cut tore a half line onto the end
    with open(next(tmp_path.glob("*.spool")), "ab") as f:
        f.write(b'{"half')
    again = Spool(tmp_path, max_bytes=10**6)
    assert len(again) == 7
    again.prepend([line(100)])  # close-time rescue goes first
    assert drain(again) == [100] + list(range(7)) and again.torn == 1


def seqs(sub):
    return [json.loads(p)["seq"] for t, p, _, _ in sub.messages if t.endswith("/bodies")]


def test_records_spooled_while_away_are_sent_after_a_restart_of_the_runtime(broker, subscribe, tmp_path):
    """The broker is unreachable, the runtime stops (records stay in the spool), starts again: all arrive, in order."""
    sub = subscribe(broker.port, ["cavatar/+/bodies"])
    gate = Gate(broker.port)
    url = f"mqtt://127.0.0.1:{gate.port}/cavatar?qos=1&ha=0&retry_s=0.2&close_s=1&spool={tmp_path / 'spool'}"
    try:
        first = open_sink(url, device=DEVICE)
        assert first.wait_connected(10)
        for seq in range(10):
            first.publish_bodies(body_record(seq))
        assert first.flush(5)
        gate.close()
        assert wait_until(lambda: not first.connected, 5)
        for seq in range(10, 40):
            first.publish_bodies(body_record(seq))
        assert first.stats()["spooled"] == 30
        first.close()  # broker still away: nothing lost, it is all on disk
        assert sum(p.read_bytes().count(b"\n") for p in (tmp_path / "spool").glob("*.spool")) == 30

        gate.open()
        second = open_sink(url, device=DEVICE)
        for seq in range(40, 50):
            second.publish_bodies(body_record(seq))
            time.sleep(0.01)
        assert second.flush(10)
        assert wait_until(lambda: len(seqs(sub)) >= 50, 10)
        second.close()
    finally:
        gate.stop()
    got = seqs(sub)
    assert got == list(range(50))
    assert not list((tmp_path / "spool").glob("*.spool"))

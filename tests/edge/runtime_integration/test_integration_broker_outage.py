"""The broker goes away for 10 s while the runtime publishes at 14 Hz: QoS 1 + spool loses nothing,
QoS 0 loses the outage and counts exactly what it lost.

The runtime runs in-process on a board streaming the virtual carpet in real time (one person,
so every frame is a record), with two MQTT sinks on the same stream: ``qos=1&spool=DIR`` (prefix
q1) and ``qos=0`` (prefix q0). The observer is a paho subscriber with a persistent session
(clean session off, QoS 1). As in tests/edge/sinks/test_sink_mqtt_outage.py, the sinks reach
the broker through a TCP gate: the outage closes the gate and stops the broker; 10 s later the
broker starts again on the same port (its persistence keeps the observer's session), the
observer resubscribes, and only then the gate lets the sinks back in — mosquitto 2.0.11 now and
then fails to deliver an acknowledged message to a subscriber that reconnects in the same instant
as the publishers (docs/mqtt.md), an observer effect this order avoids.
Counted by ``seq`` (one more per record, heartbeats included: FrameStages._next_seq).
"""

import json
import time

import pytest
from integration_helpers import RATE_HZ, runtime_on_board, seq_report, wait_until
from runtime_helpers import make_config
from sink_helpers import Gate

BEFORE_S, OUTAGE_S, AFTER_S = 2.0, 10.0, 2.0

pytestmark = pytest.mark.slow  # a 10-s outage: ~20 s


def test_ten_second_outage_qos1_spool_loses_nothing_qos0_counts_its_losses(
        tmp_path, mqtt_broker, subscribe, sim_calibration, one_person_frames):
    broker = mqtt_broker()
    gate = Gate(broker.port)
    common = "ha=0&retry_s=0.25&keepalive=5&close_s=5"
    urls = [f"mqtt://127.0.0.1:{gate.port}/q1?qos=1&spool={tmp_path / 'spool'}&client_id=rt-q1&{common}",
            f"mqtt://127.0.0.1:{gate.port}/q0?qos=0&client_id=rt-q0&{common}"]
    sub = subscribe(broker.port, ["q1/carpet-01/bodies", "q0/carpet-01/bodies"], client_id="observer", persistent=True)
    rt = runtime_on_board(make_config(tmp_path, sim_calibration, 1, sinks=urls), one_person_frames, speed=1.0)
    marks = {}
    try:
        rt.setup()
        q1, q0 = rt.sinks
        assert q1.wait_connected(10) and q0.wait_connected(10)
        rt.start()
        t0 = time.monotonic()
        time.sleep(BEFORE_S)
        gate.close()
        sub.subscribed.clear()
        broker.stop()
        time.sleep(OUTAGE_S)
        broker.start()
        assert sub.subscribed.wait(10), "the observer did not come back"
        gate.open()
        marks["outage_s"] = round(time.monotonic() - t0 - BEFORE_S, 2)
        spool_peak = q1.stats()["spooled"]  # the whole outage is on disk now
        # the spool drains while the stream goes on
        assert wait_until(lambda: q1.connected and q0.connected and q1.stats()["spooled"] == 0, 20), q1.stats()
        marks["drained_after_s"] = round(time.monotonic() - t0 - BEFORE_S - marks["outage_s"], 2)
        time.sleep(AFTER_S)
        assert rt.wait(0) is False, rt.error  # still running
    finally:
        final = rt.stop()
        gate.stop()
    last = final["publish"]["last_seq"]

    def seqs(prefix):
        with sub.lock:
            return [json.loads(p)["seq"] for t, p, _, _ in sub.messages if t == f"{prefix}/carpet-01/bodies"]

    wait_until(lambda: seq_report(seqs("q1"), 0, last)["missing"] == 0, 10)
    time.sleep(0.3)
    r1, r0 = seq_report(seqs("q1"), 0, last), seq_report(seqs("q0"), 0, last)
    s1, s0 = (final["publish"]["sinks"][k] for k in final["publish"]["sinks"])
    print(f"\n{last + 1} records at {RATE_HZ:g} Hz, broker down {marks['outage_s']} s, spool peak {spool_peak}, "
          f"spool drained {marks['drained_after_s']} s after the broker came back\n"
          f"  qos1+spool: {r1}; sink counters {s1}\n  qos0: {r0}; sink counters {s0}")
    assert final["state"] == "stopped" and final["frames"]["frames_failed"] == 0
    assert final["frames"]["frames_people"] >= final["frames"]["frames_in"] - 5  # nearly every frame is a record
    assert final["publish"]["published"] == last + 1 and final["publish"]["queue_dropped"] == 0
    # QoS 1 + spool: every record arrives, first arrivals in order
    assert r1["missing"] == 0 and r1["in_order"], r1
    assert s1["dropped"] == 0 and spool_peak >= 0.7 * OUTAGE_S * RATE_HZ
    assert s1["spooled_total"] >= 0.7 * OUTAGE_S * RATE_HZ and s1["spooled"] == 0
    assert not list((tmp_path / "spool").glob("*.spool"))
    # QoS 0: the outage's records are lost, and the sink counted each one the subscriber misses — but one: a
    # record paho had already written to the socket when the link was cut is gone unknowingly (docs/mqtt.md)
    assert r0["missing"] >= 0.7 * OUTAGE_S * RATE_HZ
    assert s0["dropped"] <= r0["missing"] <= s0["dropped"] + 1, (r0, s0)
    assert r0["duplicates"] == 0 and r0["in_order"]

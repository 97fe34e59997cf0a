"""The broker goes away mid-stream at 14 Hz: what each delivery mode loses, counted by seq.

Three sinks publish the same 14 Hz stream at once (devices q0, q1spool, q1bounded)
through a TCP gate in front of mosquitto. The outage: the gate cuts the sinks off and the
broker is stopped; OUTAGE_S seconds later the broker starts again, the observer (a paho
subscriber connected to the broker directly) resubscribes, and only then the gate lets
the sinks back in, so the observer sees everything the broker accepted. (Without the
gate, a subscriber that reconnects in the same instant as the publishers, even with a
persistent session, now and then misses a message that mosquitto 2.0.11 had already
acknowledged: an observer effect, not a sink loss.) The issue asks for 10 s; 4 s shows
the same behaviour (the outage is many times disconnect detection, reconnect back-off
and the bounded queue) and keeps the suite fast; CAVATAR_TEST_OUTAGE_S=10 runs the 10 s one.

- QoS 0: everything published while disconnected is lost, and the sink counts it.
- QoS 1 + spool: nothing is lost; first arrivals are in order; duplicates are allowed
  (at-least-once) and counted.
- QoS 1 with a bounded client queue (max_queued=10): the queue keeps the first 10 of the
  outage, the rest are dropped and counted; exactly those are missing.
"""

import json
import os
import threading
import time

from sink_helpers import Gate, body_record, wait_until

from edge.sinks import open_sink

RATE_HZ = 14.0
BEFORE_S, AFTER_S = 1.5, 1.5
OUTAGE_S = float(os.environ.get("CAVATAR_TEST_OUTAGE_S", "4"))  # CAVATAR_TEST_OUTAGE_S=10 for the 10 s
N = int((BEFORE_S + OUTAGE_S + AFTER_S) * RATE_HZ)


def seqs_by_device(*subs):
    out: dict[str, list[int]] = {}
    for sub in subs:
        with sub.lock:
            for topic, payload, _, _ in sub.messages:
                rec = json.loads(payload)
                out.setdefault(rec["device"], []).append(rec["seq"])
    return out


def test_broker_outage_qos0_vs_qos1_spool_vs_bounded_queue(broker, subscribe, tmp_path):
    sub = subscribe(broker.port, ["cavatar/+/bodies"])
    gate = Gate(broker.port)

    def gate_url(query):
        return f"mqtt://127.0.0.1:{gate.port}/cavatar?{query}"

    common = "ha=0&retry_s=0.25&keepalive=5&close_s=5"
    sinks = {
        "q0": open_sink(gate_url(f"qos=0&{common}"), device="q0"),
        "q1spool": open_sink(gate_url(f"qos=1&spool={tmp_path / 'spool'}&{common}"), device="q1spool"),
        "q1bounded": open_sink(gate_url(f"qos=1&max_queued=10&{common}"), device="q1bounded"),
    }
    try:
        assert all(s.wait_connected(10) for s in sinks.values())
        t0 = time.monotonic()
        marks = {}

        def outage():
            time.sleep(BEFORE_S)
            marks["stop"] = time.monotonic() - t0
            gate.close()
            sub.subscribed.clear()
            broker.stop()
            time.sleep(OUTAGE_S)
            broker.start()
            assert sub.subscribed.wait(10), "observer did not come back"
            gate.open()
            marks["start"] = time.monotonic() - t0

        chaos = threading.Thread(target=outage)
        chaos.start()
        spool_peak = 0
        for seq in range(N):
            delay = t0 + seq / RATE_HZ - time.monotonic()
            if delay > 0:
                time.sleep(delay)
            for device, sink in sinks.items():
                sink.publish_bodies(body_record(seq, device=device))
            spool_peak = max(spool_peak, sinks["q1spool"].stats()["spooled"])
        chaos.join(timeout=20)
        assert sinks["q1spool"].flush(15) and sinks["q1bounded"].flush(15)
        wait_until(lambda: len(set(seqs_by_device(sub).get("q1spool", []))) == N, 15)
        wait_until(lambda: len(set(seqs_by_device(sub).get("q1bounded", []))) >= N - sinks["q1bounded"].stats()["dropped"], 5)
        time.sleep(0.3)
    finally:
        for s in sinks.values():
            s.close()
        gate.stop()

    got = seqs_by_device(sub)
    stats = {d: s.stats() for d, s in sinks.items()}
    report = {}
    for device in sinks:
        seqs = got.get(device, [])
        first: list[int] = []
        seen = set()
        for q in seqs:
            if q not in seen:
                seen.add(q)
                first.append(q)
        report[device] = {"missing": N - len(seen), "duplicates": len(seqs) - len(seen),
                          "in_order": first == sorted(first), "dropped_counted": stats[device]["dropped"],
                          "sent_counted": stats[device]["sent"], "missing_seqs": sorted(set(range(N)) - seen)[:8]}
    print(f"\n{N} records at {RATE_HZ} Hz, broker down {OUTAGE_S} s ({marks}); spool peak {spool_peak}")
    for device, r in report.items():
        print(f"  {device}: {r}")

    q0, q1s, q1b = report["q0"], report["q1spool"], report["q1bounded"]
    # QoS 0: the outage's records are gone, and the sink knows (give or take what was in the socket).
    assert q0["missing"] >= OUTAGE_S * RATE_HZ * 0.7
    assert 0 < q0["dropped_counted"] <= q0["missing"] <= q0["dropped_counted"] + 3
    # QoS 1 + spool: nothing lost, in order, the spool did the work and is empty again.
    assert q1s["missing"] == 0 and q1s["in_order"]
    assert q1s["dropped_counted"] == 0 and spool_peak >= OUTAGE_S * RATE_HZ * 0.7
    assert stats["q1spool"]["spooled"] == 0 and not list((tmp_path / "spool").glob("*.spool"))
    # QoS 1, bounded queue: exactly the counted drops are missing; the first ones of the outage survive.
    assert q1b["dropped_counted"] >= OUTAGE_S * RATE_HZ * 0.5
    assert q1b["missing"] == q1b["dropped_counted"] and q1b["in_order"]

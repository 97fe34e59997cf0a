"""Fall / person-down events through the sinks: a real mosquitto and a subscriber, the spool, JSON lines."""

import json

import pytest
from sink_helpers import DEVICE, Gate, body_record, wait_until

from edge.record import RecordError
from edge.runtime.events import event_payload
from edge.sinks import open_sink
from edge.topics import DeviceTopics

T = DeviceTopics("cavatar", DEVICE)


def fall(state: str, t: float = 1_732_240_010.0, kind: str = "fall") -> dict:
    ev = {"type": kind, "state": state, "t_s": 12.5, "track_id": 3}
    if state == "raised":
        ev.update(confidence=0.9, on_floor_s=0.9, arrival_s=1.1, position_m=[0.9, 0.7], area_m2=0.08, length_m=0.7)
    else:
        ev["reason"] = "up_or_gone"
    return event_payload(DEVICE, ev, t)


def test_events_reach_the_broker_and_a_subscriber_in_order(broker, subscribe):
    sub = subscribe(broker.port, [T.events])
    sink = open_sink(broker.url("qos=0&ha=0"), device=DEVICE)  # bodies at QoS 0; events still go at QoS 1
    try:
        assert sink.wait_connected(10)
        sink.publish_event(fall("raised"))
        sink.publish_event(fall("raised", kind="person_down"))
        sink.publish_event(fall("cleared", kind="person_down"))
        assert wait_until(lambda: len(sub.on(T.events)) == 3, 10)
    finally:
        sink.close()
    got = [json.loads(p) for p, _ in sub.on(T.events)]
    assert [(g["type"], g["state"]) for g in got] == [("fall", "raised"), ("person_down", "raised"),
                                                      ("person_down", "cleared")]
    assert all(g["schema"] == "cavatar.events/1" and g["device"] == DEVICE and g["track_id"] == 3 for g in got)
    assert got[0]["confidence"] == 0.9


def test_events_wait_in_the_spool_while_the_broker_is_away(broker, subscribe, tmp_path):
    """Spooled with the bodies in order; the drain sends each line to its own topic."""
    sub = subscribe(broker.port, [T.bodies, T.events])
    gate = Gate(broker.port)
    gate.close()  # the sink cannot reach the broker yet
    sink = open_sink(f"mqtt://127.0.0.1:{gate.port}/cavatar?qos=1&ha=0&retry_s=0.25&spool={tmp_path / 'spool'}",
                     device=DEVICE)
    try:
        sink.publish_bodies(body_record(0))
        sink.publish_event(fall("raised"))
        sink.publish_bodies(body_record(1))
        assert sink.stats()["spooled"] >= 2
        gate.open()
        assert sink.wait_connected(10) and sink.flush(10)
        assert wait_until(lambda: len(sub.on(T.events)) >= 1 and len(sub.on(T.bodies)) >= 2, 10)
    finally:
        sink.close()
        gate.stop()
    assert json.loads(sub.on(T.events)[0][0])["type"] == "fall"
    assert sorted(json.loads(p)["seq"] for p, _ in sub.on(T.bodies)) == [0, 1]


def test_jsonl_writes_events_beside_the_bodies(tmp_path):
    path = tmp_path / "bodies.jsonl"
    sink = open_sink(f"jsonl://{path}", device=DEVICE)
    sink.publish_bodies(body_record(0))
    sink.publish_event(fall("raised"))
    sink.close()
    assert all(json.loads(line)["schema"] == "cavatar.bodies/1" for line in path.read_text().splitlines())
    events = [json.loads(line) for line in (tmp_path / "bodies.events.jsonl").read_text().splitlines()]
    assert [(e["type"], e["state"]) for e in events] == [("fall", "raised")]


def test_an_event_carrying_sensor_data_or_another_device_is_refused(tmp_path):
    sink = open_sink(f"jsonl://{tmp_path / 'b.jsonl'}", device=DEVICE)
    bad = fall("raised")
    bad["pressure_kpa"] = [1.0, 2.0]
    with pytest.raises(RecordError):
        sink.publish_event(bad)
    with pytest.raises(RecordError):
        sink.publish_event(event_payload("someone-else", {"type": "fall", "state": "raised"}, 0.0))
    sink.close()
    assert not (tmp_path / "b.events.jsonl").exists() and sink.stats()["refused"] == 2

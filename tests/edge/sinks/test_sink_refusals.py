"""What every sink does before its scheme sees anything (edge.sinks.base): a refused record, info or event is
counted and raised, nothing written; a closed sink refuses records and events with SinkError."""

import pytest
from sink_helpers import DEVICE, body_record

from edge.record import RecordError
from edge.runtime.events import event_payload
from edge.sinks import SinkError, open_sink


def test_refusals_of_each_kind_are_counted_and_nothing_is_written(tmp_path):
    sink = open_sink(f"jsonl://{tmp_path / 'b.jsonl'}", device=DEVICE)
    with pytest.raises(RecordError, match="not this sink's device"):
        sink.publish_bodies(body_record(0, device="someone-else"))
    with pytest.raises(RecordError):
        sink.publish_info({"pressure_kpa": [1.0, 2.0]})
    with pytest.raises(RecordError, match="not a cavatar.events/1 payload"):
        sink.publish_event(event_payload("someone-else", {"type": "fall", "state": "raised"}, 0.0))
    sink.close()
    assert sink.stats()["refused"] == 3
    assert not (tmp_path / "b.jsonl").exists() or (tmp_path / "b.jsonl").read_text() == ""


def test_a_closed_sink_refuses_records_and_events(tmp_path):
    sink = open_sink(f"jsonl://{tmp_path / 'b.jsonl'}", device=DEVICE)
    sink.close()
    with pytest.raises(SinkError, match=r"jsonl:// sink is closed"):
        sink.publish_bodies(body_record(0))
    with pytest.raises(SinkError, match=r"jsonl:// sink is closed"):
        sink.publish_event(event_payload(DEVICE, {"type": "fall", "state": "cleared", "t_s": 1.0, "track_id": 1,
                                                  "reason": "up_or_gone"}, 0.0))
    assert sink.stats()["refused"] == 0

"""The runtime on the virtual carpet: valid records, increasing seq, heartbeats, only the work the scene needs."""

import json

import jsonschema
import numpy as np
import pytest
from runtime_helpers import read_jsonl

from edge.record import load_schema
from edge.runtime import Runtime
from edge.runtime.status import read_status


def test_two_people_give_valid_records_with_increasing_seq(two_people_run):
    out, final, outcomes, _ = two_people_run
    records = read_jsonl(out / "bodies.jsonl")
    validator = jsonschema.Draft202012Validator(load_schema())
    for rec in records:
        validator.validate(rec)
    seqs = [r["seq"] for r in records]
    assert seqs == list(range(seqs[0], seqs[0] + len(seqs)))  # one by one: a gap would be a loss
    assert final["frames"]["frames_in"] == 60 and final["frames"]["frames_failed"] == 0
    with_people = [r for r in records if r["people"]]
    assert len(with_people) == final["frames"]["frames_people"] >= 50
    assert sum(len(r["people"]) == 2 for r in with_people) >= 45
    assert len(records) == final["publish"]["published"] == final["publish"]["records"] + final["publish"]["heartbeats"]
    assert {r["model"] for r in records} == {final["model"]["version"]} and final["model"]["version"].startswith("lean-96@")
    # the published time is the frame's (wall clock when it was complete), increasing
    times = [r["time"] for r in records]
    assert times == sorted(times)
    # every record came from one frame, in order
    frame_seqs = [o.frame.frame_seq for o in outcomes if o.record is not None]
    assert frame_seqs == sorted(frame_seqs) and len(frame_seqs) == len(records)


def test_status_file_says_stopped_with_every_counter(two_people_run):
    out, final, _, _ = two_people_run
    status = read_status(out / "status.json")
    assert status["state"] == "stopped" and status["error"] is None and status["end_reason"] == "frame limit"
    assert status["frames"]["frames_in"] == 60
    for stage in ("decode", "calibrate", "scene", "encoder", "head", "record", "frame", "publish", "lag"):
        assert status["stages_ms"][stage]["n"] > 0 and status["stages_ms"][stage]["median_ms"] >= 0, stage
    q = status["source"]
    assert q["queue"]["dropped_slow_consumer"] == 0  # speed=0: the sim waits for the pipeline
    assert q["decoder"]["dropped_total"] == 0 and "bad_crc" not in q["decoder"]["dropped"]
    assert q["board"]["device_id"] == "sim-7" and q["board"]["rows"] == 96
    assert status["calibration"]["automatic"] is False and status["calibration"]["due"] is False
    sink = status["publish"]["sinks"][f"jsonl://{out}/bodies.jsonl"]
    assert sink["sent"] == status["publish"]["published"] and sink["dropped"] == 0
    assert status["publish"]["last_seq"] == read_jsonl(out / "bodies.jsonl")[-1]["seq"]
    info = json.loads((out / "bodies.info.json").read_text())
    assert info["schema"] == "cavatar.info/1" and info["state"] == "stopped"
    assert info["health"]["frames_in"] == 60 and info["calibration"]["sha256"] == status["calibration"]["sha256"]


def test_one_inference_per_person_and_still_people_reuse_their_result(two_people_run):
    _, final, _, inputs = two_people_run
    w = final["work"]
    assert w["person_frames"] == w["encoder_runs"] + w["still_reuses"]
    assert w["head_runs"] == w["encoder_runs"] > 0
    assert sum(len(x) for x in inputs) == w["encoder_runs"]  # batched: one encoder input per person that changed
    assert w["saved"]["encoder_runs"] == w["still_reuses"]
    assert w["tracks_started"] >= 2 and w["tracks_open"] == w["tracks_started"] - w["tracks_freed"]
    assert final["frames"]["frames_empty"] + final["frames"]["frames_unconfirmed"] == w["saved"]["frames_without_inference"]


def test_model_inputs_are_one_person_each_prepared_as_in_training(two_people_run):
    _, _, _, inputs = two_people_run
    x = np.concatenate(inputs)[:, 0]  # (N, 96, 96) normalised
    p = np.expm1(x)  # back to kPa
    assert x.dtype == np.float32 and np.all(x >= 0)
    loaded = p[p > 0]
    assert loaded.min() >= 0.2 - 1e-4 and loaded.max() <= 14.0 + 1e-4  # the training floor and saturation
    two = [b for b in inputs if len(b) == 2]
    assert two, "no frame with two people encoded together"
    a, b = np.expm1(two[0][0, 0]), np.expm1(two[0][1, 0])
    assert not np.any((a > 0) & (b > 0))  # each person's input holds only their own sensels


def test_an_empty_carpet_sends_heartbeats_once_a_second_and_runs_no_model(config, tmp_path):
    final = Runtime(config(people=0), say=lambda text: None).run_for(frames=60)
    records = read_jsonl(tmp_path / "bodies.jsonl")
    assert all(r["people"] == [] for r in records)
    # 60 frames at 14 Hz = 4.2 s of frame time: heartbeats at 0, 1, 2, 3 and 4 s
    assert len(records) == final["publish"]["heartbeats"] == 5
    w = final["work"]
    assert w["encoder_runs"] == w["head_runs"] == w["person_frames"] == 0
    assert final["frames"]["frames_empty"] == 60 == w["saved"]["frames_without_inference"]
    assert final["stages_ms"]["encoder"]["n"] == 0


def test_seq_continues_across_runs_with_the_same_status_file(config, tmp_path):
    Runtime(config(people=0), say=lambda text: None).run_for(frames=20)
    Runtime(config(people=0), say=lambda text: None).run_for(frames=20)
    seqs = [r["seq"] for r in read_jsonl(tmp_path / "bodies.jsonl")]
    assert seqs == list(range(len(seqs))) and len(seqs) == 4


def test_the_runtime_publishes_to_mqtt_with_the_password_from_the_environment(mqtt_broker, config, tmp_path,
                                                                              monkeypatch):
    from sink_helpers import Subscriber

    broker = mqtt_broker(users={"cavatar": "s3cret", "watcher": "w"})
    sub = Subscriber(broker.port, ["cavatar/#"], username="watcher", password="w")
    try:
        monkeypatch.setenv("CAVATAR_MQTT_PASSWORD", "s3cret")
        cfg = config(people=1, sinks=[broker.url("qos=1", user="cavatar")], device="hall-1")
        final = Runtime(cfg, say=lambda text: None).run_for(frames=25)
        assert sub.wait_for("cavatar/hall-1/status", b"offline")
        bodies = [json.loads(p) for p, _ in sub.on("cavatar/hall-1/bodies")]
        assert len(bodies) == final["publish"]["published"] > 0
        assert [b["seq"] for b in bodies] == sorted(b["seq"] for b in bodies)
        assert [p for p, _ in sub.on("cavatar/hall-1/status")][0] == b"online"
        info = json.loads(sub.on("cavatar/hall-1/info")[-1][0])
        assert info["schema"] == "cavatar.info/1" and info["model"] == final["model"]["version"]
        assert sub.on("cavatar/hall-1/presence")
    finally:
        sub.close()
    assert "s3cret" not in (tmp_path / "status.json").read_text()


@pytest.fixture
def mqtt_broker(tmp_path):
    from sink_helpers import brokers

    yield from brokers(tmp_path)

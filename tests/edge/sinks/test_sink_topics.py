"""edge/topics.py is the one place topics are spelled, and docs/mqtt.md lists all of them."""

import re
from pathlib import Path

import pytest

from edge import topics
from edge.ha_discovery import discovery
from edge.sinks import jsonl, mqtt
from edge.topics import DeviceTopics

REPO = Path(__file__).resolve().parents[3]
DOC = (REPO / "docs" / "mqtt.md").read_text()


def test_device_topics():
    t = DeviceTopics("site/floor2", "carpet-01")
    assert (t.status, t.info, t.bodies, t.presence) == (
        "site/floor2/carpet-01/status", "site/floor2/carpet-01/info",
        "site/floor2/carpet-01/bodies", "site/floor2/carpet-01/presence")
    assert t.all == "site/floor2/carpet-01/#"
    assert [topic for topic, _ in discovery(t)] == [
        "homeassistant/binary_sensor/carpet-01_presence/config",
        "homeassistant/sensor/carpet-01_people/config",
        "homeassistant/sensor/carpet-01_activity/config",
        "homeassistant/binary_sensor/carpet-01_board/config",
        "homeassistant/sensor/carpet-01_fps/config",
        "homeassistant/binary_sensor/carpet-01_calibration_due/config",
        "homeassistant/sensor/carpet-01_dropped_frames/config",
        "homeassistant/sensor/carpet-01_runtime_state/config"]


@pytest.mark.parametrize("prefix,device", [("cav+atar", "c1"), ("cavatar/#", "c1"), ("/cavatar", "c1"),
                                           ("cavatar//x", "c1"), ("cavatar", "c/1"), ("cavatar", ""), ("cavatar", "c 1")])
def test_wildcards_and_empty_levels_are_refused(prefix, device):
    with pytest.raises(ValueError, match="not usable"):
        DeviceTopics(prefix, device)


def test_presence_payload():
    p = topics.presence_payload("c1", 3, ["squat", "walking", "squat"], 10.0)
    assert p == {"schema": "cavatar.presence/1", "device": "c1", "time": 10.0, "present": True, "count": 3,
                 "activity": "squat", "activities": ["squat", "walking", "squat"]}
    assert topics.presence_payload("c1", 0, [], 10.0)["activity"] == "none"
    with pytest.raises(ValueError):
        topics.presence_payload("c1", -1, [], 0.0)


def test_the_doc_lists_every_topic_and_every_option():
    for spec in topics.TOPICS:
        assert f"`{spec.pattern}`" in DOC, spec.pattern
    for name in mqtt.OPTIONS:
        assert re.search(rf"\| `{name}`|`{name}`, `|, `{name}` \|", DOC), name
    for name in jsonl.OPTIONS:
        assert f"{name}=" in DOC, name
    assert "mosquitto_sub" in DOC and "CAVATAR_MQTT_PASSWORD" in DOC


def test_no_other_module_spells_a_topic():
    """Topic strings live in edge/topics.py only (style: one module for topics)."""
    offenders = []
    for path in (REPO / "edge").rglob("*.py"):
        if path.name == "topics.py":
            continue
        text = path.read_text()
        for pattern in (r"[\"'][^\"'\n]*/(status|bodies|presence|info)[\"']", r"[\"']homeassistant/"):
            if re.search(pattern, text):
                offenders.append(f"{path.relative_to(REPO)}: {pattern}")
    assert not offenders, offenders

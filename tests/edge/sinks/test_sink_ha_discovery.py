"""Home Assistant discovery payloads (issue 17, finding 5) checked against a schema written from Home Assistant's
documentation (ha_discovery.schema.json: sensor and binary_sensor options, device and origin blocks, availability,
device classes, enum sensors, object_id → default_entity_id), and their templates rendered as Home Assistant
renders them (Jinja2, ``value_json``) against the payloads this runtime publishes."""

import json
from pathlib import Path

import jinja2
import jsonschema
import pytest

from edge.ha_discovery import RUNTIME_STATES, discovery, entity_slug
from edge.topics import DeviceTopics, presence_payload

SCHEMA = json.loads((Path(__file__).parent / "ha_discovery.schema.json").read_text())
ACTIVITIES = ["stepping", "squat", "walking", "standing"]


def validator(component):
    schema = {**SCHEMA, "$ref": f"#/$defs/{component}"}
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def render(template, payload):
    return jinja2.Environment().from_string(template).render(value_json=payload).strip()


@pytest.mark.parametrize("activities", [None, ACTIVITIES])
@pytest.mark.parametrize("device", ["carpet-01", "Floor.2_west"])
def test_every_payload_validates_against_the_documented_schema(device, activities):
    t = DeviceTopics("site/floor2", device)
    configs = discovery(t, sw_version="1.2.3", activities=activities)
    for topic, payload in configs:
        component = topic.split("/")[1]
        errors = sorted(validator(component).iter_errors(payload), key=str)
        assert not errors, (topic, [e.message for e in errors])
        assert payload["default_entity_id"].startswith(f"{component}.{entity_slug(device)}_")
        assert topic == f"homeassistant/{component}/{device}_{payload['unique_id'].rsplit(device + '_', 1)[1]}/config"
    assert len({p["unique_id"] for _, p in configs}) == len({p["default_entity_id"] for _, p in configs}) == len(configs)


def test_the_schema_refuses_what_home_assistant_refuses():
    t = DeviceTopics("cavatar", "c1")
    good = dict(discovery(t, activities=ACTIVITIES))
    sensor, binary = validator("sensor"), validator("binary_sensor")
    activity = good["homeassistant/sensor/c1_activity/config"]
    assert not list(sensor.iter_errors(activity))
    for broken in ({**activity, "object_id": "c1_activity"},                     # deprecated in 2025.10
                   {k: v for k, v in activity.items() if k != "origin"},
                   {k: v for k, v in activity.items() if k != "options"},        # an enum needs its options
                   {**activity, "state_class": "measurement"},                   # an enum has no state class
                   {**activity, "availability_mode": "both"},
                   {**activity, "default_entity_id": "sensor.C1-activity"},
                   {**activity, "frobnicate": 1}):
        assert list(sensor.iter_errors(broken)), broken
    board = good["homeassistant/binary_sensor/c1_board/config"]
    assert not list(binary.iter_errors(board))
    assert list(binary.iter_errors({**board, "device_class": "plugged_in"}))


def test_templates_give_states_home_assistant_accepts():
    t = DeviceTopics("cavatar", "c1")
    configs = {topic.split("/")[2].split("_", 1)[1]: p for topic, p in discovery(t, activities=ACTIVITIES)}
    present = presence_payload("c1", 2, ["squat", "walking", "squat"], 10.0)
    empty = presence_payload("c1", 0, [], 11.0)
    assert render(configs["presence"]["value_template"], present) == "ON"
    assert render(configs["presence"]["value_template"], empty) == "OFF"
    assert render(configs["people"]["value_template"], present) == "2"
    for payload in (present, empty):
        assert render(configs["activity"]["value_template"], payload) in configs["activity"]["options"]
    info = {"state": "running", "calibration": {"due": True},
            "health": {"fps": 13.9, "frames_dropped": 3, "frames_lost_on_link": 4}}
    assert float(render(configs["fps"]["value_template"], info)) == 13.9
    assert render(configs["calibration_due"]["value_template"], info) == "ON"
    assert render(configs["dropped_frames"]["value_template"], info) == "7"
    for state in RUNTIME_STATES:
        assert render(configs["runtime_state"]["value_template"], {**info, "state": state}) in configs["runtime_state"]["options"]
    assert configs["board"]["payload_on"] == "online" and configs["board"]["state_topic"] == t.board


def test_an_entity_added_elsewhere_gets_the_same_conventions():
    """edge.ha_discovery.entity_config is how another part (e.g. fall events) adds an entity: it validates too."""
    from edge.ha_discovery import carpet_availability, entity_config

    t = DeviceTopics("cavatar", "c1")
    topic, payload = entity_config(t, "binary_sensor", "person_down", {
        "state_topic": f"{t.base}/events", **carpet_availability(t), "name": "Person down", "device_class": "problem",
        "value_template": "{{ 'ON' if value_json.active else 'OFF' }}", "payload_on": "ON", "payload_off": "OFF"},
        sw_version="1.2.3")
    assert topic == "homeassistant/binary_sensor/c1_person_down/config"
    assert not list(validator("binary_sensor").iter_errors(payload))
    assert payload["device"] == dict(discovery(t, sw_version="1.2.3"))[
        "homeassistant/binary_sensor/c1_presence/config"]["device"]  # one device in Home Assistant

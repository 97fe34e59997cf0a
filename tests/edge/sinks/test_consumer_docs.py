"""The consumer's pages stay true to the code (issue 17, finding 7): docs/record-schema.md lists every record field,
the joint order and the shipped model's activity labels; docs/home-assistant.md names every discovered entity."""

import json
import re
from pathlib import Path

from edge.body import SMPL_JOINT_NAMES, SMPL_PARENTS
from edge.ha_discovery import discovery
from edge.record import PERSON_KEYS
from edge.runtime.config import default_bundle_path
from edge.topics import DeviceTopics

DOCS = Path(__file__).resolve().parents[3] / "docs"
SCHEMA = (DOCS / "record-schema.md").read_text()
HA = (DOCS / "home-assistant.md").read_text()


def test_the_record_page_lists_fields_joints_in_order_and_activities():
    for key in ("schema", "device", "seq", "time", "model", "people", *(f"people[].{k}" for k in PERSON_KEYS)):
        assert f"| `{key}` |" in SCHEMA, key
    rows = re.findall(r"^\| (\d+) \| `(\w+)` \| (\S+) \| (\d+)–(\d+) \|$", SCHEMA, re.M)
    assert [(int(i), name) for i, name, *_ in rows] == list(enumerate(SMPL_JOINT_NAMES))
    for i, name, parent, lo, hi in rows:
        i = int(i)
        assert parent == (SMPL_JOINT_NAMES[SMPL_PARENTS[i]] if SMPL_PARENTS[i] >= 0 else "—")
        assert (int(lo), int(hi)) == (3 * i, 3 * i + 2)
    activities = json.loads((default_bundle_path() / "manifest.json").read_text())["activities"]
    assert re.findall(r"^\| `(\w+)` \| ", SCHEMA.split("## Activity labels")[1], re.M) == activities


def test_the_home_assistant_page_names_every_entity_and_label():
    activities = json.loads((default_bundle_path() / "manifest.json").read_text())["activities"]
    for _, payload in discovery(DeviceTopics("cavatar", "carpet-01"), activities=activities):
        assert f"`{payload['default_entity_id']}`" in HA, payload["default_entity_id"]
    for label in activities:
        assert f"`{label}`" in HA, label
    for entity in re.findall(r"entity_id: (\S+)", HA):  # the automations use entities that exist
        assert f"`{entity}`" in HA, entity


def test_the_discovery_example_in_the_mqtt_page_is_what_is_sent():
    text = (DOCS / "mqtt.md").read_text()
    example = json.loads(text.split("Home Assistant discovery (one of eight")[1].split("```json")[1].split("```")[0])
    sent = dict(discovery(DeviceTopics("cavatar", "carpet-01"), sw_version="0.1.0"))
    assert example == sent["homeassistant/binary_sensor/carpet-01_presence/config"]

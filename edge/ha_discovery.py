"""Home Assistant MQTT discovery: the entities a carpet shows, as retained config payloads.

Follows Home Assistant's MQTT discovery conventions as of 2025.10 (the test checks every
payload against a schema written from its documentation, tests/edge/sinks/ha_discovery.schema.json):
``default_entity_id`` (``<domain>.<slug>``; ``object_id`` is deprecated and stops working in
2026.4), an ``origin`` block naming the software that publishes, one ``device`` shared by all.

The carpet's entities (from the retained presence topic) — available only while the runtime
(status) AND the board (frames arriving) are online, so an unplugged board turns them
unavailable instead of leaving "Occupied" on screen:

    binary_sensor  presence          occupancy
    sensor         people            count of people now
    sensor         activity          enum: the model's activity labels, and "none" when empty

Diagnostic entities (``entity_category: diagnostic``; available while the runtime is):

    binary_sensor  board             connectivity, from the board topic
    sensor         fps               frames per second (info.health.fps)
    binary_sensor  calibration_due   problem (info.calibration.due)
    sensor         dropped_frames    frames dropped or lost on the link (info.health)
    sensor         runtime_state     enum: running, stopping, stopped, failed (info.state)

Topic strings come from :class:`edge.topics.DeviceTopics`; docs/home-assistant.md shows them.
"""

from __future__ import annotations

import re
from typing import Any, Sequence

from edge.topics import NO_ACTIVITY, OFFLINE, ONLINE, DeviceTopics

ORIGIN_NAME = "CAvatar Edge"
RUNTIME_STATES = ("running", "stopping", "stopped", "failed")


def entity_slug(device: str) -> str:
    """A device id as the object part of an entity id: lower case letters, digits and underscores."""
    return re.sub(r"[^a-z0-9_]", "_", f"cavatar_{device}".lower())


def _availability(*topics: str) -> list[dict[str, str]]:
    return [{"topic": t, "payload_available": ONLINE, "payload_not_available": OFFLINE} for t in topics]


def carpet_availability(t: DeviceTopics) -> dict[str, Any]:
    """Availability of an entity that reports what is on the carpet: the runtime AND the board must be online."""
    return {"availability": _availability(t.status, t.board), "availability_mode": "all"}


def entity_config(t: DeviceTopics, component: str, object_id: str, fields: dict[str, Any],
                  sw_version: str = "") -> tuple[str, dict]:
    """(config topic, payload) of one entity, with what every CAvatar entity carries: unique_id, default_entity_id,
    the shared device and the origin. ``fields``: the entity's own options (state_topic, availability, name, …).
    For entities added elsewhere (e.g. events), so that they follow the same conventions."""
    device: dict[str, Any] = {"identifiers": [f"cavatar_{t.device}"], "name": f"CAvatar {t.device}",
                              "manufacturer": "CAvatar", "model": "CAvatar Edge carpet"}
    origin: dict[str, Any] = {"name": ORIGIN_NAME}
    if sw_version:
        device["sw_version"] = sw_version
        origin["sw_version"] = sw_version
    payload = {"unique_id": f"cavatar_{t.device}_{object_id}",
               "default_entity_id": f"{component}.{entity_slug(t.device)}_{object_id}",
               **fields, "device": device, "origin": origin}
    return t.ha_config_topic(component, object_id), payload


def discovery(t: DeviceTopics, sw_version: str = "", activities: Sequence[str] | None = None) -> list[tuple[str, dict]]:
    """(config topic, payload) of every entity. ``activities``: the model's labels (info.activities); without them
    the activity sensor is plain text (still valid), with them an ``enum`` whose options are the labels and "none"."""
    carpet = {"state_topic": t.presence, **carpet_availability(t)}
    runtime = {"availability": _availability(t.status)}
    diagnostic = {"state_topic": t.info, "entity_category": "diagnostic", **runtime}
    activity: dict[str, Any] = {"name": "Activity", "icon": "mdi:run", "value_template": "{{ value_json.activity }}"}
    if activities:
        activity.update(device_class="enum", options=list(dict.fromkeys([*activities, NO_ACTIVITY])))
    entities: list[tuple[str, str, dict[str, Any]]] = [
        ("binary_sensor", "presence", {**carpet, "name": "Presence", "device_class": "occupancy",
                                       "value_template": "{{ 'ON' if value_json.present else 'OFF' }}",
                                       "payload_on": "ON", "payload_off": "OFF"}),
        ("sensor", "people", {**carpet, "name": "People", "icon": "mdi:account-group", "state_class": "measurement",
                              "unit_of_measurement": "people", "value_template": "{{ value_json.count }}"}),
        ("sensor", "activity", {**carpet, **activity}),
        ("binary_sensor", "board", {**runtime, "state_topic": t.board, "name": "Board connected",
                                    "device_class": "connectivity", "entity_category": "diagnostic",
                                    "payload_on": ONLINE, "payload_off": OFFLINE}),
        ("sensor", "fps", {**diagnostic, "name": "Frame rate", "device_class": "frequency", "unit_of_measurement": "Hz",
                           "state_class": "measurement", "suggested_display_precision": 1,
                           "value_template": "{{ value_json.health.fps }}"}),
        ("binary_sensor", "calibration_due", {**diagnostic, "name": "Calibration due", "device_class": "problem",
                                              "value_template": "{{ 'ON' if value_json.calibration.due else 'OFF' }}",
                                              "payload_on": "ON", "payload_off": "OFF"}),
        ("sensor", "dropped_frames", {**diagnostic, "name": "Dropped frames", "icon": "mdi:alert-circle-outline",
                                      "state_class": "total_increasing", "unit_of_measurement": "frames",
                                      "value_template": "{{ value_json.health.frames_dropped "
                                                        "+ value_json.health.frames_lost_on_link }}"}),
        ("sensor", "runtime_state", {**diagnostic, "name": "Runtime state", "device_class": "enum",
                                     "options": list(RUNTIME_STATES), "value_template": "{{ value_json.state }}"}),
    ]
    return [entity_config(t, component, object_id, fields, sw_version) for component, object_id, fields in entities]


__all__ = ["RUNTIME_STATES", "carpet_availability", "discovery", "entity_config", "entity_slug"]

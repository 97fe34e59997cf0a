"""Every MQTT topic CAvatar Edge publishes, and the small payloads that go with them.

This is the one module that spells topic strings (docs/mqtt.md is the one page that
lists them; a test keeps the two in step)::

    <prefix>/<device>/status    "online" / "offline"   QoS 1, retained, also the last will
    <prefix>/<device>/info      JSON                   QoS 1, retained
    <prefix>/<device>/bodies    cavatar.bodies/1       QoS from the sink URL, not retained
    <prefix>/<device>/presence  cavatar.presence/1     QoS 1, retained, published on change
    <prefix>/<device>/board     "online" / "offline"   QoS 1, retained: frames arriving from the board
    homeassistant/<component>/<device>_<entity>/config     Home Assistant discovery, QoS 1,
                                                           retained (edge/ha_discovery.py)

    t = DeviceTopics("cavatar", "carpet-01")
    t.status            # 'cavatar/carpet-01/status'
    discovery(t)        # [(topic, payload dict), ...]: edge.ha_discovery, which builds on these names
"""

from __future__ import annotations

import re
from collections import Counter
from dataclasses import dataclass
from typing import Sequence

DEFAULT_PREFIX = "cavatar"
HA_PREFIX = "homeassistant"
ONLINE = "online"
OFFLINE = "offline"
PRESENCE_SCHEMA = "cavatar.presence/1"
EVENTS_SCHEMA = "cavatar.events/1"  # fall / person-down events (edge.runtime.events)
INFO_SCHEMA = "cavatar.info/1"
NO_ACTIVITY = "none"

_LEVEL = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$")


@dataclass(frozen=True)
class TopicSpec:
    """One row of the topic table (docs/mqtt.md is written from these)."""

    pattern: str
    payload: str
    qos: str
    retain: bool
    doc: str


TOPICS: tuple[TopicSpec, ...] = (
    TopicSpec("<prefix>/<device>/status", '"online" | "offline" (plain text)', "1", True,
              "Availability. \"online\" on every connect; \"offline\" published before a clean stop and "
              "set as the last will, so the broker publishes it when the runtime dies or hangs."),
    TopicSpec("<prefix>/<device>/info", "JSON, schema cavatar.info/1", "1", True,
              "Model, body model, calibration age, protocol and firmware versions, health counters. "
              "Republished on every connect and when the runtime updates it."),
    TopicSpec("<prefix>/<device>/bodies", "JSON, schema cavatar.bodies/1", "URL ?qos= (default 1)", False,
              "The stream: one record per frame with people, a heartbeat (people: []) when empty."),
    TopicSpec("<prefix>/<device>/presence", "JSON, schema cavatar.presence/1", "1", True,
              "Low-rate derived state, published when the people count or the activities change; "
              "withdrawn (count 0) when the board is lost."),
    TopicSpec("<prefix>/<device>/board", '"online" | "offline" (plain text)', "1", True,
              "Board availability: \"online\" while frames arrive, \"offline\" after [source] board_timeout_s "
              "without a good frame (unplugged, hung, bad CRCs) and on a clean stop."),
    TopicSpec("<prefix>/<device>/events", "JSON, schema cavatar.events/1", "URL ?qos= (at least 1)", False,
              "Fall and person-down events, raised and cleared (docs/falls.md); spooled while the broker is away."),
    TopicSpec("homeassistant/binary_sensor/<device>_person_down/config", "JSON, Home Assistant discovery", "1", True,
              "Person-down binary sensor from the events topic; availability = status topic."),
    TopicSpec("homeassistant/event/<device>_fall/config", "JSON, Home Assistant discovery", "1", True,
              "Fall event entity from the events topic; availability = status topic."),
    TopicSpec("homeassistant/binary_sensor/<device>_presence/config", "JSON, Home Assistant discovery", "1", True,
              "Occupancy binary sensor from presence.present; available while status and board are online."),
    TopicSpec("homeassistant/sensor/<device>_people/config", "JSON, Home Assistant discovery", "1", True,
              "People count sensor from presence.count; available while status and board are online."),
    TopicSpec("homeassistant/sensor/<device>_activity/config", "JSON, Home Assistant discovery", "1", True,
              "Activity sensor (enum of the model's labels and none) from presence.activity; available while status "
              "and board are online."),
    TopicSpec("homeassistant/binary_sensor/<device>_board/config", "JSON, Home Assistant discovery", "1", True,
              "Diagnostic: board connected (connectivity) from the board topic; available while status is online."),
    TopicSpec("homeassistant/sensor/<device>_fps/config", "JSON, Home Assistant discovery", "1", True,
              "Diagnostic: frames per second from info.health.fps."),
    TopicSpec("homeassistant/binary_sensor/<device>_calibration_due/config", "JSON, Home Assistant discovery", "1",
              True, "Diagnostic: calibration due (problem) from info.calibration.due."),
    TopicSpec("homeassistant/sensor/<device>_dropped_frames/config", "JSON, Home Assistant discovery", "1", True,
              "Diagnostic: frames dropped or lost on the link, from info.health."),
    TopicSpec("homeassistant/sensor/<device>_runtime_state/config", "JSON, Home Assistant discovery", "1", True,
              "Diagnostic: runtime state (enum running/stopping/stopped/failed) from info.state."),
    TopicSpec("homeassistant/status", '"online" (subscribed)', "1", False,
              "Home Assistant's birth message; on \"online\" the discovery configs are republished."),
)


def check_level(text: str, what: str) -> str:
    """A device id used as one topic level: letters, digits, _ . - (no /, +, #)."""
    if not isinstance(text, str) or not _LEVEL.match(text):
        raise ValueError(f"{what} {text!r} is not usable in an MQTT topic: use 1-64 of A-Z a-z 0-9 _ . - (starting with a letter or digit)")
    return text


def check_prefix(prefix: str, what: str = "topic prefix") -> str:
    """A prefix of one or more levels (``cavatar``, ``site/floor2``): no wildcards, no empty levels."""
    if not isinstance(prefix, str) or not prefix or any(not _LEVEL.match(level) for level in prefix.split("/")):
        raise ValueError(f"{what} {prefix!r} is not usable: levels of A-Z a-z 0-9 _ . - separated by '/', no wildcards, no empty levels")
    return prefix


@dataclass(frozen=True)
class DeviceTopics:
    """The topics of one device under one prefix."""

    prefix: str = DEFAULT_PREFIX
    device: str = "carpet-01"
    ha_prefix: str = HA_PREFIX

    def __post_init__(self) -> None:
        check_prefix(self.prefix)
        check_level(self.device, "device id")
        check_prefix(self.ha_prefix, "Home Assistant discovery prefix")

    @property
    def base(self) -> str:
        return f"{self.prefix}/{self.device}"

    @property
    def status(self) -> str:
        return f"{self.base}/status"

    @property
    def info(self) -> str:
        return f"{self.base}/info"

    @property
    def bodies(self) -> str:
        return f"{self.base}/bodies"

    @property
    def presence(self) -> str:
        return f"{self.base}/presence"

    @property
    def board(self) -> str:
        return f"{self.base}/board"

    @property
    def events(self) -> str:
        return f"{self.base}/events"

    @property
    def all(self) -> str:
        """Wildcard for everything this device publishes under the prefix."""
        return f"{self.base}/#"

    @property
    def ha_status(self) -> str:
        return f"{self.ha_prefix}/status"

    def ha_config_topic(self, component: str, object_id: str) -> str:
        return f"{self.ha_prefix}/{component}/{self.device}_{object_id}/config"



def presence_payload(device: str, count: int, activities: Sequence[str], time_s: float) -> dict:
    """``cavatar.presence/1``: present, count, the activities (one per person) and the most common one."""
    if isinstance(count, bool) or int(count) != count or count < 0:
        raise ValueError(f"people count must be an integer >= 0, got {count!r}")
    acts = [str(a) for a in activities]
    top = Counter(acts).most_common(1)[0][0] if acts else NO_ACTIVITY
    return {"schema": PRESENCE_SCHEMA, "device": device, "time": round(float(time_s), 3),
            "present": int(count) > 0, "count": int(count), "activity": top, "activities": acts}


def info_payload(device: str, info: dict, time_s: float) -> dict:
    """``cavatar.info/1``: the runtime's info fields under a schema, device and time."""
    return {"schema": INFO_SCHEMA, "device": device, "time": round(float(time_s), 3), **info}


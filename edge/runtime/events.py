"""Fall and person-down events in the runtime: the detector per frame, payloads, board loss, HA entities.

    stage = EventStage(config.events, device="carpet-01", pitch_m=0.01905, times=times)
    for payload in stage.frame(outcome, scene_frame, wall_time_s): publisher.put_event(payload)
    for payload in stage.idle(): ...           # no frame for board_lost_s: everything raised is cleared
    for payload in stage.close(): ...          # the runtime stops: the same

A payload (schema ``cavatar.events/1``) is one change of one event of one track::

    {"schema":"cavatar.events/1","device":"carpet-01","time":1732240000.1,"type":"fall","state":"raised",
     "track_id":3,"confidence":0.87,"on_floor_s":0.86,"arrival_s":0.93,"position_m":[0.9,0.7],...}

It goes to ``<prefix>/<device>/events`` (QoS ≥ 1, through the MQTT sink's spool while the broker is
away) and to ``<stem>.events.jsonl`` beside a JSON-lines sink's file. Home Assistant gets a binary
sensor "Person down" and an event entity "Fall" (:func:`ha_event_discovery`), both available only
while the board's status topic says online. Nothing but these few numbers leaves the device.
"""

from __future__ import annotations

import time
from typing import TYPE_CHECKING, Any

from edge.scene.falls import FallConfig, FallDetector
from edge.topics import EVENTS_SCHEMA

if TYPE_CHECKING:
    from edge.runtime.stages import FrameOutcome
    from edge.scene import SceneFrame


def event_payload(device: str, event: dict, time_s: float) -> dict:
    """``cavatar.events/1``: the detector's event under a schema, the device and the wall time."""
    return {"schema": EVENTS_SCHEMA, "device": device, "time": round(float(time_s), 3), **event}


class EventStage:
    """The detector inside the runtime (one per runtime; called from the pipeline thread only)."""

    def __init__(self, config: FallConfig, device: str, pitch_m: float, times: Any = None,
                 board_lost_s: float = 3.0, clock=time.time, monotonic=time.monotonic) -> None:
        self.detector = FallDetector(config, pitch_m)
        self.device, self.times = device, times
        self.board_lost_s = float(board_lost_s)
        self.clock, self.monotonic = clock, monotonic
        self._last_frame_mono: float | None = None
        self._last_t_s = 0.0

    @property
    def active(self) -> dict[str, list[int]]:
        return self.detector.active

    def frame(self, outcome: FrameOutcome | None, scene_frame: SceneFrame | None, wall_time_s: float | None = None) -> list[dict]:
        """This frame's event payloads. ``outcome``: the FrameOutcome (its record's people give the
        model's activity per track); ``scene_frame``: the SceneFrame the scene made of it (None: skipped)."""
        self._last_frame_mono = self.monotonic()
        if scene_frame is None or outcome is None or outcome.kind == "invalid":
            return []
        t0 = time.perf_counter()
        record = outcome.record or {}
        acts = {int(p["track_id"]): p.get("activity") for p in record.get("people", ())}
        self._last_t_s = float(scene_frame.t_s)
        events = self.detector.update(scene_frame, acts)
        if self.times is not None:
            self.times.add("events", (time.perf_counter() - t0) * 1e3)
        now = self.clock() if wall_time_s is None else wall_time_s
        return [event_payload(self.device, e, now) for e in events]

    def idle(self) -> list[dict]:
        """Called when no frame came: after board_lost_s without one, every raised event is cleared."""
        last = self._last_frame_mono
        if last is None or self.monotonic() - last < self.board_lost_s:
            return []
        if not (self.detector.active["fall"] or self.detector.active["person_down"]):
            return []
        return self._reset("board_lost")

    def close(self) -> list[dict]:
        """The runtime stops: clear everything raised (a stopped board alerts nobody)."""
        return self._reset("stopped")

    def _reset(self, reason: str) -> list[dict]:
        now = self.clock()
        return [event_payload(self.device, e, now) for e in self.detector.reset(self._last_t_s, reason)]


def ha_event_discovery(topics: Any, device: dict, origin: dict | None = None) -> list[tuple[str, dict]]:
    """Home Assistant discovery (topic, payload): a "Person down" binary sensor and a "Fall" event entity on
    the events topic, shaped as edge.ha_discovery's (the same device and origin); available only while the
    runtime (status) and the board (board) are online, like the carpet's other entities."""
    from edge.ha_discovery import entity_slug
    from edge.topics import OFFLINE, ONLINE

    common = {"state_topic": topics.events, "availability_mode": "all",
              "availability": [{"topic": t, "payload_available": ONLINE, "payload_not_available": OFFLINE}
                               for t in (topics.status, topics.board)]}
    down = {"name": "Person down", "device_class": "safety", "payload_on": "ON", "payload_off": "OFF",
            "value_template": "{% if value_json.type == 'person_down' %}"
                              "{{ 'ON' if value_json.state == 'raised' else 'OFF' }}{% endif %}"}
    fall = {"name": "Fall", "event_types": ["fall"],
            "value_template": "{% if value_json.type == 'fall' and value_json.state == 'raised' %}"
                              "{\"event_type\":\"fall\",\"track_id\":{{ value_json.track_id }},"
                              "\"confidence\":{{ value_json.confidence }}}{% endif %}"}
    slug = entity_slug(topics.device)
    out = []
    for component, object_id, fields in (("binary_sensor", "person_down", down), ("event", "fall", fall)):
        payload = {"unique_id": f"cavatar_{topics.device}_{object_id}", "default_entity_id": f"{component}.{slug}_{object_id}",
                   **common, **fields, "device": device}
        if origin:
            payload["origin"] = origin
        out.append((topics.ha_config_topic(component, object_id), payload))
    return out


__all__ = ["EVENTS_SCHEMA", "EventStage", "event_payload", "ha_event_discovery"]

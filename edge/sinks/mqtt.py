"""mqtt:// — publish to an MQTT broker (paho-mqtt 2.x, VERSION2 callbacks, MQTT 3.1.1).

    mqtt://[user@]host[:port][/prefix]?qos=1&spool=/var/lib/cavatar/spool

Topics come from :mod:`edge.topics` (docs/mqtt.md lists them). The password is never in
the URL: it is read from the environment variable named by ``password_env``
(``CAVATAR_MQTT_PASSWORD``); a URL with ``user:password@`` is refused without echoing it.
The URL's form and options live in :mod:`edge.sinks.mqtt_url`, the `cavatar doctor` check in
:mod:`edge.sinks.mqtt_check`, the connection (client, callbacks, unacknowledged messages) in
:mod:`edge.sinks.mqtt_connection`, the spool's routing and drain in :mod:`edge.sinks.mqtt_drain`;
this file is what the sink publishes (records, events, retained states, Home Assistant discovery).

Behaviour
- Connects in the background and reconnects forever (back-off up to ``retry_s``); a broker
  that is down at start is not an error, but it is loud: the first failed attempt of every
  outage is a WARNING with the reason (name does not resolve, connection refused, no answer),
  and the first connection and every recovery are a WARNING too ("connected to …"), so the
  journal confirms both. ``cavatar run`` exits 1 when a sink never connected during the run
  (``--require-sinks`` refuses to start without the broker). On every connect: status,
  info, board, presence (all retained), Home Assistant discovery (retained, if ``ha=1``).
- Last will: ``status`` = "offline" (QoS 1, retained), sent by the broker when the process
  dies or hangs (after about 1.5 × ``keepalive``). A clean ``close()`` publishes "offline"
  itself first, because a graceful disconnect does not trigger the will.
- Bodies at ``qos``. QoS 0 while disconnected is dropped and counted. QoS ≥ 1 waits in the
  client queue, bounded by ``max_queued`` (the client's default is unbounded); beyond it
  records are dropped and counted.
- ``spool=DIR`` (QoS ≥ 1 only): while the broker is away, records go to a bounded on-disk
  spool (:mod:`edge.sinks.spool`, ``spool_mb``) instead of memory; on reconnect a drain
  thread sends them in order, deleting a segment only after every PUBACK, and live records
  keep going to the spool until it is empty, so order is kept. At-least-once: around a
  reconnect a few records can arrive twice; consumers drop duplicates by (device, seq).
- ``close()`` waits up to ``close_s`` for acknowledgements; with a spool, records still
  unacknowledged are written back to the spool (sent first next time) instead of lost.
"""

from __future__ import annotations

import re
import time
from typing import Any, Mapping, Sequence

from edge import __version__
from edge.health import CheckContext, Finding
from edge.record import ACTIVITY_PATTERN, RecordError, dumps
from edge.sinks.mqtt_connection import CONTROL_HEADROOM, Pending, log, unreachable_reason  # noqa: F401  (public here)
from edge.sinks.mqtt_drain import SpooledConnection
from edge.sinks.mqtt_url import FORM, OPTIONS, PASSWORD_ENV, SCHEME, MqttConfig, parse  # noqa: F401  (the scheme's URL)
from edge.topics import OFFLINE, ONLINE, info_payload, presence_payload
from edge.urls import redact


def open_sink(url: str, device: str, **kwargs: Any) -> "MqttSink":
    return MqttSink(parse(url), device, **kwargs)


def check(url: str, ctx: CheckContext) -> list[Finding]:
    """`cavatar doctor`: the broker reachable and the login accepted; the spool folder writable (edge.sinks.mqtt_check)."""
    from edge.sinks.mqtt_check import check_broker

    return check_broker(f"sink {redact(url)}", parse(url), ctx)


class MqttSink(SpooledConnection):
    def __init__(self, config: MqttConfig, device: str) -> None:
        super().__init__(config, device)  # the connection's state and the spool (SinkError for an unusable one)
        self._info: dict | None = None
        self._presence: dict | None = None
        self._presence_key: tuple | None = None
        self._board: bool | None = None  # info's board_connected: frames arriving from the board
        self._activities: list[str] | None = None  # info's activities: the model's labels (the HA activity enum)
        self._open_client(self._on_message)  # last: paho's callbacks read the states above
        self._start_drainer()

    # -- public API -----------------------------------------------------------------------

    def publish_status(self, online: bool) -> None:
        self._online = bool(online)
        if self._connected:
            self._send(self.topics.status, ONLINE if online else OFFLINE, 1, True, "status")

    def _write_info(self, info: dict) -> None:
        self._info = info_payload(self.device, info, time.time())
        if self._connected:
            self._send(self.topics.info, dumps(self._info), 1, True, "info")
        acts = info.get("activities")
        if isinstance(acts, list) and acts != self._activities:  # the activity sensor's options follow the model
            self._activities = [str(a) for a in acts]
            if self._connected and self.config.ha:
                self._send_discovery()
        board = info.get("board_connected")
        if isinstance(board, bool) and board != self._board:  # the board's availability, retained, on change
            self._board = board
            if self._connected:
                self._send(self.topics.board, ONLINE if board else OFFLINE, 1, True, "board")

    def publish_presence(self, count: int, activities: Sequence[str]) -> None:
        """Retained presence state, published only when the count or the activities change."""
        acts = list(activities)
        for a in acts:
            if not isinstance(a, str) or not re.match(ACTIVITY_PATTERN, a):
                raise RecordError(f"presence activity must match {ACTIVITY_PATTERN}, got {a!r}")
        key = (int(count), tuple(acts))
        if key == self._presence_key:
            return
        self._presence_key = key
        self._presence = presence_payload(self.device, count, acts, time.time())
        if self._connected:
            self._send(self.topics.presence, dumps(self._presence), 1, True, "presence")

    def flush(self, timeout_s: float = 5.0) -> bool:
        """Wait until every record handed over so far is delivered (and the spool is empty)."""
        deadline = time.monotonic() + timeout_s
        with self._acks:
            while time.monotonic() < deadline:
                busy = any(p.kind in ("bodies", "spool") for p in self._pending.values())
                if not busy and not (self._spool is not None and len(self._spool)):
                    return True
                self._acks.wait(min(0.05, max(0.0, deadline - time.monotonic())))
        return False

    def close(self) -> None:
        if self.closed:
            return
        self.closed = True
        self._stop.set()
        self._wake.set()
        if self._drainer is not None:
            self._drainer.join(timeout=self.config.close_s + 1)
        deadline = time.monotonic() + max(0.0, self.config.close_s)
        if self._connected:
            if self._board is not None:  # a stopped runtime reads no frames
                self._send(self.topics.board, OFFLINE, 1, True, "board")
            self._send(self.topics.status, OFFLINE, 1, True, "status")
            with self._acks:
                while self._pending and self._connected and time.monotonic() < deadline:
                    self._acks.wait(0.02)
        with self._acks:
            left = list(self._pending.values())
            self._pending.clear()
        unacked = [p.payload for p in left if p.kind == "bodies" and p.qos > 0 and p.payload is not None]
        lost = sum(1 for p in left if p.kind == "bodies" and p.qos == 0)
        if self._spool is not None:
            self._spool.prepend(unacked)  # sent first by the next run
        else:
            lost += len(unacked)
        if lost:
            self.counters.add("dropped", lost)
            log.warning("mqtt:// closed with %d records undelivered", lost)
        try:
            self._client.disconnect()
        finally:
            self._client.loop_stop()
            if self._spool is not None:
                self._spool.close()

    def _gauges(self) -> dict[str, Any]:
        with self._acks:
            queued = sum(1 for p in self._pending.values() if p.kind in ("bodies", "spool"))
        out: dict[str, Any] = {"queued": queued, "connected": self._connected, "connects": self.connects}
        if self._spool is not None:
            out["spooled"] = len(self._spool)
            out["dropped"] = self.counters.get("dropped") + self._spool.dropped
            out["spool_bytes"] = self._spool.size_bytes()
            out["spool_refused"] = self._spool.refused + self._spool.foreign  # lines/files there not ours: never sent
        return out

    # -- publishing -----------------------------------------------------------------------

    def _queue_full(self) -> bool:
        """The bound on records held in memory (QoS >= 1). Paho's own bound is set a little
        higher so that status/info/discovery still go out when the records fill theirs."""
        if self.config.qos == 0:
            return False
        with self._acks:
            return sum(1 for p in self._pending.values() if p.kind == "bodies") >= self.config.max_queued

    def _write_bodies(self, record: Mapping, line: str, t_call: float) -> None:
        if self._spool is not None:
            with self._route:
                if self._spooling or not self._connected or self._queue_full():
                    self._to_spool(line)
                    return
                info = self._client.publish(self.topics.bodies, line, self.config.qos)
                if info.rc == self._m.MQTT_ERR_QUEUE_SIZE:
                    self._to_spool(line)
                    return
                self._after_publish(info, Pending("bodies", t_call, self.config.qos, line))
            return
        if self._queue_full():
            self.counters.add("dropped")
            return
        info = self._client.publish(self.topics.bodies, line, self.config.qos)
        self._after_publish(info, Pending("bodies", t_call, self.config.qos))

    def _write_event(self, payload: dict, line: str) -> None:
        """Events go to the events topic at QoS ≥ 1, through the spool (in order with the bodies) while the
        broker is away; the spool's drain sends each line to its topic by schema."""
        qos = max(1, self.config.qos)
        if self._spool is not None:
            with self._route:
                if self._spooling or not self._connected:
                    self._to_spool(line)
                    return
        info = self._client.publish(self.topics.events, line, qos)
        self._after_publish(info, Pending("event", time.monotonic(), qos))

    # -- retained states and Home Assistant discovery (paho's network thread) ----------------

    def _resend_states(self, client: Any) -> None:
        if self._info is not None:
            self._send(self.topics.info, dumps(self._info), 1, True, "info")
        if self._board is not None:
            self._send(self.topics.board, ONLINE if self._board else OFFLINE, 1, True, "board")
        if self.config.ha:
            self._send_discovery()
            client.subscribe(self.topics.ha_status, qos=1)
        if self._presence is not None:
            self._send(self.topics.presence, dumps(self._presence), 1, True, "presence")

    def _send_discovery(self) -> None:
        from edge.ha_discovery import discovery
        from edge.runtime.events import ha_event_discovery

        configs = discovery(self.topics, sw_version=__version__, activities=self._activities)
        configs += ha_event_discovery(self.topics, configs[0][1]["device"], configs[0][1].get("origin"))
        for topic, payload in configs:
            self._send(topic, dumps(payload), 1, True, "discovery")

    def _on_message(self, client: Any, userdata: Any, message: Any) -> None:
        if message.topic == self.topics.ha_status and message.payload == b"online":
            self._send_discovery()  # Home Assistant restarted: it asks for discovery again

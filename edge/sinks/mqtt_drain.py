"""The mqtt:// sink's on-disk spool (``spool=DIR``, QoS ≥ 1): records go there while the broker is away, and a
drain thread sends them back in order once it returns (the behaviour: :mod:`edge.sinks.mqtt`).

Routing: while anything is spooled, live records are spooled too (under ``_route``), so order is kept; the
drain sends a segment with a bounded window and deletes it only after every PUBACK.
"""

from __future__ import annotations

import logging
import threading
import time
from typing import Any

from edge.sinks.base import SinkError
from edge.sinks.mqtt_connection import MqttConnection, Pending
from edge.sinks.mqtt_url import MqttConfig
from edge.sinks.spool import Spool

log = logging.getLogger("edge.sinks.mqtt")


class SpooledConnection(MqttConnection):
    """An :class:`~edge.sinks.mqtt_connection.MqttConnection` with the optional spool and its drain thread."""

    def __init__(self, config: MqttConfig, device: str) -> None:
        super().__init__(config, device)
        self._route = threading.Lock()  # orders direct publishes against the spool
        self._spool: Spool | None = None
        self._spooling = False
        if config.spool:
            try:
                self._spool = Spool(config.spool, int(config.spool_mb * 1e6), device=device)
            except OSError as exc:
                raise SinkError(f"mqtt:// spool: {exc}") from None
            self._spool.seal()
            self._spooling = len(self._spool) > 0  # left by an earlier run: send those first
        self._drainer: threading.Thread | None = None

    def _start_drainer(self) -> None:
        """After the client is made: the drain thread, when there is a spool."""
        if self._spool is not None:
            self._drainer = threading.Thread(target=self._drain_loop, name="mqtt-spool-drain", daemon=True)
            self._drainer.start()

    def _meanwhile(self) -> str:
        if self._spool is not None:
            return "records wait in the spool until it connects"
        return super()._meanwhile()

    def _line_topic(self, line: bytes) -> tuple[str, int]:
        """A spooled line's topic and QoS: events by their schema, everything else is bodies."""
        if line.startswith(b'{"schema":"cavatar.events/'):
            return self.topics.events, max(1, self.config.qos)
        return self.topics.bodies, self.config.qos

    def _to_spool(self, line: str) -> None:
        """Under self._route."""
        self._spooling = True
        assert self._spool is not None  # called only with a spool
        self._spool.append(line)  # a refusal is counted in spool.dropped
        self.counters.add("spooled_total")
        self._wake.set()

    def _drain_loop(self) -> None:
        while not self._stop.is_set():
            self._wake.wait(0.25)
            self._wake.clear()
            if self._spooling and self._connected and not self._stop.is_set():
                try:
                    self._drain()
                except Exception:  # keep publishing; the spool stays on disk
                    log.exception("mqtt:// spool drain failed")
                    self.counters.add("errors")
                    self._stop.wait(1.0)

    def _drain(self) -> None:
        assert self._spool is not None
        # Records handed to paho before the outage are resent by paho on reconnect; let them
        # be acknowledged first so that the spool (newer records) follows them in order.
        with self._acks:
            while any(p.kind == "bodies" for p in self._pending.values()):
                if not self._connected or self._stop.is_set():
                    return
                self._acks.wait(0.05)
        while self._connected and not self._stop.is_set():
            got = self._spool.claim()
            if got is None:
                with self._route:
                    if self._spool.seal():
                        continue
                    self._spooling = False  # empty: live records go direct again, after everything spooled
                    log.info("mqtt:// spool drained")
                    return
            seg, lines = got
            if self._send_segment(seg, lines):
                self._spool.remove(seg)
            else:
                self._spool.release(seg)
                return

    def _send_segment(self, seg: Any, lines: list[bytes]) -> bool:
        """Publish a segment's unacknowledged lines with a bounded window; True once all are acknowledged."""
        window = max(1, min(64, self.config.max_queued // 2))
        todo = [i for i in range(len(lines)) if i not in seg.acked]
        sent = 0
        for i in todo:
            with self._acks:
                while (sent - len(seg.acked.intersection(todo))) >= window:
                    if not self._connected or self._stop.is_set():
                        return False
                    self._acks.wait(0.05)
            if not self._connected or self._stop.is_set():
                return False
            topic, qos = self._line_topic(lines[i])
            info = self._client.publish(topic, lines[i], qos)
            if info.rc == self._m.MQTT_ERR_QUEUE_SIZE:
                return False
            self._after_publish(info, Pending("spool", time.monotonic(), qos, None, seg, i))
            sent += 1
            if info.rc != self._m.MQTT_ERR_SUCCESS:
                return False
        with self._acks:
            while not seg.acked.issuperset(todo):
                if not self._connected or self._stop.is_set():
                    return False
                self._acks.wait(0.05)
        return True

"""mqtt:// — publish to an MQTT broker (paho-mqtt 2.x, VERSION2 callbacks, MQTT 3.1.1).

    mqtt://[user@]host[:port][/prefix]?qos=1&spool=/var/lib/cavatar/spool

Topics come from :mod:`edge.topics` (docs/mqtt.md lists them). The password is never in
the URL: it is read from the environment variable named by ``password_env``
(``CAVATAR_MQTT_PASSWORD``); a URL with ``user:password@`` is refused without echoing it.
The URL's form and options live in :mod:`edge.sinks.mqtt_url`, the `cavatar doctor` check in
:mod:`edge.sinks.mqtt_check`.

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

import logging
import os
import re
import socket
import ssl
import threading
import time
from typing import Any, Mapping, Sequence

from edge import __version__
from edge.health import CheckContext, Finding
from edge.record import ACTIVITY_PATTERN, RecordError, dumps
from edge.sinks.base import Sink, SinkError
from edge.sinks.mqtt_url import FORM, OPTIONS, PASSWORD_ENV, SCHEME, MqttConfig, parse  # noqa: F401  (the scheme's URL)
from edge.sinks.spool import Spool
from edge.topics import OFFLINE, ONLINE, DeviceTopics, info_payload, presence_payload
from edge.urls import redact

log = logging.getLogger(__name__)

CONTROL_HEADROOM = 64  # room in the client queue for status/info/presence/discovery beyond max_queued records


def open_sink(url: str, device: str, **kwargs: Any) -> "MqttSink":
    return MqttSink(parse(url), device, **kwargs)


def check(url: str, ctx: CheckContext) -> list[Finding]:
    """`cavatar doctor`: the broker reachable and the login accepted; the spool folder writable (edge.sinks.mqtt_check)."""
    from edge.sinks.mqtt_check import check_broker

    return check_broker(f"sink {redact(url)}", parse(url), ctx)


def unreachable_reason(host: str, port: int, timeout_s: float = 1.0) -> str:
    """Why a broker cannot be reached, in words (paho's on_connect_fail does not say): the name does not resolve,
    or the TCP connection's error (refused, timed out, no route)."""
    try:
        infos = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)
    except socket.gaierror as exc:
        return f"the host name {host!r} does not resolve ({exc.strerror or exc})"
    except OSError as exc:
        return f"the host name {host!r} cannot be looked up ({exc})"
    family, kind, proto, _, address = infos[0]
    try:
        with socket.socket(family, kind, proto) as s:
            s.settimeout(timeout_s)
            s.connect(address)
    except socket.timeout:
        return f"no answer from {address[0]}:{port} within {timeout_s:g} s (firewall, wrong host, broker hung)"
    except OSError as exc:
        return f"{exc.strerror or exc} at {address[0]}:{port} (is the broker running, on this port?)"
    return "the TCP connection opens but the MQTT connection failed (TLS or protocol mismatch?)"


class _Pending:
    """A message handed to paho and not yet delivered."""

    __slots__ = ("kind", "t0", "qos", "payload", "seg", "idx")

    def __init__(self, kind: str, t0: float, qos: int, payload: bytes | str | None = None, seg: Any = None, idx: int = -1):
        self.kind, self.t0, self.qos, self.payload, self.seg, self.idx = kind, t0, qos, payload, seg, idx


class MqttSink(Sink):
    scheme = SCHEME

    def __init__(self, config: MqttConfig, device: str) -> None:
        super().__init__(device)
        import paho.mqtt.client as mqtt  # runtime dependency, imported only when an mqtt sink is opened

        self._m = mqtt
        self.config = config
        self.topics = DeviceTopics(config.prefix, device, config.ha_prefix)
        self._route = threading.Lock()  # orders direct publishes against the spool
        self._acks = threading.Condition()  # guards _pending/_early
        self._pending: dict[int, _Pending] = {}
        self._early: set[int] = set()
        self._connected = False
        self._connected_evt = threading.Event()
        self._stop = threading.Event()
        self._wake = threading.Event()
        self._online = True
        self._info: dict | None = None
        self._presence: dict | None = None
        self._presence_key: tuple | None = None
        self._board: bool | None = None  # info's board_connected: frames arriving from the board
        self._activities: list[str] | None = None  # info's activities: the model's labels (the HA activity enum)
        self._last_refusal = ""
        self.connects = 0
        self._down_since: float | None = time.monotonic()  # not connected since (None: connected)
        self._failures_said = False  # the current outage's first failure is logged, once
        self.counters.add("spooled_total", 0)
        self.counters.add("connect_failures", 0)

        self._spool: Spool | None = None
        self._spooling = False
        if config.spool:
            try:
                self._spool = Spool(config.spool, int(config.spool_mb * 1e6), device=device)
            except OSError as exc:
                raise SinkError(f"mqtt:// spool: {exc}") from None
            self._spool.seal()
            self._spooling = len(self._spool) > 0  # left by an earlier run: send those first

        client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=config.client_id or f"cavatar-{device}",
                             protocol=mqtt.MQTTv311, clean_session=True)
        client.will_set(self.topics.status, OFFLINE, qos=1, retain=True)
        if config.username:
            password = os.environ.get(config.password_env)
            if password is None:
                log.warning("mqtt:// user %r but $%s is not set: connecting without a password", config.username, config.password_env)
            client.username_pw_set(config.username, password)
        elif os.environ.get(config.password_env):
            log.warning("$%s is set but the mqtt:// URL names no user; connecting anonymously", config.password_env)
        if config.tls:
            client.tls_set_context(self._tls_context())
        client.max_queued_messages_set(config.max_queued + CONTROL_HEADROOM)
        client.reconnect_delay_set(min_delay=min(1.0, config.retry_s), max_delay=config.retry_s)  # type: ignore[arg-type]
        client.on_connect = self._on_connect
        client.on_connect_fail = self._on_connect_fail
        client.on_disconnect = self._on_disconnect
        client.on_publish = self._on_publish
        client.on_message = self._on_message
        self._client = client
        client.connect_async(config.host, config.port, config.keepalive)
        client.loop_start()
        self._drainer: threading.Thread | None = None
        if self._spool is not None:
            self._drainer = threading.Thread(target=self._drain_loop, name="mqtt-spool-drain", daemon=True)
            self._drainer.start()

    def _tls_context(self) -> ssl.SSLContext:
        c = self.config
        for what, path in (("ca", c.ca), ("cert", c.cert), ("key", c.key)):
            if path and not os.path.isfile(path):
                raise SinkError(f"mqtt:// {what}={path!r}: no such file")
        try:
            ctx = ssl.create_default_context(cafile=c.ca or None)
            if c.cert:
                ctx.load_cert_chain(c.cert, c.key or None)
        except (ssl.SSLError, OSError) as exc:
            raise SinkError(f"mqtt:// TLS files unusable: {exc}") from None
        return ctx

    # -- public API -----------------------------------------------------------------------

    def describe(self) -> str:
        return self.config.describe()

    def wait_connected(self, timeout_s: float) -> bool:
        """True once connected and the broker has acknowledged this connection's retained status (so a subscriber
        that comes after finds it retained)."""
        return self._connected_evt.wait(timeout_s)

    @property
    def connected(self) -> bool:
        return self._connected

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
        unacked = [p.payload for p in left if p.kind == "bodies" and p.qos > 0]
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
                self._after_publish(info, _Pending("bodies", t_call, self.config.qos, line))
            return
        if self._queue_full():
            self.counters.add("dropped")
            return
        info = self._client.publish(self.topics.bodies, line, self.config.qos)
        self._after_publish(info, _Pending("bodies", t_call, self.config.qos))

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
        self._after_publish(info, _Pending("event", time.monotonic(), qos))

    def _line_topic(self, line: bytes) -> tuple[str, int]:
        """A spooled line's topic and QoS: events by their schema, everything else is bodies."""
        if line.startswith(b'{"schema":"cavatar.events/'):
            return self.topics.events, max(1, self.config.qos)
        return self.topics.bodies, self.config.qos

    def _to_spool(self, line: str) -> None:
        """Under self._route."""
        self._spooling = True
        self._spool.append(line)  # a refusal is counted in spool.dropped
        self.counters.add("spooled_total")
        self._wake.set()

    def _send(self, topic: str, payload: str, qos: int, retain: bool, kind: str) -> None:
        info = self._client.publish(topic, payload, qos, retain)
        self._after_publish(info, _Pending(kind, time.monotonic(), qos))

    def _after_publish(self, info: Any, entry: _Pending) -> Any:
        rc = info.rc
        m = self._m
        ok = rc == m.MQTT_ERR_SUCCESS or (rc == m.MQTT_ERR_NO_CONN and entry.qos > 0)  # QoS>=1: queued for reconnect
        if not ok:
            if entry.kind in ("bodies", "spool"):
                self.counters.add("dropped" if entry.kind == "bodies" else "errors")
            if rc not in (m.MQTT_ERR_NO_CONN, m.MQTT_ERR_QUEUE_SIZE):
                self.counters.add("errors")
            return rc
        with self._acks:
            if info.mid in self._early:  # delivered before we got here (the callback raced us)
                self._early.discard(info.mid)
                self._delivered(entry)
            else:
                self._pending[info.mid] = entry
        return rc

    def _delivered(self, entry: _Pending) -> None:
        """Under self._acks."""
        if entry.kind == "bodies":
            self._count_delivered(time.monotonic() - entry.t0)
        elif entry.kind == "spool":
            self._count_delivered(None)
            entry.seg.acked.add(entry.idx)
        elif entry.kind == "announce" and self._connected:
            self._connected_evt.set()
        self._acks.notify_all()

    # -- spool drain ----------------------------------------------------------------------

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
            self._after_publish(info, _Pending("spool", time.monotonic(), qos, None, seg, i))
            sent += 1
            if info.rc != self._m.MQTT_ERR_SUCCESS:
                return False
        with self._acks:
            while not seg.acked.issuperset(todo):
                if not self._connected or self._stop.is_set():
                    return False
                self._acks.wait(0.05)
        return True

    # -- paho callbacks (paho's network thread) -------------------------------------------

    def _on_connect(self, client: Any, userdata: Any, flags: Any, reason_code: Any, properties: Any) -> None:
        if reason_code.is_failure:
            self.counters.add("errors")
            text = str(reason_code)
            if text != self._last_refusal:
                hint = f" (check the user in the URL and ${self.config.password_env})" if "auth" in text.lower() else ""
                log.error("mqtt:// broker %s:%d refused the connection: %s%s", self.config.host, self.config.port, text, hint)
                self._last_refusal = text
            return
        self._last_refusal = ""
        self.connects += 1
        down = time.monotonic() - self._down_since if self._down_since is not None else 0.0
        failed = self.counters.get("connect_failures")
        # WARNING, the journal's level: the first connection and every recovery are confirmed there, once each
        log.warning("mqtt:// connected to %s%s", self.config.describe(),
                    "" if self.connects == 1 and not self._failures_said else
                    f" again after {down:.1f} s ({failed} failed attempts so far)")
        self._down_since, self._failures_said = None, False
        # Connected before the retained states are sent: a state another thread changes meanwhile is then either
        # read below or sent by that thread itself (it updates the state first, then looks at _connected).
        self._connected = True
        self._send(self.topics.status, ONLINE if self._online else OFFLINE, 1, True, "announce")  # PUBACK → wait_connected
        if self._info is not None:
            self._send(self.topics.info, dumps(self._info), 1, True, "info")
        if self._board is not None:
            self._send(self.topics.board, ONLINE if self._board else OFFLINE, 1, True, "board")
        if self.config.ha:
            self._send_discovery()
            client.subscribe(self.topics.ha_status, qos=1)
        if self._presence is not None:
            self._send(self.topics.presence, dumps(self._presence), 1, True, "presence")
        self._wake.set()

    def _send_discovery(self) -> None:
        from edge.ha_discovery import discovery
        from edge.runtime.events import ha_event_discovery

        configs = discovery(self.topics, sw_version=__version__, activities=self._activities)
        configs += ha_event_discovery(self.topics, configs[0][1]["device"], configs[0][1].get("origin"))
        for topic, payload in configs:
            self._send(topic, dumps(payload), 1, True, "discovery")

    def _on_connect_fail(self, client: Any, userdata: Any) -> None:
        self.counters.add("connect_failures")
        if not self._failures_said and not self.closed:  # once per outage, with the reason; recovery says so too
            self._failures_said = True
            log.warning("mqtt:// cannot connect to %s:%d: %s; %s; retrying every %g s at most", self.config.host,
                        self.config.port, unreachable_reason(self.config.host, self.config.port), self._meanwhile(),
                        self.config.retry_s)

    def _meanwhile(self) -> str:
        if self._spool is not None:
            return "records wait in the spool until it connects"
        if self.config.qos == 0:
            return "records are dropped (qos=0) until it connects"
        return f"records wait in memory (up to max_queued={self.config.max_queued}) until it connects"

    def _on_disconnect(self, client: Any, userdata: Any, flags: Any, reason_code: Any, properties: Any) -> None:
        self._connected = False
        if self._down_since is None:
            self._down_since = time.monotonic()
        self._connected_evt.clear()
        with self._acks:
            lost = [mid for mid, p in self._pending.items() if p.qos == 0]
            for mid in lost:
                if self._pending.pop(mid).kind == "bodies":
                    self.counters.add("dropped")
            self._acks.notify_all()
        if not self.closed:
            log.warning("mqtt:// disconnected from %s:%d (%s); reconnecting", self.config.host, self.config.port, reason_code)

    def _on_publish(self, client: Any, userdata: Any, mid: int, reason_code: Any, properties: Any) -> None:
        with self._acks:
            entry = self._pending.pop(mid, None)
            if entry is None:
                self._early.add(mid)
                return
            self._delivered(entry)

    def _on_message(self, client: Any, userdata: Any, message: Any) -> None:
        if message.topic == self.topics.ha_status and message.payload == b"online":
            self._send_discovery()  # Home Assistant restarted: it asks for discovery again

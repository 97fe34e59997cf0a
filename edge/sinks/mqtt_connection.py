"""The mqtt:// sink's connection to the broker: the paho client (login, TLS, bounded queue, back-off), the
connect / disconnect / publish callbacks, and the book of messages handed to paho and not yet acknowledged.

The behaviour is described in :mod:`edge.sinks.mqtt` (what the sink publishes); the on-disk spool and its
drain are :mod:`edge.sinks.mqtt_drain`. All three log as ``edge.sinks.mqtt``.
"""

from __future__ import annotations

import logging
import os
import socket
import ssl
import threading
import time
from abc import abstractmethod
from typing import Any, Callable

from edge.sinks.base import Sink, SinkError
from edge.sinks.mqtt_url import SCHEME, MqttConfig
from edge.topics import OFFLINE, ONLINE, DeviceTopics

log = logging.getLogger("edge.sinks.mqtt")  # one logger for the sink, whichever of its files speaks

CONTROL_HEADROOM = 64  # room in the client queue for status/info/presence/discovery beyond max_queued records


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


def tls_context(config: MqttConfig) -> ssl.SSLContext:
    """The TLS context of ``ca``/``cert``/``key``; SinkError for a missing or unusable file."""
    for what, path in (("ca", config.ca), ("cert", config.cert), ("key", config.key)):
        if path and not os.path.isfile(path):
            raise SinkError(f"mqtt:// {what}={path!r}: no such file")
    try:
        ctx = ssl.create_default_context(cafile=config.ca or None)
        if config.cert:
            ctx.load_cert_chain(config.cert, config.key or None)
    except (ssl.SSLError, OSError) as exc:
        raise SinkError(f"mqtt:// TLS files unusable: {exc}") from None
    return ctx


class Pending:
    """A message handed to paho and not yet delivered."""

    __slots__ = ("kind", "t0", "qos", "payload", "seg", "idx")

    def __init__(self, kind: str, t0: float, qos: int, payload: bytes | str | None = None, seg: Any = None, idx: int = -1):
        self.kind, self.t0, self.qos, self.payload, self.seg, self.idx = kind, t0, qos, payload, seg, idx


class MqttConnection(Sink):
    """The connection half of :class:`edge.sinks.mqtt.MqttSink`: state here, the client made by
    :meth:`_open_client` once the subclasses' state exists (paho's callbacks read it from then on)."""

    scheme = SCHEME

    def __init__(self, config: MqttConfig, device: str) -> None:
        super().__init__(device)
        import paho.mqtt.client as mqtt  # runtime dependency, imported only when an mqtt sink is opened

        self._m = mqtt
        self.config = config
        self.topics = DeviceTopics(config.prefix, device, config.ha_prefix)
        self._acks = threading.Condition()  # guards _pending/_early
        self._pending: dict[int, Pending] = {}
        self._early: set[int] = set()
        self._connected = False
        self._connected_evt = threading.Event()
        self._stop = threading.Event()
        self._wake = threading.Event()
        self._online = True
        self._last_refusal = ""
        self.connects = 0
        self._down_since: float | None = time.monotonic()  # not connected since (None: connected)
        self._failures_said = False  # the current outage's first failure is logged, once
        self.counters.add("spooled_total", 0)
        self.counters.add("connect_failures", 0)

    def _open_client(self, on_message: Callable[[Any, Any, Any], None]) -> None:
        """Make the client (last will, login, TLS, bounds, back-off) and connect in the background."""
        mqtt, config = self._m, self.config
        client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=config.client_id or f"cavatar-{self.device}",
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
            client.tls_set_context(tls_context(config))
        client.max_queued_messages_set(config.max_queued + CONTROL_HEADROOM)
        client.reconnect_delay_set(min_delay=min(1.0, config.retry_s), max_delay=config.retry_s)  # type: ignore[arg-type]
        client.on_connect = self._on_connect
        client.on_connect_fail = self._on_connect_fail
        client.on_disconnect = self._on_disconnect
        client.on_publish = self._on_publish
        client.on_message = on_message
        self._client = client
        client.connect_async(config.host, config.port, config.keepalive)
        client.loop_start()

    def describe(self) -> str:
        return self.config.describe()

    def wait_connected(self, timeout_s: float) -> bool:
        """True once connected and the broker has acknowledged this connection's retained status (so a subscriber
        that comes after finds it retained)."""
        return self._connected_evt.wait(timeout_s)

    @property
    def connected(self) -> bool:
        return self._connected

    @abstractmethod
    def _resend_states(self, client: Any) -> None:
        """On every connect, after the status: the retained states and subscriptions (paho's network thread)."""

    def _meanwhile(self) -> str:
        """What happens to records while the broker is away, for the outage's warning."""
        if self.config.qos == 0:
            return "records are dropped (qos=0) until it connects"
        return f"records wait in memory (up to max_queued={self.config.max_queued}) until it connects"

    # -- the book of unacknowledged messages ----------------------------------------------

    def _send(self, topic: str, payload: str, qos: int, retain: bool, kind: str) -> None:
        info = self._client.publish(topic, payload, qos, retain)
        self._after_publish(info, Pending(kind, time.monotonic(), qos))

    def _after_publish(self, info: Any, entry: Pending) -> Any:
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

    def _delivered(self, entry: Pending) -> None:
        """Under self._acks."""
        if entry.kind == "bodies":
            self._count_delivered(time.monotonic() - entry.t0)
        elif entry.kind == "spool":
            self._count_delivered(None)
            entry.seg.acked.add(entry.idx)
        elif entry.kind == "announce" and self._connected:
            self._connected_evt.set()
        self._acks.notify_all()

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
        self._resend_states(client)
        self._wake.set()

    def _on_connect_fail(self, client: Any, userdata: Any) -> None:
        self.counters.add("connect_failures")
        if not self._failures_said and not self.closed:  # once per outage, with the reason; recovery says so too
            self._failures_said = True
            log.warning("mqtt:// cannot connect to %s:%d: %s; %s; retrying every %g s at most", self.config.host,
                        self.config.port, unreachable_reason(self.config.host, self.config.port), self._meanwhile(),
                        self.config.retry_s)

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

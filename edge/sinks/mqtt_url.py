"""The mqtt:// URL: its form, typed options and :class:`MqttConfig` (the sink and its doctor check both read it).

    mqtt://[user@]host[:port][/prefix]?qos=1&spool=/var/lib/cavatar/spool

The password is never in the URL: it is read from the environment variable named by
``password_env`` (``CAVATAR_MQTT_PASSWORD``); a URL with ``user:password@`` is refused without
echoing it. Behaviour of the sink: :mod:`edge.sinks.mqtt`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from urllib.parse import unquote, urlsplit

from edge.sinks.base import Option, parse_bool, parse_sink_url
from edge.topics import DEFAULT_PREFIX, HA_PREFIX, check_prefix

SCHEME = "mqtt"
FORM = ("mqtt://[user@]host[:port][/prefix]?qos=0|1|2&keepalive=S&max_queued=N&spool=DIR&spool_mb=MB"
        "&tls=0|1&ca=PEM&cert=PEM&key=PEM&client_id=ID&retry_s=S&close_s=S&ha=0|1&ha_prefix=P"
        "&password_env=VAR (the password comes from $CAVATAR_MQTT_PASSWORD, never the URL)")
PASSWORD_ENV = "CAVATAR_MQTT_PASSWORD"


def _qos(text: str) -> int:
    if text not in ("0", "1", "2"):
        raise ValueError("QoS is 0, 1 or 2")
    return int(text)


def _positive(kind):
    def parse(text: str):
        value = kind(text)
        if value <= 0:
            raise ValueError("must be > 0")
        return value
    return parse


OPTIONS = {
    "qos": Option(_qos, 1, "QoS of the bodies stream: 0 drops during outages, 1 at-least-once"),
    "keepalive": Option(_positive(int), 30, "seconds between pings; the broker sends the last will after ~1.5x this on a hang"),
    "max_queued": Option(_positive(int), 1000, "most messages held in client memory (QoS>=1); beyond it records are dropped and counted"),
    "spool": Option(str, "", "directory of an on-disk spool for QoS>=1 records while the broker is away (empty: no spool)"),
    "spool_mb": Option(_positive(float), 64.0, "spool bound in MB; beyond it the oldest records are dropped and counted"),
    "tls": Option(parse_bool, False, "TLS to the broker (default port 8883)"),
    "ca": Option(str, "", "CA certificate file (PEM) to verify the broker; implies tls=1; empty: system CAs"),
    "cert": Option(str, "", "client certificate (PEM) for mutual TLS; implies tls=1"),
    "key": Option(str, "", "private key (PEM) of cert, if not inside cert"),
    "client_id": Option(str, "", "MQTT client id (default cavatar-<device>); must be unique on the broker"),
    "retry_s": Option(_positive(float), 30.0, "longest wait between reconnection attempts, seconds"),
    "close_s": Option(float, 5.0, "how long close() waits for acknowledgements, seconds"),
    "ha": Option(parse_bool, True, "publish Home Assistant discovery (presence, people count, activity)"),
    "ha_prefix": Option(str, HA_PREFIX, "Home Assistant discovery prefix"),
    "password_env": Option(str, PASSWORD_ENV, "environment variable that holds the broker password"),
}


@dataclass(frozen=True)
class MqttConfig:
    host: str
    port: int
    username: str | None
    prefix: str
    qos: int
    keepalive: int
    max_queued: int
    spool: str
    spool_mb: float
    tls: bool
    ca: str
    cert: str
    key: str
    client_id: str
    retry_s: float
    close_s: float
    ha: bool
    ha_prefix: str
    password_env: str

    def describe(self) -> str:
        user = f"{self.username}@" if self.username else ""
        extras = (", tls" if self.tls else "") + (", spool" if self.spool else "")
        return f"mqtt://{user}{self.host}:{self.port}/{self.prefix} (qos {self.qos}{extras})"


def parse(url: str) -> MqttConfig:
    """Typed configuration from a mqtt:// URL. ValueError (quoting the accepted form) on any mistake."""
    parts = urlsplit(url)
    if parts.scheme != SCHEME:
        raise ValueError(f"not a mqtt:// URL. Form: {FORM}")
    if parts.password is not None:
        raise ValueError(f"mqtt:// URL carries a password: put it in the environment variable {PASSWORD_ENV} "
                         f"(or the one named by password_env=), never in the URL. Form: {FORM}")
    _, opts = parse_sink_url(url, SCHEME, FORM, OPTIONS)
    if not parts.hostname:
        raise ValueError(f"mqtt:// URL needs a broker host. Form: {FORM}")
    try:
        port = parts.port
    except ValueError as exc:
        raise ValueError(f"mqtt:// port is not valid ({exc}). Form: {FORM}") from None
    tls = opts["tls"] or bool(opts["ca"] or opts["cert"])
    if opts["key"] and not opts["cert"]:
        raise ValueError(f"mqtt:// key= needs cert=. Form: {FORM}")
    if opts["spool"] and opts["qos"] == 0:
        raise ValueError(f"mqtt:// spool= keeps QoS 1 records: use qos=1 with it. Form: {FORM}")
    if not re.match(r"^[A-Za-z_][A-Za-z0-9_]*$", opts["password_env"]):
        raise ValueError(f"mqtt:// password_env must name an environment variable. Form: {FORM}")
    prefix = unquote(parts.path).strip("/") or DEFAULT_PREFIX
    try:
        check_prefix(prefix)
        check_prefix(opts["ha_prefix"], "Home Assistant discovery prefix")
    except ValueError as exc:
        raise ValueError(f"mqtt:// {exc}. Form: {FORM}") from None
    return MqttConfig(
        host=parts.hostname, port=port or (8883 if tls else 1883),
        username=unquote(parts.username) if parts.username else None, prefix=prefix,
        qos=opts["qos"], keepalive=opts["keepalive"], max_queued=opts["max_queued"],
        spool=opts["spool"], spool_mb=opts["spool_mb"], tls=tls, ca=opts["ca"], cert=opts["cert"],
        key=opts["key"], client_id=opts["client_id"], retry_s=opts["retry_s"], close_s=opts["close_s"],
        ha=opts["ha"], ha_prefix=opts["ha_prefix"], password_env=opts["password_env"],
    )


__all__ = ["FORM", "OPTIONS", "PASSWORD_ENV", "SCHEME", "MqttConfig", "parse"]

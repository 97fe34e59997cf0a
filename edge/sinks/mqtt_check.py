"""`cavatar doctor` for mqtt:// sinks: the spool folder, the broker over TCP, then an MQTT CONNECT with the login.

The login is the configured user and the password from the environment variable the URL names
(``password_env``, default ``CAVATAR_MQTT_PASSWORD``); the password is never printed. Every
failure says what to check. Reached through :func:`edge.sinks.mqtt.check`.
"""

from __future__ import annotations

import os
import socket
import ssl
import time
from pathlib import Path
from typing import Any

from edge.health import FAIL, OK, WARN, CheckContext, Finding, writable_file
from edge.sinks.mqtt_url import MqttConfig

LOGIN_REFUSED = ("Bad user name or password", "Not authorized")


def check_broker(name: str, c: MqttConfig, ctx: CheckContext) -> list[Finding]:
    """The findings of one mqtt:// sink called ``name``: the broker's, then its spool folder's when it has one."""
    spool = [writable_file(f"{name} spool", Path(c.spool) / "segment", free_space=True, folder_only=True)] if c.spool else []
    return [_reach_and_login(name, c, ctx)] + spool


def _reach_and_login(name: str, c: MqttConfig, ctx: CheckContext) -> Finding:
    timeout_s = ctx.timeout_s
    where = f"{c.host}:{c.port}"
    try:
        socket.create_connection((c.host, c.port), timeout=timeout_s).close()
    except socket.gaierror as exc:
        return Finding(name, FAIL, f"cannot resolve the broker host {c.host!r} ({exc.strerror}): check the host in "
                       "the URL, DNS or /etc/hosts")
    except OSError as exc:
        return Finding(name, FAIL, f"broker {where} not reachable over TCP within {timeout_s:g} s "
                       f"({exc.strerror or exc}): is the broker running (`systemctl status mosquitto` on its host), "
                       "the port right, a firewall in the way?")
    password = ctx.env.get(c.password_env)
    try:
        tls = _tls_context(c) if c.tls else None
    except (ssl.SSLError, OSError) as exc:
        return Finding(name, FAIL, f"TLS files unusable ({exc}): check ca=, cert=, key= in the URL")
    try:
        rc = _connack(c, password, tls, timeout_s)
    except (OSError, ssl.SSLError) as exc:
        hint = ": check tls=, ca= and the broker's certificate" if c.tls else " (a TLS port needs tls=1)"
        return Finding(name, FAIL, f"MQTT connection to {where} failed ({exc}){hint}")
    who = f"user {c.username!r}" if c.username else "anonymous"
    if rc is None:
        return Finding(name, FAIL, f"{where} accepts TCP but sent no MQTT CONNACK within {timeout_s:g} s: is it an "
                       "MQTT port? (a TLS listener needs tls=1; 8883 is the usual TLS port)")
    if rc.is_failure:
        return Finding(name, FAIL, f"broker {where} refused the MQTT login of {who}: {rc}; "
                       f"{_login_fix(c, str(rc), password, where)}")
    note, level = "", OK
    if c.username and password is None:
        note = f" (without a password: ${c.password_env} is not set here)"
    elif not c.username and password:
        level, note = WARN, (f"; ${c.password_env} is set but the URL names no user, so it is unused: "
                             "mqtt://USER@host/... to log in")
    return Finding(name, level, f"broker {where} reachable, MQTT login accepted ({who}{', TLS' if c.tls else ''})"
                   f"{note}")


def _tls_context(c: MqttConfig) -> ssl.SSLContext:
    """The TLS context of the URL's ca=, cert= and key= (ssl.SSLError or OSError when a file is unusable)."""
    ctx = ssl.create_default_context(cafile=c.ca or None)
    if c.cert:
        ctx.load_cert_chain(c.cert, c.key or None)
    return ctx


def _connack(c: MqttConfig, password: str | None, tls: ssl.SSLContext | None, timeout_s: float) -> Any:
    """The broker's CONNACK reason code for this login, None when it sent none within ``timeout_s``."""
    import paho.mqtt.client as mqtt

    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=f"cavatar-doctor-{os.getpid()}",
                         protocol=mqtt.MQTTv311, clean_session=True)
    client.connect_timeout = timeout_s
    if c.username:
        client.username_pw_set(c.username, password)
    if tls is not None:
        client.tls_set_context(tls)
    answer: dict[str, Any] = {}
    client.on_connect = lambda client, userdata, flags, reason_code, properties: answer.setdefault("rc", reason_code)
    try:
        client.connect(c.host, c.port, keepalive=max(5, int(timeout_s * 2)))
        deadline = time.monotonic() + timeout_s
        while "rc" not in answer and time.monotonic() < deadline:
            client.loop(timeout=0.05)
    finally:
        try:
            client.disconnect()
        except Exception:  # the connection may already be gone; nothing to release then
            pass
    return answer.get("rc")


def _login_fix(c: MqttConfig, reason: str, password: str | None, where: str) -> str:
    if c.username and reason in LOGIN_REFUSED:
        state = "set" if password else "NOT set"
        return (f"check the user in the URL and the password in ${c.password_env} ({state} here; the service "
                "reads it from /etc/cavatar/cavatar.env)")
    if reason in LOGIN_REFUSED:
        return (f"the broker wants a login: put the user in the URL (mqtt://USER@{where}/...) and the password in "
                f"${c.password_env}")
    return "see the broker's log"


__all__ = ["check_broker"]

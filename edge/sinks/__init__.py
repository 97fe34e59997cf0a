"""Sinks, chosen by URL scheme (one module per scheme). They publish body parameters, never pressure.

    open_sink("mqtt://cavatar@broker.local:1883/cavatar?qos=1&spool=/var/lib/cavatar/spool", device="carpet-01")
    open_sink("jsonl:///var/lib/cavatar/bodies.jsonl?rotate_mb=100&keep=10", device="carpet-01")
    open_sink("jsonl:-", device="carpet-01")

Each scheme module defines SCHEME, FORM (the accepted form, quoted in errors), OPTIONS,
``parse(url)`` (the URL checked, nothing opened), ``open_sink(url, device) -> Sink`` and
``check(url, ctx) -> list[Finding]`` (its `cavatar doctor` check, see :mod:`edge.health`).
Schemes resolve through one :class:`edge.urls.Schemes` registry, ``SINKS``; a scheme whose
module fails to import (an optional dependency missing) is reported when asked for, not at import.
"""

from __future__ import annotations

from typing import Any

from edge.health import CheckContext, Finding
from edge.sinks.base import Sink, SinkError
from edge.urls import Schemes, redact

SCHEMES = {
    "mqtt": "edge.sinks.mqtt",
    "jsonl": "edge.sinks.jsonl",
}
SINKS = Schemes("sink", SCHEMES, separator=":", unavailable=SinkError)

__all__ = ["open_sink", "accepted_forms", "check_sink", "sink_url_problem", "redact", "Sink", "SinkError", "SCHEMES",
           "SINKS"]


def accepted_forms() -> str:
    return SINKS.accepted_forms()


def open_sink(url: str, *, device: str, **kwargs: Any) -> Sink:
    """The sink for ``url``, publishing as ``device``. ValueError for an unknown scheme or option."""
    return SINKS.handler(url).open_sink(url, device, **kwargs)


def sink_url_problem(url: str) -> str | None:
    """What is wrong with ``url`` (scheme, options, a password in it), or None. Opens nothing."""
    try:
        SINKS.handler(url).parse(url)
    except (ValueError, SinkError) as exc:
        return str(exc)
    return None


def check_sink(url: str, ctx: CheckContext) -> list[Finding]:
    """``url``'s scheme's own health check (folder writable, broker reachable, …). ValueError for an unknown scheme
    or option, SinkError when the scheme cannot load here."""
    return SINKS.handler(url).check(url, ctx)

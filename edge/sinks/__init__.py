"""Sinks, chosen by URL scheme (one module per scheme). They publish body parameters, never pressure.

    open_sink("mqtt://cavatar@broker.local:1883/cavatar?qos=1&spool=/var/lib/cavatar/spool", device="carpet-01")
    open_sink("jsonl:///var/lib/cavatar/bodies.jsonl?rotate_mb=100&keep=10", device="carpet-01")
    open_sink("jsonl:-", device="carpet-01")

Each scheme module defines SCHEME, FORM (the accepted form, quoted in errors), OPTIONS and
``open_sink(url, device) -> Sink``. A scheme whose module fails to import (an optional
dependency missing) is reported when asked for, not at import.
"""

from __future__ import annotations

import importlib
import re
from typing import Any

from edge.sinks.base import Sink, SinkError

SCHEMES = {
    "mqtt": "edge.sinks.mqtt",
    "jsonl": "edge.sinks.jsonl",
}

__all__ = ["open_sink", "accepted_forms", "Sink", "SinkError", "SCHEMES"]


def accepted_forms() -> str:
    return "; ".join(importlib.import_module(m).FORM for m in SCHEMES.values())


def redact(url: str) -> str:
    """``url`` safe to print: a password in the user part is replaced by ***."""
    return re.sub(r"^([A-Za-z][A-Za-z0-9+.-]*://[^/@:]*):[^/@]*@", r"\1:***@", url)


def open_sink(url: str, *, device: str, **kwargs: Any) -> Sink:
    """The sink for ``url``, publishing as ``device``. ValueError for an unknown scheme or option."""
    scheme, sep, _ = url.partition(":")
    if not sep or scheme not in SCHEMES:
        raise ValueError(f"unknown sink {redact(url)!r}. Accepted forms: {accepted_forms()}")
    try:
        module = importlib.import_module(SCHEMES[scheme])
    except ImportError as exc:
        raise SinkError(f"{scheme}:// sinks are unavailable here: {exc}") from None
    return module.open_sink(url, device, **kwargs)

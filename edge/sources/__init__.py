"""Carpet sources, chosen by URL scheme (one module per scheme).

    open_source("serial:///dev/ttyACM0?baud=2000000")
    open_source("usb://1209:CA7A")
    open_source("replay://capture.bin?speed=1")
    open_source("sim://?people=2&seed=7")

Each scheme module defines SCHEME, FORM (the accepted form, quoted in errors),
OPTIONS and ``open_link(url, **kwargs) -> Link``. A scheme whose module fails to
import (an optional dependency missing) is reported when asked for, not at import.
"""

from __future__ import annotations

import importlib
from typing import Any

from edge.sources.base import Link, LinkEnded, LinkLost, SourceError
from edge.sources.carpet import CarpetSource, CommandRefused

SCHEMES = {
    "serial": "edge.sources.serial_port",
    "usb": "edge.sources.usb_bulk",
    "replay": "edge.sources.replay",
    "sim": "edge.sources.sim",
}

__all__ = ["open_source", "open_link", "CarpetSource", "CommandRefused", "SourceError", "Link", "LinkLost", "LinkEnded", "SCHEMES"]


def accepted_forms() -> str:
    return ", ".join(importlib.import_module(m).FORM for m in SCHEMES.values())


def open_link(url: str, **kwargs: Any) -> Link:
    """The byte link for ``url`` (not opened). ValueError for an unknown scheme or option."""
    scheme, sep, _ = url.partition("://")
    if not sep or scheme not in SCHEMES:
        raise ValueError(f"unknown source {url!r}. Accepted forms: {accepted_forms()}")
    try:
        module = importlib.import_module(SCHEMES[scheme])
    except ImportError as exc:
        raise SourceError(f"{scheme}:// sources are unavailable here: {exc}") from None
    return module.open_link(url, **kwargs)


def open_source(url: str, *, usb_backend: Any = None, **kwargs: Any) -> CarpetSource:
    """A :class:`CarpetSource` for ``url`` (call ``start()`` or use ``with``)."""
    link = open_link(url, usb_backend=usb_backend)
    if "speed" not in kwargs and hasattr(link, "speed"):
        kwargs["speed"] = link.speed
    return CarpetSource(link, **kwargs)

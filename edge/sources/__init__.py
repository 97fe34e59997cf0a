"""Carpet sources, chosen by URL scheme (one module per scheme).

    open_source("serial:///dev/ttyACM0?baud=2000000")
    open_source("usb://1209:CA7A")
    open_source("replay://capture.bin?speed=1")
    open_source("sim://?people=2&seed=7")          # a plug-in: the virtual carpet of sim

Each built-in scheme module defines SCHEME, FORM (the accepted form, quoted in errors),
OPTIONS, ``open_link(url, **kwargs) -> Link`` and ``check(url, ctx) -> (Finding, Board | None)``
(its `cavatar doctor` check, see :mod:`edge.health`). Other packages add schemes as plug-ins
(entry-point group ``cavatar.sources``, see :mod:`edge.sources.plugins`): a virtual carpet
behind a virtual board, served by :class:`edge.sources.virtual.VirtualScheme`. Schemes resolve
through one :class:`edge.urls.Schemes` registry, ``SOURCES``; a scheme whose module fails to
import (an optional dependency or plug-in missing or broken) is reported when asked for and in
the accepted forms, never at import.
"""

from __future__ import annotations

from typing import Any

from edge.health import Board, CheckContext, Finding
from edge.sources import plugins, virtual
from edge.sources.base import Link, LinkEnded, LinkLost, SourceError, parse_url
from edge.sources.carpet import CarpetSource, CommandRefused
from edge.urls import Loader, Schemes

SCHEMES = {
    "serial": "edge.sources.serial_port",
    "usb": "edge.sources.usb_bulk",
    "replay": "edge.sources.replay",
}

__all__ = ["open_source", "open_link", "source_options", "source_plugin", "accepted_forms", "check_source",
           "CarpetSource", "CommandRefused", "SourceError", "Link", "LinkLost", "LinkEnded", "SCHEMES", "SOURCES"]


def _plugin_schemes() -> dict[str, Loader]:
    def loader(plugin: plugins.Plugin) -> Loader:
        return lambda: virtual.VirtualScheme(plugins.load(plugin))

    return {scheme: loader(plugin) for scheme, plugin in plugins.registered().items()}


SOURCES = Schemes("source", SCHEMES, plugins=_plugin_schemes, unavailable=SourceError,
                  hint=f" (plug-in schemes such as sim:// come from installed entry points, {plugins.GROUP}: reinstall "
                  "with `pip install -e .` if one is missing)")


def accepted_forms() -> str:
    return SOURCES.accepted_forms()


def source_plugin(url: str) -> plugins.Plugin | None:
    """The loaded plug-in serving ``url``'s scheme, None for a built-in scheme; ValueError for an unknown
    scheme, SourceError when the plug-in cannot be loaded here."""
    if SOURCES.scheme_of(url) in SCHEMES:
        return None
    return SOURCES.handler(url).plugin


def source_options(url: str) -> dict[str, Any]:
    """``url``'s typed options, checked against its scheme (ValueError that quotes the form)."""
    handler = SOURCES.handler(url)
    return parse_url(url, handler.SCHEME, handler.FORM, handler.OPTIONS)[1]


def open_link(url: str, **kwargs: Any) -> Link:
    """The byte link for ``url`` (not opened). ValueError for an unknown scheme or option."""
    return SOURCES.handler(url).open_link(url, **kwargs)


def check_source(url: str, ctx: CheckContext) -> tuple[Finding, Board | None]:
    """``url``'s scheme's own health check (device present and accessible, capture readable, …) and what the URL
    alone tells of the board (a virtual carpet's options; None: the board must be asked). ValueError for an unknown
    scheme or option, SourceError when the scheme cannot load here."""
    return SOURCES.handler(url).check(url, ctx)


def open_source(url: str, *, usb_backend: Any = None, source_class: type[CarpetSource] = CarpetSource,
                **kwargs: Any) -> CarpetSource:
    """A ``source_class`` (:class:`CarpetSource`) for ``url``; call ``start()`` or use ``with``."""
    link = open_link(url, usb_backend=usb_backend)
    if "speed" not in kwargs and hasattr(link, "speed"):
        kwargs["speed"] = link.speed
    return source_class(link, **kwargs)

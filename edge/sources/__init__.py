"""Carpet sources, chosen by URL scheme (one module per scheme).

    open_source("serial:///dev/ttyACM0?baud=2000000")
    open_source("usb://1209:CA7A")
    open_source("replay://capture.bin?speed=1")
    open_source("sim://?people=2&seed=7")          # a plug-in: the virtual carpet of sim

Each built-in scheme module defines SCHEME, FORM (the accepted form, quoted in errors),
OPTIONS and ``open_link(url, **kwargs) -> Link``. Other packages add schemes as plug-ins
(entry-point group ``cavatar.sources``, see :mod:`edge.sources.plugins`): a virtual carpet
behind a virtual board. A scheme whose module fails to import (an optional dependency or
plug-in missing or broken) is reported when asked for and in the accepted forms, never at
import.
"""

from __future__ import annotations

import importlib
from typing import Any

from edge.sources import plugins, virtual
from edge.sources.base import Link, LinkEnded, LinkLost, SourceError, parse_url
from edge.sources.carpet import CarpetSource, CommandRefused

SCHEMES = {
    "serial": "edge.sources.serial_port",
    "usb": "edge.sources.usb_bulk",
    "replay": "edge.sources.replay",
}

__all__ = ["open_source", "open_link", "source_options", "source_plugin", "accepted_forms", "CarpetSource",
           "CommandRefused", "SourceError", "Link", "LinkLost", "LinkEnded", "SCHEMES"]


def _form(scheme: str) -> str:
    try:
        if scheme in SCHEMES:
            return importlib.import_module(SCHEMES[scheme]).FORM
        return plugins.load(plugins.registered()[scheme]).form
    except ImportError as exc:
        return f"{scheme}:// (unavailable here: {exc})"


def accepted_forms() -> str:
    return ", ".join(_form(s) for s in [*SCHEMES, *sorted(set(plugins.registered()) - set(SCHEMES))])


def _scheme_of(url: str) -> str:
    scheme, sep, _ = url.partition("://")
    if not sep or (scheme not in SCHEMES and scheme not in plugins.registered()):
        raise ValueError(f"unknown source {url!r}. Accepted forms: {accepted_forms()} (plug-in schemes such as sim:// "
                         f"come from installed entry points, {plugins.GROUP}: reinstall with `pip install -e .` if one "
                         "is missing)")
    return scheme


def source_plugin(url: str) -> plugins.Plugin | None:
    """The loaded plug-in serving ``url``'s scheme, None for a built-in scheme; ValueError for an unknown
    scheme, SourceError when the plug-in cannot be loaded here."""
    scheme = _scheme_of(url)
    if scheme in SCHEMES:
        return None
    try:
        return plugins.load(plugins.registered()[scheme])
    except ImportError as exc:
        raise SourceError(f"{scheme}:// sources are unavailable here: {exc}") from None


def _builtin(scheme: str) -> Any:
    try:
        return importlib.import_module(SCHEMES[scheme])
    except ImportError as exc:
        raise SourceError(f"{scheme}:// sources are unavailable here: {exc}") from None


def source_options(url: str) -> dict[str, Any]:
    """``url``'s typed options, checked against its scheme (ValueError that quotes the form)."""
    plugin = source_plugin(url)
    if plugin is not None:
        return parse_url(url, plugin.scheme, plugin.form, plugin.options)[1]
    module = _builtin(_scheme_of(url))
    return parse_url(url, module.SCHEME, module.FORM, module.OPTIONS)[1]


def open_link(url: str, **kwargs: Any) -> Link:
    """The byte link for ``url`` (not opened). ValueError for an unknown scheme or option."""
    plugin = source_plugin(url)
    if plugin is not None:
        return virtual.open_link(url, plugin)
    return _builtin(_scheme_of(url)).open_link(url, **kwargs)


def open_source(url: str, *, usb_backend: Any = None, **kwargs: Any) -> CarpetSource:
    """A :class:`CarpetSource` for ``url`` (call ``start()`` or use ``with``)."""
    link = open_link(url, usb_backend=usb_backend)
    if "speed" not in kwargs and hasattr(link, "speed"):
        kwargs["speed"] = link.speed
    return CarpetSource(link, **kwargs)

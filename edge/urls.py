"""URLs of sources and sinks: ``scheme://location?option=value``, resolved by scheme, typed options, clear errors.

    SINKS = Schemes("sink", {"mqtt": "edge.sinks.mqtt", "jsonl": "edge.sinks.jsonl"}, separator=":")
    module = SINKS.handler("jsonl:///var/lib/cavatar/bodies.jsonl")   # the jsonl scheme module
    SINKS.handler("ftp://x")   # ValueError: unknown sink 'ftp://x'. Accepted forms: mqtt://… ; jsonl://…

One :class:`Schemes` registry per kind of URL (edge.sources, edge.sinks): built-in scheme modules
are imported when first asked for, plug-in schemes come from a callable; a scheme whose module
cannot be imported is reported when asked for and in the accepted forms, never at import.
Standard library only, so that sinks and sources share it without importing each other.
"""

from __future__ import annotations

import importlib
import re
from dataclasses import dataclass
from typing import Any, Callable, Mapping
from urllib.parse import parse_qsl, urlsplit

Loader = Callable[[], Any]  # returns a scheme's handler (module or object), raises ImportError when unavailable


@dataclass(frozen=True)
class Option:
    """One query-string option of a source URL."""

    parse: Callable[[str], Any]
    default: Any
    doc: str


def parse_bool(text: str) -> bool:
    if text.lower() in ("1", "true", "yes", "on"):
        return True
    if text.lower() in ("0", "false", "no", "off"):
        return False
    raise ValueError(f"expected 0/1, got {text!r}")


def parse_url(url: str, scheme: str, form: str, options: dict[str, Option], kind: str = "source") -> tuple[str, dict[str, Any]]:
    """Split ``url`` into its location (netloc + path) and typed options.

    Unknown or malformed options are a ValueError that quotes ``form`` and lists the
    accepted options with their meaning.
    """
    parts = urlsplit(url)
    location = parts.netloc + parts.path
    accepted = "; ".join(f"{k} ({o.doc}, default {o.default})" for k, o in options.items()) or "none"
    values = {k: o.default for k, o in options.items()}
    for key, raw in parse_qsl(parts.query, keep_blank_values=True):
        if key not in options:
            raise ValueError(f"{scheme}:// {kind} has no option {key!r}. Form: {form}. Options: {accepted}")
        try:
            values[key] = options[key].parse(raw)
        except ValueError as exc:
            raise ValueError(f"{scheme}:// option {key}={raw!r} is not valid ({exc}). Form: {form}") from None
    return location, values


def redact(url: str) -> str:
    """``url`` safe to print: a password in the user part is replaced by ***."""
    return re.sub(r"^([A-Za-z][A-Za-z0-9+.-]*://[^/@:]*):[^/@]*@", r"\1:***@", url)


def _import(path: str) -> Loader:
    return lambda: importlib.import_module(path)


class Schemes:
    """scheme → handler for one kind of URL (``kind``: "source" or "sink").

    A handler is the scheme's module (or an object like one): ``FORM`` (the accepted form, quoted in
    errors), ``OPTIONS``, ``check(url, ctx)`` and the kind's opener. ``modules`` maps the built-in
    schemes to their module paths, in the order errors list them; ``plugins()`` gives more schemes
    as ``{scheme: loader}`` (asked again each time, so newly registered ones count). ``separator``
    ends the scheme (``"://"``, or ``":"`` where ``jsonl:-`` is a URL); ``hint`` closes the
    unknown-scheme error; ``unavailable`` is the error raised when a scheme's module cannot load.
    """

    def __init__(self, kind: str, modules: Mapping[str, str], *, separator: str = "://", hint: str = "",
                 plugins: Callable[[], Mapping[str, Loader]] | None = None,
                 unavailable: type[Exception] = ImportError) -> None:
        self.kind, self.modules, self.separator, self.hint = kind, dict(modules), separator, hint
        self._plugins = plugins or dict
        self.unavailable = unavailable

    def loaders(self) -> dict[str, Loader]:
        """Every scheme, built-ins first (in their order), then plug-ins by name."""
        found = {scheme: _import(path) for scheme, path in self.modules.items()}
        extra = self._plugins()
        found.update((scheme, extra[scheme]) for scheme in sorted(set(extra) - set(found)))
        return found

    def accepted_forms(self) -> str:
        """Every scheme's FORM, "; "-separated; a scheme that cannot load says why instead."""
        forms = []
        for scheme, load in self.loaders().items():
            try:
                forms.append(load().FORM)
            except ImportError as exc:
                forms.append(f"{scheme}:// (unavailable here: {exc})")
        return "; ".join(forms)

    def scheme_of(self, url: str) -> str:
        """``url``'s scheme; ValueError quoting the accepted forms when it is not one of this registry's."""
        scheme, sep, _ = url.partition(self.separator)
        if not sep or scheme not in self.loaders():
            forms = self.accepted_forms() or "none"
            raise ValueError(f"unknown {self.kind} {redact(url)!r}. Accepted forms: {forms}{self.hint}")
        return scheme

    def handler(self, url: str) -> Any:
        """The handler of ``url``'s scheme: ValueError for an unknown scheme, ``unavailable`` when it cannot load."""
        scheme = self.scheme_of(url)
        try:
            return self.loaders()[scheme]()
        except ImportError as exc:
            raise self.unavailable(f"{scheme}:// {self.kind}s are unavailable here: {exc}") from None


__all__ = ["Option", "Schemes", "parse_bool", "parse_url", "redact"]

"""URLs of sources and sinks: ``scheme://location?option=value``, typed options, clear errors.

Standard library only, so that sinks and sources share it without importing each other.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Callable
from urllib.parse import parse_qsl, urlsplit


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

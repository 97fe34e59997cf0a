"""What every carpet source is made of: a byte link, and the errors sources raise.

A *link* moves bytes to and from the readout board (a serial port, a USB bulk pipe,
a recorded file, the in-process virtual carpet). Everything above it — handshake,
decoding, frame assembly, reconnection — is shared (:mod:`edge.sources.carpet`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass
from typing import Any, Callable
from urllib.parse import parse_qsl, urlsplit


class SourceError(Exception):
    """A source cannot be opened or used; the message says what to do."""


class LinkLost(Exception):
    """The link went away (unplugged, closed); a reconnectable source will try again."""


class LinkEnded(Exception):
    """The link has no more data and never will (end of a recording)."""


class Link(ABC):
    """Bytes to and from a board. ``read`` returns b"" on timeout and raises LinkLost / LinkEnded."""

    #: True when bytes arrive at the board's pace (hardware, sim); False for recordings.
    paced: bool = True
    #: True when a lost link is worth reopening.
    reconnectable: bool = True
    #: False for links that cannot carry commands (recordings).
    writable: bool = True

    @abstractmethod
    def open(self) -> None:
        """Open the link. SourceError for a mistake the user must fix, LinkLost for a transient failure."""

    @abstractmethod
    def read(self, timeout_s: float) -> bytes: ...

    @abstractmethod
    def write(self, data: bytes) -> None: ...

    @abstractmethod
    def close(self) -> None: ...

    def describe(self) -> str:
        return type(self).__name__


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


def parse_url(url: str, scheme: str, form: str, options: dict[str, Option]) -> tuple[str, dict[str, Any]]:
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
            raise ValueError(f"{scheme}:// source has no option {key!r}. Form: {form}. Options: {accepted}")
        try:
            values[key] = options[key].parse(raw)
        except ValueError as exc:
            raise ValueError(f"{scheme}:// option {key}={raw!r} is not valid ({exc}). Form: {form}") from None
    return location, values

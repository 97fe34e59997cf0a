"""The errors several packages raise or catch: one class each, defined once, low in the layering.

- :class:`CliError`: a user-facing error of any ``cavatar`` subcommand (edge, sim, export,
  calibration all have some): printed as one line, no traceback, exit code 2.
- :class:`SourceError`, :class:`LinkLost`, :class:`LinkEnded`: what a carpet source raises
  (edge.sources and its plug-ins) and what calibration catches while it reads frames.

Standard library only.
"""

from __future__ import annotations


class CliError(Exception):
    """A user-facing error: printed as one line (no traceback), exit code 2."""


class SourceError(Exception):
    """A source cannot be opened or used; the message says what to do."""


class LinkLost(Exception):
    """The link went away (unplugged, closed); a reconnectable source will try again."""


class LinkEnded(Exception):
    """The link has no more data and never will (end of a recording)."""


__all__ = ["CliError", "LinkEnded", "LinkLost", "SourceError"]

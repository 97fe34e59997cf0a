"""The runtime's own errors.

``SetupError``: the runtime refuses to start (a tampered bundle, a calibration of another
carpet, a status file it cannot write, a sink it cannot open …). Its message is one paragraph
that says what is wrong and what to do; `cavatar run` prints it and exits 2, nothing written.
"""

from __future__ import annotations


class SetupError(Exception):
    """The runtime cannot start as configured; the message says why and what to do."""


__all__ = ["SetupError"]

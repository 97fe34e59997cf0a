"""What every carpet source is made of: a byte link, and the errors sources raise (from cavatar_common.errors).

A *link* moves bytes to and from the readout board (a serial port, a USB bulk pipe,
a recorded file, the in-process virtual carpet). Everything above it — handshake,
decoding, frame assembly, reconnection — is shared (:mod:`edge.sources.carpet`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod

from cavatar_common.errors import LinkEnded, LinkLost, SourceError  # noqa: F401  (shared with calibration and plug-ins)
from edge.urls import Option, parse_bool, parse_url  # noqa: F401  (re-exported for the scheme modules)


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

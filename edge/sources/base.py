"""What every carpet source is made of: a byte link, the errors sources raise (from cavatar_common.errors), and
the interface the runtime reads frames through (:class:`FrameSource`).

A *link* moves bytes to and from the readout board (a serial port, a USB bulk pipe,
a recorded file, the in-process virtual carpet). Everything above it — handshake,
decoding, frame assembly, reconnection — is shared (:mod:`edge.sources.carpet`).
"""

from __future__ import annotations

from abc import ABC, abstractmethod
from typing import TYPE_CHECKING, Any, Iterator, Protocol, cast

from cavatar_common.errors import LinkEnded, LinkLost, SourceError  # noqa: F401  (shared with calibration and plug-ins)
from edge.urls import Option, parse_bool, parse_url  # noqa: F401  (re-exported for the scheme modules)

if TYPE_CHECKING:
    from edge.frames import RawFrame


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


class FrameSource(Protocol):
    """What the runtime reads frames from (:class:`edge.sources.CarpetSource` is one; tests inject others).

    Every member is read by the runtime's loop; :func:`require_frame_source` refuses an object that lacks
    one when the runtime is built, so a partial source fails at construction, never mid-run.
    """

    #: The board's INFO (rows, cols, adc_bits, device_id, firmware…) once started; None before.
    info: Any
    #: The board's latest STATUS packet (temperature…); None until one arrives.
    last_status: Any

    def start(self) -> None: ...

    def stop(self) -> None: ...

    def frames(self, timeout_s: float | None = None) -> Iterator[RawFrame]: ...

    @property
    def ended(self) -> bool:
        """True once no frame will come any more (end of a recording, a fatal error) and every one was taken."""
        ...

    def queue_depth(self) -> tuple[int, int]:
        """(frames waiting now, the queue's bound); any thread."""
        ...

    def stats(self) -> dict[str, Any]:
        """Counters of every stage (decoder, assembly, link, queue), ``board_mismatch`` and ``board_status``."""
        ...


FRAME_SOURCE_MEMBERS = tuple(sorted({*FrameSource.__annotations__,
                                     *(name for name in vars(FrameSource) if not name.startswith("_"))}))
_FRAME_SOURCE_METHODS = tuple(name for name in FRAME_SOURCE_MEMBERS if callable(vars(FrameSource).get(name)))


def require_frame_source(source: object) -> FrameSource:
    """``source`` as a FrameSource; TypeError naming every member it lacks (or has but cannot call)."""
    missing = [name for name in FRAME_SOURCE_MEMBERS if not hasattr(source, name)]
    missing += [f"{name} (not callable)" for name in _FRAME_SOURCE_METHODS
                if hasattr(source, name) and not callable(getattr(source, name))]
    if missing:
        raise TypeError(f"{type(source).__name__} is not a frame source: it lacks {', '.join(missing)} "
                        f"(edge.sources.base.FrameSource: {', '.join(FRAME_SOURCE_MEMBERS)})")
    return cast(FrameSource, source)

"""Board health: is the readout board delivering frames? Its own availability, beside the runtime's.

The runtime can be up (status "online") while the board is not: the cable pulled, the board
hung, or every frame failing its CRC. :class:`BoardHealth` turns frame arrivals into two states
(docs/runtime.md, "Board health"):

    connected ── no good frame for timeout_s ──▶ lost ── a good frame ──▶ connected

- ``connected``: frames arrive. The run starts here (the handshake has just answered), so a
  board that never sends a frame is lost ``timeout_s`` after the start.
- ``lost``: no frame for ``timeout_s`` ([source] board_timeout_s). The reason says why when the
  source's counters tell: the link dropped (unplugged, reset), or bytes still arrive but frames
  fail their checks (bad CRCs, torn frames) — otherwise just "no frames".

:meth:`check` returns a :class:`Change` exactly once per transition, so the caller logs it once,
publishes it once and withdraws presence once. Pure bookkeeping: no threads, no I/O.

    health = BoardHealth(timeout_s=5.0, now_s=time.monotonic())
    health.frame(now_s)                     # every good frame
    change = health.check(now_s, source_stats)   # at least every second: Change | None
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Mapping

CONNECTED = "connected"
LOST = "lost"


@dataclass(frozen=True)
class Change:
    """One transition: the new state, why, and how long the previous state lasted."""

    state: str
    reason: str
    after_s: float


def link_counts(stats: Mapping[str, Any]) -> tuple[int, int]:
    """(link losses, frames refused by the checks) from a source's ``stats()``: disconnects; CRC mismatches,
    torn frames and decoder drops. Missing keys count as 0 (an injected source has none)."""
    queue = stats.get("source", {}) or {}
    asm = stats.get("frames", {}) or {}
    dec = stats.get("decoder", {}) or {}
    bad = int(asm.get("crc_mismatch", 0)) + int(asm.get("torn_dropped", 0)) + int(dec.get("dropped_total", 0))
    return int(queue.get("disconnects", 0)), bad


class BoardHealth:
    """Frame arrivals → ``connected`` / ``lost``, with the transitions reported once each."""

    def __init__(self, timeout_s: float, now_s: float) -> None:
        if not timeout_s > 0:
            raise ValueError(f"board timeout must be > 0 s, got {timeout_s!r}")
        self.timeout_s = float(timeout_s)
        self.state = CONNECTED
        self.reason = ""
        self.last_frame_s = float(now_s)
        self._since_s = float(now_s)
        self._marks: tuple[int, int] | None = None  # link counts at the last good frame

    @property
    def connected(self) -> bool:
        return self.state == CONNECTED

    def frame(self, now_s: float, stats: Mapping[str, Any] | None = None) -> None:
        """A good frame arrived (``stats``: the source's counters now, the reference for the next loss's reason)."""
        self.last_frame_s = float(now_s)
        if stats is not None:
            self._marks = link_counts(stats)

    def age_s(self, now_s: float) -> float:
        """Seconds since the last good frame (or since the start)."""
        return max(0.0, float(now_s) - self.last_frame_s)

    def due(self, now_s: float) -> bool:
        """A transition is due now (cheap: lets the caller fetch the source's counters only then)."""
        return (self.age_s(now_s) >= self.timeout_s) == self.connected

    def check(self, now_s: float, stats: Mapping[str, Any] | None = None) -> Change | None:
        """The transition due now, once; None when the state holds."""
        age = self.age_s(now_s)
        if self.state == CONNECTED and age >= self.timeout_s:
            self.reason = self._why(age, stats)
            return self._enter(LOST, self.reason, now_s)
        if self.state == LOST and age < self.timeout_s:
            self.reason = ""
            return self._enter(CONNECTED, "frames again", now_s)
        return None

    def _enter(self, state: str, reason: str, now_s: float) -> Change:
        after = max(0.0, float(now_s) - self._since_s)
        self.state, self._since_s = state, float(now_s)
        return Change(state, reason, after)

    def _why(self, age_s: float, stats: Mapping[str, Any] | None) -> str:
        base = f"no frames for {age_s:.0f} s"
        if stats is None or self._marks is None:
            return base
        lost, bad = link_counts(stats)
        if lost > self._marks[0]:
            return f"{base}: the link dropped (unplugged or reset; the source keeps reopening it)"
        if bad > self._marks[1]:
            return f"{base}: bytes arrive but {bad - self._marks[1]} frames/packets failed their checks (bad CRC, torn)"
        return base

    def as_dict(self, now_s: float) -> dict[str, Any]:
        """For the status file and info: ``connected``, ``state``, ``reason``, ``last_frame_age_s``, ``timeout_s``."""
        return {"connected": self.connected, "state": self.state, "reason": self.reason or None,
                "last_frame_age_s": round(self.age_s(now_s), 3), "timeout_s": self.timeout_s}


__all__ = ["BoardHealth", "Change", "CONNECTED", "LOST", "link_counts"]

"""A virtual carpet readout board: the device side of the protocol as a pure state machine.

No threads, no I/O, no wall clock unless you inject one: the caller says what time it
is, the board answers with the bytes a real board would have put on the wire by then.
Transports wrap it: :mod:`firmware_protocol.pty_board` (a pseudo-terminal, so the host
uses real pyserial) and :mod:`edge.sources.usb_virtual` (a pyusb backend).

Usage::

    from firmware_protocol import codec
    from firmware_protocol.virtual_board import VirtualBoard

    board = VirtualBoard(rows=96, cols=96, adc_bits=12, packing="packed12")
    dec = codec.StreamDecoder()
    dec.feed(board.read(0.0))                         # [Info]: sent once at power-up
    board.receive(codec.encode_command("START", 1), now_s=0.0)
    pkts = dec.feed(board.read(1.0))                  # Ack, 14 frames (96 Row + FrameEnd each), Status
    board.tear_next_frame(); board.drop_bytes(20)     # faults hit the next frame / next bytes out
    dec.feed(board.read(2.0)); print(board.injected, dec.stats.as_dict())

The board's arguments are :class:`~firmware_protocol.board_settings.BoardSettings`' (checked
there, with the accepted values in the error); ``VirtualBoard(settings=...)`` takes one
made beforehand. The parts: board_settings.py (what it is built with), board_faults.py
(faults waiting to be applied), board_frames.py (rows scanned, packet bytes),
board_firmware.py (the state machine this class puts a lock around).

Time model (all times in the caller's seconds, any epoch, never going backwards):

- Power-up happens at the first time the board is told (``read``/``receive``), or at
  ``replug``. INFO is queued then. The device clock ``t_us`` is
  ``t_us_start + (now - power_up) * 1e6`` wrapping at 2**32.
- While streaming, frame k starts at ``t0_k`` (the first at START, then every
  ``1/rate``); row r is sampled, and due, at ``t0_k + r * row_time_us``; FRAME_END is
  due with the last row. STATUS is due every ``status_interval_s`` while streaming.
- ``read(now_s)`` returns every byte due by ``now_s``. Bytes due but not yet read sit
  in a transmit buffer of ``tx_buffer_bytes``; a frame that does not fit is scanned but
  not sent (``frames_dropped``, a frame_seq gap), as firmware does when the host stops
  reading.
- ``frames(frame_index)`` gets the count of frames scanned since power-up (0, 1, 2, ...);
  ``frame_seq`` on the wire is ``frame_seq_start + frame_index`` wrapping at 2**32.
  Samples are clamped to the ADC range, as an ADC saturates at its rails.

Faults (each deterministic given ``seed``; each hits the *next* bytes or frame out, in
the order they were asked for; ``injected`` counts what was actually applied):

- ``drop_bytes(n)``, ``flip_bits(n)`` (one bit in each of the next n bytes),
  ``garbage(n)`` (n random bytes inserted, may include 0x00): on the link.
- ``stall(s)``: nothing comes out for s seconds, then the backlog in one burst.
- ``tear_next_frame()``: some rows are lost on the link (their packet seqs are used,
  so the decoder counts them ``missed``); FRAME_END still says all rows and carries the
  CRC of the whole frame.
- ``skip_frames(k)``: the next k frames are scanned but not sent (frame_seq gap,
  ``frames_dropped`` in STATUS).
- ``duplicate_next_frame()``: the next frame is sent twice (same frame_seq, new packet seqs).
- ``unplug()`` / ``replug()``: flags that transports obey (``plugged``,
  ``plug_generation``). A bus-powered board (the default) loses power: on replug it
  boots again (INFO, counters and sequence numbers reset, not streaming unless
  ``autostart``); a self-powered one keeps scanning and its output while unplugged is lost.

Every public method takes the board's lock, so transports and tests may call from
different threads.
"""

from __future__ import annotations

import functools
from typing import Any, Iterable

from firmware_protocol import codec
from firmware_protocol.board_firmware import BoardFirmware
from firmware_protocol.board_frames import FrameSource
from firmware_protocol.board_settings import ADC_BITS, MASK32, BoardSettings

__all__ = ["ADC_BITS", "MASK32", "BoardSettings", "FrameSource", "VirtualBoard"]


def _locked(method):
    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        with self._lock:
            return method(self, *args, **kwargs)

    return wrapper


class VirtualBoard(BoardFirmware):
    """The device side of the carpet protocol (see the module docstring): the firmware, locked, with its public face.

    Built as :class:`BoardFirmware` is: ``VirtualBoard(96, 96, adc_bits=12, ...)`` (the
    arguments of :class:`BoardSettings`) or ``VirtualBoard(settings=BoardSettings(...))``;
    ``frames=`` what it scans, ``clock=`` the time when not told.
    """

    # ------------------------------------------------------------------ public: time and I/O

    @_locked
    def read(self, now_s: float | None = None) -> bytes:
        """The device→host bytes due by ``now_s`` (after the link faults). b"" while unplugged or stalled."""
        now = self._time(now_s)
        self._advance(now)
        if not self._plugged or now < self._stall_until:
            return b""
        if not self._pending and not self._faults.link_ops_waiting:
            return b""
        out = self._faults.apply_to_link(bytes(self._pending))
        self._pending.clear()
        self.sent["bytes"] += len(out)
        return out

    @_locked
    def receive(self, data: bytes, now_s: float | None = None) -> None:
        """Host→device bytes, in any chunking. Commands take effect at ``now_s`` (default: the last time seen)."""
        now = self._time(now_s, default_last=True)
        self._advance(now)
        if not self._powered or not self._plugged:
            return  # nothing reaches an unplugged board
        self._receive_bytes(data)

    @_locked
    def next_due_s(self) -> float | None:
        """When ``read`` will next have bytes (now if some are waiting); None when idle. For pacing transports."""
        if not self._plugged and self.bus_powered:
            return None
        if not self._powered:
            return self._now if self._now is not None else 0.0
        cands = []
        if self._pending or self._faults.link_ops_waiting:
            cands.append(self._now)
        t, _ = self._next_event()
        if t is not None:
            cands.append(t)
        if not cands:
            return None
        return max(min(cands), self._stall_until)

    def now(self) -> float | None:
        """The injected clock's time, else the last time the board was told."""
        return self._clock() if self._clock is not None else self._now

    # ------------------------------------------------------------------ public: state

    @property
    def plugged(self) -> bool:
        return self._plugged

    @property
    def powered(self) -> bool:
        return self._powered

    @property
    def streaming(self) -> bool:
        return self._streaming

    @property
    def rate_hz(self) -> float:
        return self._rate_mhz / 1000.0

    @property
    def gain_step(self) -> int | None:
        return self._gain_step if self.has_gain else None

    @property
    def frames_scanned(self) -> int:
        return self._frames_scanned

    @property
    def frames_dropped(self) -> int:
        return self._frames_dropped

    @property
    def rx_stats(self) -> codec.DecoderStats:
        """The board's command decoder counters (since the last power-up)."""
        return self._rx.stats

    @_locked
    def info_packet(self, seq: int = 0) -> Any:
        """The INFO this board sends (a :class:`codec.Info`)."""
        return self._info_packet(seq)

    @_locked
    def status_packet(self, seq: int = 0, t_s: float | None = None) -> Any:
        """The STATUS this board would send at ``t_s`` (default: now), a :class:`codec.Status`."""
        return self._status_packet(seq, t_s)

    # ------------------------------------------------------------------ public: faults

    @_locked
    def drop_bytes(self, n: int) -> None:
        """Lose the next ``n`` bytes out."""
        self._faults.drop_bytes(n)

    @_locked
    def flip_bits(self, n: int) -> None:
        """Flip one (seeded random) bit in each of the next ``n`` bytes out."""
        self._faults.flip_bits(n)

    @_locked
    def garbage(self, n: int, zeros: bool = True) -> bytes:
        """Insert ``n`` seeded random bytes before the next bytes out (``zeros=False``: no 0x00). Returns them."""
        return self._faults.garbage(n, zeros)

    @_locked
    def stall(self, seconds: float, now_s: float | None = None) -> None:
        """Send nothing for ``seconds`` from ``now_s`` (default: now); the backlog follows in one burst."""
        now = self._time(now_s, default_last=True)
        self._stall_until = max(self._stall_until, now + seconds)
        self.injected["stalls"] += 1
        self.injected["stalled_s"] += seconds

    @_locked
    def tear_next_frame(self, missing_rows: Iterable[int] | None = None) -> None:
        """Lose some rows of the next frame sent (default: a seeded choice of max(1, rows//8) rows)."""
        self._faults.tear_next_frame(missing_rows)

    @_locked
    def skip_frames(self, k: int) -> None:
        """Scan the next ``k`` frames without sending them (a frame_seq gap)."""
        self._faults.skip_frames(k)

    @_locked
    def duplicate_next_frame(self) -> None:
        """Send the next frame twice."""
        self._faults.duplicate_next_frame()

    @_locked
    def unplug(self, now_s: float | None = None) -> None:
        """Pull the cable. Bytes not yet read are lost; a bus-powered board powers off."""
        if not self._plugged:
            return
        if now_s is not None or self._clock is not None:
            self._advance(self._time(now_s))
        self._plugged = False
        self.injected["unplugs"] += 1
        self.injected["lost_unplugged_bytes"] += len(self._pending)
        self._pending.clear()
        if self.bus_powered:
            self._power_off()

    @_locked
    def replug(self, now_s: float | None = None) -> None:
        """Plug the cable back in; a bus-powered board boots (at ``now_s``, or the next time it is told)."""
        if self._plugged:
            return
        self._plugged = True
        self.plug_generation += 1
        self.injected["replugs"] += 1
        if now_s is not None:
            self._advance(self._time(now_s))

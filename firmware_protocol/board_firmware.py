"""A virtual board's firmware: power, the scan schedule, frames and packets out, commands in.

:class:`BoardFirmware` is the state machine behind :class:`~firmware_protocol.virtual_board.VirtualBoard`;
``VirtualBoard`` is its public face (its module docstring has the time model and the
faults) and takes the firmware's lock around each call. The settings are checked by
:class:`~firmware_protocol.board_settings.BoardSettings`, the faults wait in
:class:`~firmware_protocol.board_faults.PendingFaults`.
"""

from __future__ import annotations

import dataclasses
import functools
import threading
from collections import Counter
from typing import Any, Callable

from firmware_protocol import cobs, codec
from firmware_protocol.board_faults import PendingFaults
from firmware_protocol.board_frames import (
    FrameInFlight,
    FrameSource,
    packet_wire_bytes,
    scan_rows,
    u16le,
    unloaded_frame,
)
from firmware_protocol.board_settings import MASK32, BoardSettings

_NO_TEMPERATURE = -32768
_NO_GAIN = 0xFFFF


class BoardFirmware:
    """The device side of the carpet protocol as firmware runs it, unlocked (see the module docstring)."""

    def __init__(self, *grid: int, settings: BoardSettings | None = None, frames: FrameSource | None = None,
                 clock: Callable[[], float] | None = None, **settings_kw: Any) -> None:
        """A board built with ``settings``, or with :class:`BoardSettings`' arguments (``VirtualBoard(96, 96, seed=3)``).

        ``frames``: what it scans (default: an unloaded carpet). ``clock``: the time when
        ``read``/``receive`` are not told it (default: none, they must be told).
        """
        if settings is None:
            settings = BoardSettings(*grid, **settings_kw)
        elif grid or settings_kw:
            raise TypeError("VirtualBoard takes settings= or BoardSettings' arguments, not both")
        self._lock = threading.RLock()  # taken by VirtualBoard's public methods
        self.settings = settings
        self._adopt(settings)
        self._clock = clock
        self._frames = frames if frames is not None else functools.partial(
            unloaded_frame, seed=settings.seed, adc_bits=settings.adc_bits, rows=settings.rows, cols=settings.cols)
        # link state and fault injection survive a power cycle
        self._now: float | None = None
        self._plugged = True
        self.plug_generation = 0
        self._stall_until = float("-inf")
        self._faults = PendingFaults(settings.seed)
        self.injected: Counter = self._faults.injected  # what was actually applied (see virtual_board)
        self.sent: Counter = Counter()  # packets by name, "frames", "bytes" (handed out by read)
        self._power_off()

    def _adopt(self, s: BoardSettings) -> None:
        """The settings as the board's attributes (``packing`` is the code, ``max_rate_hz`` the fastest allowed)."""
        self.rows, self.cols, self.tile_rows, self.tile_cols = s.rows, s.cols, s.tile_rows, s.tile_cols
        self.adc_bits, self.packing, self.packing_name, self.sign = s.adc_bits, s.packing_code, str(s.packing), s.sign
        self.device_id, self.fw_version = s.device_id, s.fw_version
        self.protocol_version, self.definition_hash = s.protocol_version, s.definition_hash
        self.has_temperature, self.temperature_c = s.has_temperature, s.temperature_c
        self.has_gain, self.gain_steps, self.default_gain_step = s.has_gain, s.gain_steps, s.gain_step
        self.seed, self.row_time_us, self.status_interval_s = s.seed, s.row_time_us, s.status_interval_s
        self.min_rate_hz, self.max_rate_hz, self.default_rate_mhz = s.min_rate_hz, s.fastest_rate_hz, s.rate_mhz
        self.link_bytes_per_s, self.tx_buffer_bytes = s.link_bytes_per_s, s.tx_buffer_bytes
        self.frame_wire_bytes, self.scan_time_s = s.frame_wire_bytes, s.scan_time_s
        self.t_us_start, self.frame_seq_start, self.seq_start = s.t_us_start, s.frame_seq_start, s.seq_start
        self.autostart, self.bus_powered = s.autostart, s.bus_powered
        self._full_scale = s.full_scale

    def _receive_bytes(self, data: bytes) -> None:
        """Host→device bytes, in any chunking: each complete packet decoded and answered."""
        view = bytes(data)
        start = 0
        while start < len(view):
            z = view.find(b"\x00", start)
            if z < 0:
                self._rx_partial += view[start:]
                if len(self._rx_partial) > 2 * codec.SPEC.max_packet_bytes:
                    self._rx_partial.clear()  # the decoder counts it too_long
                self._rx.feed(view[start:])
                break
            chunk = bytes(self._rx_partial) + view[start:z]
            self._rx_partial.clear()
            self._receive_chunk(chunk, view[start : z + 1])
            start = z + 1

    def _info_packet(self, seq: int = 0) -> Any:
        """The INFO this board sends (a :class:`codec.Info`)."""
        flags = (1 if self.has_temperature else 0) | (2 if self._streaming else 0) | (4 if self.has_gain else 0)
        return codec.Info(
            seq, self.protocol_version, self.definition_hash, *self.fw_version, self.device_id,
            self.rows, self.cols, self.tile_rows, self.tile_cols, self.adc_bits, self.packing, self.sign,
            self._rate_mhz, flags,
        )

    def _status_packet(self, seq: int = 0, t_s: float | None = None) -> Any:
        """The STATUS this board would send at ``t_s`` (default: now), a :class:`codec.Status`."""
        now = t_s if t_s is not None else (self._now if self._now is not None else 0.0)
        st = self._rx.stats
        bad_crc = st.dropped["bad_crc"] + self._rx_foreign
        return codec.Status(
            seq,
            self._t_us(now),
            int(now - self._power_on_s) & MASK32 if self._power_on_s is not None else 0,
            self._frames_scanned & MASK32,
            self._frames_dropped & MASK32,
            0,
            bad_crc & MASK32,
            (st.dropped_bytes - self._rx_bad_crc_bytes) & MASK32,
            self._tx_overflows & MASK32,
            int(round(self.temperature_c * 100)) if self.has_temperature else _NO_TEMPERATURE,
            self._gain_step if self.has_gain else _NO_GAIN,
        )

    # ------------------------------------------------------------------ internals: power and time

    def _power_off(self) -> None:
        self._powered = False
        self._power_on_s: float | None = None
        self._streaming = False
        self._frame: FrameInFlight | None = None
        self._next_frame_t = 0.0
        self._last_frame_t0: float | None = None
        self._next_status_t: float | None = None
        self._pending = bytearray()
        self._seq = self.seq_start
        self._frames_scanned = 0
        self._frames_dropped = 0
        self._tx_overflows = 0
        self._rate_mhz = self.default_rate_mhz
        self._gain_step = self.default_gain_step
        self._rx = codec.StreamDecoder(direction="host_to_device")
        self._rx_partial = bytearray()
        self._rx_bad_crc_bytes = 0
        self._rx_foreign = 0  # commands of our definition refused by a board of another definition

    def _power_on(self, now: float) -> None:
        self._powered = True
        self._power_on_s = now
        self._send(self._info_packet())
        if self.autostart:
            self._start_streaming(now)

    def _time(self, now_s: float | None, default_last: bool = False) -> float:
        if now_s is not None:
            return float(now_s)
        if self._clock is not None:
            return float(self._clock())
        if default_last:
            return self._now if self._now is not None else 0.0
        raise ValueError("read() needs now_s (seconds) unless the board was given a clock=")

    def _t_us(self, t: float) -> int:
        return (self.t_us_start + int((t - self._power_on_s) * 1e6 + 0.5)) & MASK32

    # ------------------------------------------------------------------ internals: scheduling

    def _advance(self, now: float) -> None:
        """Generate every event due by ``now`` into the transmit buffer."""
        if self._now is not None and now < self._now:
            now = self._now  # time never goes backwards
        self._now = now
        if not self._plugged and self.bus_powered:
            return
        if not self._powered:
            self._power_on(now)
        while True:
            t, kind = self._next_event()
            if t is None or t > now:
                break
            if kind == "row":
                self._send_row(t)
            elif kind == "frame":
                self._start_frame(t)
            else:
                self._next_status_t = t + self.status_interval_s
                self._send(self._status_packet(t_s=t))
        if not self._plugged:  # self-powered and unplugged: the bytes go nowhere
            self.injected["lost_unplugged_bytes"] += len(self._pending)
            self._pending.clear()

    def _next_event(self) -> tuple[float | None, str | None]:
        t, kind = None, None
        if self._frame is not None:
            t, kind = self._frame.t0_s + self._frame.next_row * self.row_time_us * 1e-6, "row"
        elif self._streaming:
            t, kind = self._next_frame_t, "frame"
        if self._streaming and self._next_status_t is not None and (t is None or self._next_status_t < t):
            t, kind = self._next_status_t, "status"
        return t, kind

    def _start_streaming(self, now: float) -> None:
        if not self._streaming:
            self._streaming = True
            self._next_frame_t = now if self._last_frame_t0 is None else max(now, self._last_frame_t0 + 1000.0 / self._rate_mhz)
            self._next_status_t = now + self.status_interval_s

    def _start_frame(self, t: float) -> None:
        index = self._frames_scanned
        self._frames_scanned += 1
        self._last_frame_t0 = t
        self._next_frame_t = t + 1000.0 / self._rate_mhz
        seq = (self.frame_seq_start + index) & MASK32
        if self._faults.take_skip():
            self._frames_dropped += 1
            return
        if len(self._pending) + self.frame_wire_bytes > self.tx_buffer_bytes:
            self._frames_dropped += 1
            self._tx_overflows += 1
            return
        rows = scan_rows(self._frames, index, self.rows, self.cols, self._full_scale)
        missing = self._faults.take_tear(self.rows)
        duplicate = self._faults.take_duplicate()
        crc = codec.frame_crc32(u16le(r) for r in rows)
        self._frame = FrameInFlight(index, seq, t, rows, crc, missing, duplicate)

    def _send_row(self, t: float) -> None:
        f = self._frame
        r = f.next_row
        t_us = self._t_us(t)
        if r == 0:
            f.t_us_first = t_us
        pkt = codec.make_row(self._seq, f.seq, t_us, r, f.rows[r], self.packing)
        if r in f.missing:
            self._seq = (self._seq + 1) & 0xFFFF  # sent, lost on the link
            self.injected["torn_rows"] += 1
        else:
            self._send(pkt)
        if f.duplicate:
            f.sent.append(pkt)
        f.next_row += 1
        if f.next_row < self.rows:
            return
        end = codec.FrameEnd(self._seq, f.seq, t_us, self.rows, (t_us - f.t_us_first) & MASK32, f.crc32)
        self._send(end)
        self.sent["frames"] += 1
        if f.duplicate:
            for p in f.sent:
                self._send(dataclasses.replace(p, seq=self._seq))
            self._send(dataclasses.replace(end, seq=self._seq))
            self.sent["frames"] += 1
            self.injected["duplicated_frames"] += 1
        self._frame = None

    def _send(self, pkt: Any) -> None:
        """Queue ``pkt`` with the next packet seq (its seq field is replaced)."""
        if pkt.seq != self._seq:
            pkt = dataclasses.replace(pkt, seq=self._seq)
        self._seq = (self._seq + 1) & 0xFFFF
        self._pending += packet_wire_bytes(pkt, self.definition_hash)
        self.sent[pkt.NAME] += 1

    # ------------------------------------------------------------------ internals: commands

    def _receive_chunk(self, chunk: bytes, seg: bytes) -> None:
        st = self._rx.stats
        bad_crc, unknown, bad_len = st.dropped["bad_crc"], st.dropped["unknown_type"], st.dropped["bad_length"]
        for pkt in self._rx.feed(seg):
            self._handle(pkt)
        if st.dropped["bad_crc"] > bad_crc:
            self._rx_bad_crc_bytes += len(chunk) + 1
        if st.dropped["unknown_type"] > unknown or st.dropped["bad_length"] > bad_len:
            raw = cobs.decode(chunk)
            if raw is not None and len(raw) >= 5:
                reason = "unknown_command" if st.dropped["unknown_type"] > unknown else "bad_length"
                self._send(codec.Nak(0, raw[0], int.from_bytes(raw[1:3], "little"), codec.NAK_REASON[reason]))

    def _handle(self, pkt: Any) -> None:
        name = pkt.NAME
        if self.definition_hash != codec.DEFINITION_HASH and pkt.DEF.seed != "fixed":
            self._rx_foreign += 1  # this board would have failed the command's CRC
            return
        now = self._now

        def ack(value: int = 0) -> None:
            self._send(codec.Ack(0, pkt.TYPE, pkt.seq, value & MASK32))

        def nak(reason: str) -> None:
            self._send(codec.Nak(0, pkt.TYPE, pkt.seq, codec.NAK_REASON[reason]))

        if name == "GET_INFO":
            self._send(self._info_packet())
        elif name == "START":
            self._start_streaming(now)
            ack()
        elif name == "STOP":
            self._streaming = False  # a frame in progress is finished
            self._next_status_t = None
            ack()
        elif name == "SET_RATE":
            if not self.settings.rate_ok(pkt.rate_mhz):
                nak("out_of_range")
                return
            self._rate_mhz = pkt.rate_mhz
            if self._streaming and self._last_frame_t0 is not None:
                self._next_frame_t = max(now, self._last_frame_t0 + 1000.0 / self._rate_mhz)
            ack(pkt.rate_mhz)
        elif name == "SET_GAIN":
            if not self.has_gain:
                nak("unsupported")
            elif pkt.gain_step >= self.gain_steps:
                nak("out_of_range")
            else:
                self._gain_step = pkt.gain_step
                ack(pkt.gain_step)
        elif name == "PING":
            ack(pkt.token)
            self._send(self._status_packet())
        else:  # a host→device packet this firmware does not implement
            nak("unknown_command")

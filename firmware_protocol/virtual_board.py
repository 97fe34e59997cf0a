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

import binascii
import dataclasses
import functools
import random
import sys
import threading
from array import array
from collections import Counter, deque
from typing import Any, Callable, Iterable

from firmware_protocol import cobs, codec

MASK32 = 0xFFFFFFFF
ADC_BITS = (8, 10, 12, 16)
_PACKING_MAX_BITS = {"u8": 8, "packed12": 12, "u16": 16}
_NO_TEMPERATURE = -32768
_NO_GAIN = 0xFFFF

FrameSource = Callable[[int], Iterable[Iterable[int]]]


def _locked(method):
    @functools.wraps(method)
    def wrapper(self, *args, **kwargs):
        with self._lock:
            return method(self, *args, **kwargs)

    return wrapper


def _wire_len(nbytes: int) -> int:
    """Bytes on the wire for a packet of ``nbytes`` before COBS (overhead and delimiter)."""
    return nbytes + nbytes // 254 + 2


@dataclasses.dataclass
class _Frame:
    """A frame being sent row by row."""

    index: int
    seq: int
    t0_s: float
    rows: list  # list of rows, each a list of int samples
    crc32: int
    missing: frozenset
    duplicate: bool
    next_row: int = 0
    t_us_first: int = 0
    sent: list = dataclasses.field(default_factory=list)  # packets, for duplicate_next_frame


def _check_settings(rows: int, cols: int, tile_rows: int | None, tile_cols: int | None, adc_bits: int,
                    packing: str | int, sign: int, device_id: str, fw_version: tuple[int, int, int]) -> tuple[str, int, int]:
    """Every physical setting checked, with the accepted values in the error → (packing name, tile rows, tile cols)."""
    if rows < 1 or cols < 1 or rows > 0xFFFF or cols > 0xFFFF:
        raise ValueError(f"rows and cols must be 1..65535; got {rows}x{cols}")
    if adc_bits not in ADC_BITS:
        raise ValueError(f"adc_bits must be one of {ADC_BITS}; got {adc_bits}")
    packing_name = codec.PACKING_NAMES.get(packing, packing) if isinstance(packing, int) else packing
    if packing_name not in _PACKING_MAX_BITS:
        raise ValueError(f"packing must be one of {sorted(codec.PACKING)} (or its code); got {packing!r}")
    if adc_bits > _PACKING_MAX_BITS[packing_name]:
        raise ValueError(f"packing {packing_name} holds at most {_PACKING_MAX_BITS[packing_name]} bits; adc_bits={adc_bits}")
    if sign not in (-1, 1):
        raise ValueError(f"sign must be -1 (pressure lowers the reading) or +1 (raises it); got {sign}")
    tile_rows = tile_rows if tile_rows is not None else (rows // 32 if rows % 32 == 0 else 1)
    tile_cols = tile_cols if tile_cols is not None else (cols // 32 if cols % 32 == 0 else 1)
    if not (1 <= tile_rows <= 255 and 1 <= tile_cols <= 255) or rows % tile_rows or cols % tile_cols:
        raise ValueError(f"tiles {tile_rows}x{tile_cols} must be 1..255 and divide the grid {rows}x{cols}")
    try:
        device_id.encode("ascii")
    except UnicodeEncodeError:
        raise ValueError(f"device_id must be ASCII; got {device_id!r}") from None
    if not 1 <= len(device_id) <= 16:
        raise ValueError(f"device_id must be 1..16 ASCII characters; got {device_id!r}")
    if len(fw_version) != 3 or not all(0 <= v <= 255 for v in fw_version):
        raise ValueError(f"fw_version must be (major, minor, patch), each 0..255; got {fw_version!r}")
    return str(packing_name), tile_rows, tile_cols


class VirtualBoard:
    """The device side of the carpet protocol (see the module docstring)."""

    def __init__(
        self,
        rows: int = 96,
        cols: int = 96,
        *,
        tile_rows: int | None = None,
        tile_cols: int | None = None,
        adc_bits: int = 12,
        packing: str | int = "packed12",
        sign: int = -1,
        rate_hz: float = 14.0,
        device_id: str = "virtual-carpet",
        fw_version: tuple[int, int, int] = (1, 0, 0),
        has_temperature: bool = True,
        temperature_c: float = 24.0,
        has_gain: bool = True,
        gain_steps: int = 128,
        gain_step: int = 64,
        frames: FrameSource | None = None,
        seed: int = 0,
        row_time_us: float = 100.0,
        min_rate_hz: float = 0.5,
        max_rate_hz: float = 100.0,
        link_bytes_per_s: float | None = None,
        tx_buffer_bytes: int = 1 << 20,
        status_interval_s: float = 1.0,
        t_us_start: int = 0,
        frame_seq_start: int = 0,
        seq_start: int = 0,
        autostart: bool = False,
        bus_powered: bool = True,
        clock: Callable[[], float] | None = None,
        protocol_version: int | None = None,
        definition_hash: int | None = None,
    ) -> None:
        """Configure the board. Everything physical is checked here, with the accepted values in the error.

        ``protocol_version``/``definition_hash`` make a board built from another protocol
        definition (INFO carries them, and definition-seeded packets are CRC'd with that
        hash), to test that a host refuses it loudly.
        """
        self._lock = threading.RLock()
        packing_name, tile_rows, tile_cols = _check_settings(rows, cols, tile_rows, tile_cols, adc_bits, packing, sign,
                                                             device_id, fw_version)
        self.rows, self.cols = rows, cols
        self.tile_rows, self.tile_cols = tile_rows, tile_cols
        self.adc_bits = adc_bits
        self.packing = codec.PACKING[packing_name]
        self.packing_name = packing_name
        self.sign = sign
        self.device_id = device_id
        self.fw_version = tuple(fw_version)
        self.has_temperature = has_temperature
        self.temperature_c = temperature_c
        self.has_gain = has_gain
        self.gain_steps = gain_steps
        self.default_gain_step = gain_step
        self.seed = seed
        self.row_time_us = float(row_time_us)
        self.min_rate_hz = min_rate_hz
        self.link_bytes_per_s = link_bytes_per_s
        self.tx_buffer_bytes = tx_buffer_bytes
        self.status_interval_s = status_interval_s
        self.t_us_start = t_us_start & MASK32
        self.frame_seq_start = frame_seq_start & MASK32
        self.seq_start = seq_start & 0xFFFF
        self.autostart = autostart
        self.bus_powered = bus_powered
        self._clock = clock
        self.protocol_version = codec.PROTOCOL_VERSION if protocol_version is None else protocol_version
        self.definition_hash = codec.DEFINITION_HASH if definition_hash is None else definition_hash
        self._frames = frames if frames is not None else self._default_frames
        self._full_scale = (1 << adc_bits) - 1

        self._set_rates(rate_hz, max_rate_hz)
        self._init_link(seed)
        self._power_off()

    def _set_rates(self, rate_hz: float, max_rate_hz: float) -> None:
        """The wire size of a frame and the fastest rate the scan, the link and ``max_rate_hz`` allow."""
        row_bytes = 18 + codec.packed_size(self.cols, self.packing)
        if row_bytes > codec.SPEC.max_packet_bytes:
            raise ValueError(f"a ROW of {self.cols} samples in {self.packing_name} takes {row_bytes} bytes "
                             f"> max_packet_bytes={codec.SPEC.max_packet_bytes}")
        self.frame_wire_bytes = self.rows * _wire_len(row_bytes) + _wire_len(23)
        self.scan_time_s = self.rows * self.row_time_us * 1e-6
        limits = [max_rate_hz, 1.0 / self.scan_time_s]
        if self.link_bytes_per_s:
            limits.append(self.link_bytes_per_s / self.frame_wire_bytes)
        self.max_rate_hz = min(limits)
        self.default_rate_mhz = int(round(rate_hz * 1000))
        if not self._rate_ok(self.default_rate_mhz):
            raise ValueError(f"rate_hz={rate_hz} is outside {self.min_rate_hz}..{self.max_rate_hz:.3f} Hz for this board")

    def _init_link(self, seed: int) -> None:
        """Link state and fault injection; survives a power cycle."""
        self._now: float | None = None
        self._plugged = True
        self.plug_generation = 0
        self._stall_until = float("-inf")
        self._link_ops: deque = deque()  # ("garbage", bytes) | ("drop", n) | ("flip", n)
        self._fault_rng = random.Random(seed ^ 0x5EED_F417)
        self._tear_next = 0  # frames to tear
        self._tear_rows: list[Iterable[int] | None] = []
        self._dup_next = 0
        self._skip_next = 0
        self.injected: Counter = Counter()  # what was actually applied, see the module docstring
        self.sent: Counter = Counter()  # packets by name, "frames", "bytes" (handed out by read)

    # ------------------------------------------------------------------ public: time and I/O

    @_locked
    def read(self, now_s: float | None = None) -> bytes:
        """The device→host bytes due by ``now_s`` (after the link faults). b"" while unplugged or stalled."""
        now = self._time(now_s)
        self._advance(now)
        if not self._plugged or now < self._stall_until:
            return b""
        if not self._pending and not self._link_ops:
            return b""
        out = self._apply_link_faults(bytes(self._pending))
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

    @_locked
    def next_due_s(self) -> float | None:
        """When ``read`` will next have bytes (now if some are waiting); None when idle. For pacing transports."""
        if not self._plugged and self.bus_powered:
            return None
        if not self._powered:
            return self._now if self._now is not None else 0.0
        cands = []
        if self._pending or self._link_ops:
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
        flags = (1 if self.has_temperature else 0) | (2 if self._streaming else 0) | (4 if self.has_gain else 0)
        return codec.Info(
            seq, self.protocol_version, self.definition_hash, *self.fw_version, self.device_id,
            self.rows, self.cols, self.tile_rows, self.tile_cols, self.adc_bits, self.packing, self.sign,
            self._rate_mhz, flags,
        )

    @_locked
    def status_packet(self, seq: int = 0, t_s: float | None = None) -> Any:
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

    # ------------------------------------------------------------------ public: faults

    @_locked
    def drop_bytes(self, n: int) -> None:
        """Lose the next ``n`` bytes out."""
        if n > 0:
            self._link_ops.append(("drop", int(n)))

    @_locked
    def flip_bits(self, n: int) -> None:
        """Flip one (seeded random) bit in each of the next ``n`` bytes out."""
        if n > 0:
            self._link_ops.append(("flip", int(n)))

    @_locked
    def garbage(self, n: int, zeros: bool = True) -> bytes:
        """Insert ``n`` seeded random bytes before the next bytes out (``zeros=False``: no 0x00). Returns them."""
        junk = bytearray(self._fault_rng.randbytes(n))
        if not zeros:
            junk = bytearray(b or 1 + self._fault_rng.randrange(255) for b in junk)
        if n > 0:
            self._link_ops.append(("garbage", bytes(junk)))
        return bytes(junk)

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
        self._tear_next += 1
        self._tear_rows.append(None if missing_rows is None else list(missing_rows))

    @_locked
    def skip_frames(self, k: int) -> None:
        """Scan the next ``k`` frames without sending them (a frame_seq gap)."""
        self._skip_next += max(0, int(k))

    @_locked
    def duplicate_next_frame(self) -> None:
        """Send the next frame twice."""
        self._dup_next += 1

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

    # ------------------------------------------------------------------ internals: power and time

    def _power_off(self) -> None:
        self._powered = False
        self._power_on_s: float | None = None
        self._streaming = False
        self._frame: _Frame | None = None
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
        self._send(self.info_packet())
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

    def _rate_ok(self, rate_mhz: int) -> bool:
        return self.min_rate_hz * 1000 - 1e-9 <= rate_mhz <= self.max_rate_hz * 1000 + 1e-9

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
                self._send(self.status_packet(t_s=t))
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
        if self._skip_next > 0:
            self._skip_next -= 1
            self._frames_dropped += 1
            self.injected["skipped_frames"] += 1
            return
        if len(self._pending) + self.frame_wire_bytes > self.tx_buffer_bytes:
            self._frames_dropped += 1
            self._tx_overflows += 1
            return
        rows = self._frame_rows(index)
        missing: frozenset = frozenset()
        if self._tear_next > 0:
            self._tear_next -= 1
            chosen = self._tear_rows.pop(0)
            if chosen is None:
                k = max(1, self.rows // 8)
                chosen = self._fault_rng.sample(range(self.rows), min(k, self.rows))
            missing = frozenset(r for r in chosen if 0 <= r < self.rows)
            self.injected["torn_frames"] += 1
        duplicate = self._dup_next > 0
        if duplicate:
            self._dup_next -= 1
        crc = codec.frame_crc32(self._u16le(r) for r in rows)
        self._frame = _Frame(index, seq, t, rows, crc, missing, duplicate)

    def _frame_rows(self, index: int) -> list[list[int]]:
        data = self._frames(index)
        rows = []
        for r, row in enumerate(data):
            vals = row.tolist() if hasattr(row, "tolist") else list(row)
            if len(vals) != self.cols:
                raise ValueError(f"frames({index}) row {r} has {len(vals)} samples; the board has {self.cols} columns")
            if vals and not isinstance(vals[0], int):
                vals = [int(v) for v in vals]
            if vals and (min(vals) < 0 or max(vals) > self._full_scale):
                fs = self._full_scale
                vals = [0 if v < 0 else fs if v > fs else v for v in vals]
            rows.append(vals)
        if len(rows) != self.rows:
            raise ValueError(f"frames({index}) gave {len(rows)} rows; the board has {self.rows} rows of {self.cols}")
        return rows

    @staticmethod
    def _u16le(vals: list[int]) -> bytes:
        a = array("H", vals)
        if sys.byteorder == "big":
            a.byteswap()
        return a.tobytes()

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
        if self.definition_hash == codec.DEFINITION_HASH or pkt.DEF.seed == "fixed":
            wire = codec.encode(pkt)
        else:  # a board built from another definition: its CRC seed differs
            body = codec.pack(pkt)[:-2]
            crc = binascii.crc_hqx(body, self.definition_hash)
            wire = cobs.encode(body + crc.to_bytes(2, "little")) + b"\x00"
        self._pending += wire
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
            self._send(self.info_packet())
        elif name == "START":
            self._start_streaming(now)
            ack()
        elif name == "STOP":
            self._streaming = False  # a frame in progress is finished
            self._next_status_t = None
            ack()
        elif name == "SET_RATE":
            if not self._rate_ok(pkt.rate_mhz):
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
            self._send(self.status_packet())
        else:  # a host→device packet this firmware does not implement
            nak("unknown_command")

    # ------------------------------------------------------------------ internals: link faults and data

    def _apply_link_faults(self, data: bytes) -> bytes:
        out = bytearray()
        pos = 0
        ops = self._link_ops
        while ops:
            kind, arg = ops[0]
            if kind == "garbage":
                out += arg
                self.injected["garbage_bytes"] += len(arg)
                ops.popleft()
                continue
            if pos >= len(data):
                break
            k = min(arg, len(data) - pos)
            if kind == "drop":
                self.injected["dropped_bytes"] += k
            else:
                for b in data[pos : pos + k]:
                    out.append(b ^ (1 << self._fault_rng.randrange(8)))
                self.injected["flipped_bits"] += k
            pos += k
            if k < arg:
                ops[0] = (kind, arg - k)
                break
            ops.popleft()
        out += data[pos:]
        return bytes(out)

    def _default_frames(self, index: int) -> list[list[int]]:
        """Mid-scale with ±3 counts of seeded noise: an unloaded carpet."""
        rng = random.Random(self.seed * 1_000_003 + index)
        mid = 1 << (self.adc_bits - 1)
        return [[mid + b % 7 - 3 for b in rng.randbytes(self.cols)] for _ in range(self.rows)]

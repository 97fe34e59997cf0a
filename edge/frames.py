"""Frame assembly: ROW packets → whole frames of raw counts, checked and counted.

Policy for a frame that is not whole (documented in README and SPEC.md):

- every row present, FRAME_END seen, CRC-32 matches → the frame is emitted;
- CRC-32 mismatch → dropped (``crc_mismatch``): some sample is wrong, we cannot say which;
- no FRAME_END (the next frame began first) → dropped (``missing_frame_end``), whole or
  not: without it nothing says the rows belong together (rows of two frames could mix);
- rows missing but FRAME_END seen (a torn frame) →
  ``missing_rows="drop"`` (default) drops it (``torn_dropped``);
  ``missing_rows="flag"`` emits it when at most ``max_missing_rows`` are missing,
  with those rows copied from the last good frame and marked in ``RawFrame.stale``
  (``torn_flagged``); with no earlier frame it is dropped.
- a frame_seq equal to the last emitted one is a duplicate (``duplicate_frames``);
  a forward gap adds to ``missed_frames``; a backward jump means the device restarted
  (``seq_restarts``) and the frame is accepted.

Device time ``t_us`` (u32) is unwrapped across 2^32 µs into ``RawFrame.t_s`` (seconds
since the first frame of this source); intervals outside (0, 10 nominal periods] count
as ``time_jumps``. ``t_s`` always increases: where the device clock cannot say how much
time passed (the device restarted, its clock stood still, or it stepped back, i.e. an
interval over 2^31 µs that the host clock did not see pass), ``t_s`` advances by the
nominal period per frame and a ``time_jumps`` is counted.
"""

from __future__ import annotations

import time
import zlib
from collections import Counter
from dataclasses import dataclass
from typing import Any, Callable

import numpy as np

from edge.wiring import WiringMap
from firmware_protocol import codec

U32 = 1 << 32


@dataclass(frozen=True, slots=True)
class RawFrame:
    """One assembled frame.

    counts: (H, W) uint16, carpet orientation (wiring map applied).
    frame_seq: the device's frame counter (wraps at 2^32).
    index: host-side frame number since the source opened, unwrapped, gaps included.
    t_s: device time of the frame's last row, unwrapped, seconds since the first frame.
    host_time_s: host wall clock (time.time()) when the frame completed.
    stale: (H, W) bool of sensels copied from an earlier frame, or None when all are fresh.
    """

    counts: np.ndarray
    frame_seq: int
    index: int
    t_s: float
    host_time_s: float
    stale: np.ndarray | None = None


def unpack_rows(payloads: list[bytes], packing: int, count: int) -> np.ndarray:
    """Samples of equally long rows → (rows, count) uint16, vectorised."""
    buf = np.frombuffer(b"".join(payloads), dtype=np.uint8).reshape(len(payloads), -1)
    if packing == codec.PACKING["u8"]:
        return buf.astype(np.uint16)
    if packing == codec.PACKING["u16"]:
        return buf.view("<u2").astype(np.uint16)
    if packing == codec.PACKING["packed12"]:
        n_pairs = (count + 1) // 2
        if buf.shape[1] % 3:  # odd count: pad the last pair's missing byte
            buf = np.concatenate([buf, np.zeros((buf.shape[0], 1), np.uint8)], axis=1)
        trip = buf.reshape(len(payloads), n_pairs, 3).astype(np.uint16)
        out = np.empty((len(payloads), 2 * n_pairs), np.uint16)
        out[:, 0::2] = trip[..., 0] | ((trip[..., 1] & 0x0F) << 8)
        out[:, 1::2] = (trip[..., 1] >> 4) | (trip[..., 2] << 4)
        return out[:, :count]
    raise ValueError(f"unknown packing code {packing}")


class FrameAssembler:
    """Feed decoded packets with :meth:`push`; it returns the frames they complete."""

    def __init__(
        self,
        info: Any,
        wiring: WiringMap | None = None,
        missing_rows: str = "drop",
        max_missing_rows: int = 4,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        if missing_rows not in ("drop", "flag"):
            raise ValueError("missing_rows must be 'drop' or 'flag'")
        self.rows, self.cols = int(info.rows), int(info.cols)
        self.wiring = wiring or WiringMap.identity(self.rows, self.cols)
        if (self.wiring.wire_rows, self.wiring.wire_cols) != (self.rows, self.cols):
            raise ValueError(
                f"wiring map is for a {self.wiring.wire_rows}×{self.wiring.wire_cols} wire grid, "
                f"the device sends {self.rows}×{self.cols}"
            )
        self.period_us = 1e9 / info.rate_mhz if info.rate_mhz else 0.0
        self.missing_rows = missing_rows
        self.max_missing_rows = max_missing_rows
        self.counters: Counter = Counter()
        self._cur_seq: int | None = None
        self._rows: dict[int, bytes] = {}
        self._packing: int | None = None
        self._last_row_t_us = 0
        self._last_wire: np.ndarray | None = None
        self._last_seq: int | None = None
        self._index = -1
        self._t0_us: int | None = None
        self._t_total_us = 0
        self._t_last_us: int | None = None
        self._clock = clock  # host seconds: tells a long pause from a device clock that stepped back
        self._host_last_s: float | None = None

    def reset(self) -> None:
        """Forget the frame in progress (after a reconnect); keeps counters and continuity."""
        if self._rows:
            self.counters["torn_dropped"] += 1
        self._cur_seq, self._rows, self._packing = None, {}, None

    def push(self, pkt: Any) -> list[RawFrame]:
        if isinstance(pkt, codec.Row):
            return self._on_row(pkt)
        if isinstance(pkt, codec.FrameEnd):
            return self._on_end(pkt)
        return []

    # -- rows and frame ends

    def _on_row(self, row: Any) -> list[RawFrame]:
        out: list[RawFrame] = []
        if self._cur_seq is not None and row.frame_seq != self._cur_seq:
            out += self._finish(expected_crc=None, end_t_us=self._last_row_t_us)  # FRAME_END never came
        if row.row >= self.rows or row.count != self.cols:
            self.counters["bad_rows"] += 1
            return out
        if self._packing is not None and row.packing != self._packing:
            self.counters["bad_rows"] += 1
            return out
        self._cur_seq, self._packing = row.frame_seq, row.packing
        if row.row in self._rows:
            self.counters["repeated_rows"] += 1
        self._rows[row.row] = row.samples
        self._last_row_t_us = row.t_us
        return out

    def _on_end(self, end: Any) -> list[RawFrame]:
        if self._cur_seq is None or end.frame_seq != self._cur_seq:
            if self._cur_seq is not None:
                out = self._finish(expected_crc=None, end_t_us=self._last_row_t_us)
            else:
                out = []
            self.counters["orphan_frame_ends"] += 1
            return out
        return self._finish(expected_crc=end.frame_crc32, end_t_us=end.t_us)

    def _finish(self, expected_crc: int | None, end_t_us: int) -> list[RawFrame]:
        seq, rows, packing = self._cur_seq, self._rows, self._packing
        self._cur_seq, self._rows, self._packing = None, {}, None
        assert seq is not None and packing is not None  # called only inside a frame (its first ROW set both)
        if expected_crc is None:  # never emitted unchecked
            self.counters["missing_frame_end"] += 1
            return []
        missing = [r for r in range(self.rows) if r not in rows]
        stale = None
        if missing:
            if self.missing_rows == "drop" or len(missing) > self.max_missing_rows or self._last_wire is None:
                self.counters["torn_dropped"] += 1
                return []
            present = [r for r in range(self.rows) if r in rows]
            wire = self._last_wire.copy()
            wire[present] = unpack_rows([rows[r] for r in present], packing, self.cols)
            stale_wire = np.zeros((self.rows, self.cols), bool)
            stale_wire[missing] = True
            stale = self.wiring.apply(stale_wire)
            self.counters["torn_flagged"] += 1
        else:
            wire = unpack_rows([rows[r] for r in range(self.rows)], packing, self.cols)
            if zlib.crc32(wire.astype("<u2").tobytes()) != expected_crc:
                self.counters["crc_mismatch"] += 1
                return []
        if not self._continuity(seq, end_t_us):
            return []
        if stale is None:
            self._last_wire = wire
        self.counters["frames"] += 1
        t_s = self._t_total_us * 1e-6
        return [RawFrame(self.wiring.apply(wire), seq, self._index, t_s, time.time(), stale)]

    def _continuity(self, seq: int, t_us: int) -> bool:
        last, step, restarted = self._last_seq, 1, False
        if last is not None:
            step = (seq - last) % U32
            if step == 0:
                self.counters["duplicate_frames"] += 1
                return False
            if step >= U32 // 2:
                self.counters["seq_restarts"] += 1
                step, restarted = 1, True
            self.counters["missed_frames"] += step - 1
            self._index += step
        else:
            self._index = 0
        self._last_seq = seq
        host_s = self._clock()
        if self._t_last_us is not None and self._host_last_s is not None:  # set together
            dt = (t_us - self._t_last_us) % U32
            # A restarted device restarted its clock too, and "more than half a wrap forward" is
            # a clock that stepped back unless the host saw that long pass: taken at face value
            # either added up to 71.6 bogus minutes. Then t_s moves on by the nominal period.
            back = dt >= U32 // 2 and host_s - self._host_last_s < 0.5 * dt * 1e-6
            if restarted or back or dt == 0:
                self.counters["time_jumps"] += 1
                dt = max(int(round(self.period_us * step)), 1)
            elif self.period_us and not dt <= 10 * self.period_us * max(1, step):
                self.counters["time_jumps"] += 1
            self._t_total_us += dt
        self._t_last_us = t_us
        self._host_last_s = host_s
        return True

"""Wrap-arounds on the wire and in frame assembly: packet seq (u16), frame_seq (u32), the device's
microsecond clock t_us (u32, protocol.toml: wraps every 2^32 µs ≈ 71.6 min), a run longer than
that, drops across the wraps, a device that restarts, and a device clock that steps back.

Documented behaviour (docs/stability.md): host time ``RawFrame.t_s`` is the unwrapped device
time, strictly increasing; drops across a wrap count exactly; where device time cannot be
believed (restart, step back, standing still) t_s moves on by the nominal period and
``time_jumps`` counts it.
"""

from __future__ import annotations

import zlib

import numpy as np
import pytest

from edge.frames import FrameAssembler
from firmware_protocol import codec
from firmware_protocol.spec import load as load_spec
from firmware_protocol.virtual_board import VirtualBoard

U32 = 2**32
ROWS = COLS = 4
PERIOD_US = 2_000_000  # 0.5 Hz: a run past 2^32 µs in ~2200 frames


def test_the_widths_come_from_the_protocol_definition():
    spec = load_spec()
    header = {f.name: f.type for f in spec.header}
    row = {f.name: f.type for f in spec.by_name("ROW").fields}
    assert header["seq"] == "u16" and row["frame_seq"] == "u32" and row["t_us"] == "u32"


def run_board(board: VirtualBoard, until_s: float, dec: codec.StreamDecoder, asm: FrameAssembler | None = None,
              start_s: float = 0.0, step_s: float = 100.0):
    """Read the board from ``start_s`` to ``until_s``; returns (INFO packets, frames assembled)."""
    infos, frames, t = [], [], start_s
    while t < until_s:
        t = min(t + step_s, until_s)
        for pkt in dec.feed(board.read(t)):
            if isinstance(pkt, codec.Info):
                infos.append(pkt)
            elif asm is not None:
                frames += asm.push(pkt)
    return infos, frames


def started_board(**kw):
    board = VirtualBoard(rows=ROWS, cols=COLS, rate_hz=1e6 / PERIOD_US, status_interval_s=10.0, **kw)
    dec = codec.StreamDecoder()
    (info,) = dec.feed(board.read(0.0))  # INFO at power-up
    board.receive(codec.encode_command("START", 1), now_s=0.0)
    return board, dec, FrameAssembler(info)


def test_a_run_longer_than_2_to_the_32_microseconds_keeps_exact_monotonic_time():
    # every counter starts just short of its wrap: t_us wraps at 5 s and again at ~4300 s
    board, dec, asm = started_board(t_us_start=U32 - 5_000_000, frame_seq_start=U32 - 3, seq_start=65536 - 7)
    _, frames = run_board(board, 4400.0, dec, asm)
    assert len(frames) == 2200
    t = np.array([f.t_s for f in frames])
    assert t[-1] > U32 * 1e-6  # longer than one wrap of the device clock
    np.testing.assert_allclose(np.diff(t), PERIOD_US * 1e-6, atol=1e-9)  # exact, across both wraps
    assert [f.index for f in frames] == list(range(2200))
    assert [f.frame_seq for f in frames[:5]] == [U32 - 3, U32 - 2, U32 - 1, 0, 1]
    assert asm.counters["missed_frames"] == 0 and asm.counters["time_jumps"] == 0
    assert dec.stats.missed == 0 and dec.stats.repeated == 0 and not dec.stats.dropped


def test_frames_dropped_across_the_wraps_are_counted_exactly():
    # frame 0 at 0 s is 2^32−3; t_us wraps between the frames at 6 s and 8 s
    board, dec, asm = started_board(t_us_start=U32 - 7_000_000, frame_seq_start=U32 - 3, seq_start=65536 - 3)
    _, frames = run_board(board, 1.0, dec, asm, step_s=1.0)
    board.skip_frames(3)  # 2^32−2, 2^32−1 and 0 are scanned, never sent
    _, more = run_board(board, 20.0, dec, asm, start_s=1.0, step_s=1.0)
    frames += more
    assert [f.frame_seq for f in frames[:3]] == [U32 - 3, 1, 2]
    assert asm.counters["missed_frames"] == 3 and asm.counters["time_jumps"] == 0
    assert [f.index for f in frames] == [0] + list(range(4, 4 + len(frames) - 1))
    t = np.array([f.t_s for f in frames])
    np.testing.assert_allclose(np.diff(t), [8.0] + [2.0] * (len(t) - 2), atol=1e-9)  # through the t_us wrap
    assert dec.stats.missed == 0  # skipped frames never used packet seqs


def test_packet_seq_gaps_across_the_u16_wrap_are_counted_exactly():
    dec = codec.StreamDecoder()
    for seq in (65533, 65534, 2, 3):  # 65535, 0 and 1 lost across the wrap
        dec.feed(codec.encode(codec.Ack(seq, 0x86, 0, 0)))
    assert dec.stats.missed == 3 and dec.stats.repeated == 0
    for seq in (65000, 65001):  # 540 back (a late packet, a restart): not a gap of 64 996
        dec.feed(codec.encode(codec.Ack(seq, 0x86, 0, 0)))
    assert dec.stats.missed == 3 and dec.stats.packets == 6


def test_a_device_restart_after_the_wrap_does_not_add_71_minutes():
    board, dec, asm = started_board(t_us_start=U32 - 5_000_000)
    _, frames = run_board(board, 100.0, dec, asm, step_s=10.0)
    last = frames[-1]
    board.unplug(now_s=100.0)
    board.replug(now_s=101.0)  # bus powered: boots again, frame_seq and t_us restart from their start values
    infos, _ = run_board(board, 101.0, dec, asm, start_s=100.0, step_s=1.0)
    assert infos
    asm.reset()  # what the carpet source does on a new INFO
    board.receive(codec.encode_command("START", 2), now_s=101.0)
    _, after = run_board(board, 111.0, dec, asm, start_s=101.0, step_s=1.0)
    assert after and asm.counters["seq_restarts"] == 1
    assert after[0].t_s == pytest.approx(last.t_s + PERIOD_US * 1e-6)  # one nominal period, not 2^32 µs
    assert after[0].index == last.index + 1 and asm.counters["missed_frames"] == 0
    np.testing.assert_allclose(np.diff([f.t_s for f in after]), PERIOD_US * 1e-6, atol=1e-9)


def frame_packets(seq: int, t_us: int) -> list:
    counts = np.full((ROWS, COLS), 100, np.uint16)
    rows = [codec.make_row(r, seq, t_us % U32, r, counts[r].tolist(), codec.PACKING["u16"]) for r in range(ROWS)]
    return rows + [codec.FrameEnd(ROWS, seq, t_us % U32, ROWS, 0, zlib.crc32(counts.astype("<u2").tobytes()))]


def info_packet():
    return codec.Info(0, codec.PROTOCOL_VERSION, codec.DEFINITION_HASH, 1, 0, 0, "wrap-test", ROWS, COLS, 1, 1, 12,
                      codec.PACKING["u16"], -1, int(1e9 / PERIOD_US), 0)


def push(asm: FrameAssembler, seq: int, t_us: int):
    out = []
    for p in frame_packets(seq, t_us):
        out += asm.push(p)
    (frame,) = out
    return frame


def test_a_device_clock_that_steps_back_or_stands_still_keeps_host_time_increasing():
    asm = FrameAssembler(info_packet(), clock=lambda: 0.0)  # the host sees no time pass
    t0 = U32 - 1_000_000
    times = [push(asm, s, t).t_s for s, t in ((10, t0), (11, t0 + PERIOD_US), (12, t0 + PERIOD_US - 500_000),
                                              (13, t0 + PERIOD_US - 500_000), (14, t0 + PERIOD_US + 1_500_000))]
    assert all(b > a for a, b in zip(times, times[1:]))
    np.testing.assert_allclose(np.diff(times), [2.0, 2.0, 2.0, 2.0])  # a step back and a stall: one period each
    assert asm.counters["time_jumps"] == 2 and asm.counters["missed_frames"] == 0


def test_a_pause_longer_than_half_a_wrap_is_believed_when_the_host_saw_it():
    pause_us = 40 * 60 * 1_000_000  # 40 min > 2^31 µs: alone, it reads like a clock stepping back
    host = iter([0.0, 2400.0])
    asm = FrameAssembler(info_packet(), clock=lambda: next(host))
    a = push(asm, 7, U32 - 1_000_000)
    b = push(asm, 8, U32 - 1_000_000 + pause_us)
    assert b.t_s - a.t_s == pytest.approx(pause_us * 1e-6)
    assert asm.counters["time_jumps"] == 1  # longer than 10 periods: counted, and kept

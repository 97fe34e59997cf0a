"""The virtual readout board as a state machine: commands, frames, rates, wrap-arounds (faults: test_virtual_board_faults.py)."""

from __future__ import annotations

import binascii

import numpy as np
import pytest
from virtual_board_helpers import (
    COLS,
    ROWS,
    check_frames_true,
    cmd,
    crc_of,
    frames_of,
    ramp_frames,
    small_board,
    started,
)

from firmware_protocol import cobs, codec
from firmware_protocol.virtual_board import VirtualBoard


def test_power_up_sends_info_once_with_the_configured_fields():
    board = VirtualBoard(rows=96, cols=96, adc_bits=12, packing="packed12", sign=-1, device_id="carpet-07",
                         fw_version=(2, 3, 4), has_temperature=True, has_gain=False)
    dec = codec.StreamDecoder()
    (info,) = dec.feed(board.read(10.0))
    assert isinstance(info, codec.Info)
    codec.check_compatible(info)
    assert (info.rows, info.cols, info.tile_rows, info.tile_cols) == (96, 96, 3, 3)
    assert (info.adc_bits, info.packing, info.sign, info.rate_mhz) == (12, codec.PACKING["packed12"], -1, 14000)
    assert (info.fw_major, info.fw_minor, info.fw_patch, info.device_id) == (2, 3, 4, "carpet-07")
    assert info.flags == 0b001  # temperature, not streaming, no gain
    assert board.read(20.0) == b""  # once, not again


def test_get_info_start_stop_are_answered():
    board = small_board()
    dec = codec.StreamDecoder()
    dec.feed(board.read(0.0))
    board.receive(cmd("GET_INFO", 5), now_s=0.0)
    (info,) = dec.feed(board.read(0.0))
    assert isinstance(info, codec.Info) and info.flags & 2 == 0
    board.receive(cmd("START", 6) + cmd("GET_INFO", 7), now_s=0.0)
    pkts = dec.feed(board.read(0.0))
    ack, info = pkts[:2]
    assert isinstance(ack, codec.Ack) and (ack.cmd_type, ack.cmd_seq, ack.value) == (0x82, 6, 0)
    assert info.flags & 2  # streaming now
    board.receive(cmd("STOP", 8), now_s=0.5)
    later = dec.feed(board.read(3.0))
    pkts += later
    acks = [p for p in later if isinstance(p, codec.Ack)]
    assert [(a.cmd_type, a.cmd_seq) for a in acks] == [(0x83, 8)]
    # the frame being scanned at STOP is finished, and nothing starts after it
    ends = [p for p in pkts if isinstance(p, codec.FrameEnd)]
    assert ends[-1].frame_seq == board.frames_scanned - 1
    assert all(len(rows) == ROWS for rows, _ in frames_of(pkts).values())
    assert board.read(10.0) == b""
    assert dec.stats.missed == 0 and not dec.stats.dropped


def test_commands_in_any_chunking():
    board = small_board()
    board.read(0.0)
    data = cmd("PING", 1, token=0xDEADBEEF) + cmd("SET_GAIN", 2, gain_step=9) + cmd("GET_INFO", 3)
    for i in range(len(data)):
        board.receive(data[i : i + 1], now_s=0.0)
    pkts = codec.StreamDecoder().feed(board.read(0.0))
    names = [p.NAME for p in pkts]
    assert names == ["ACK", "STATUS", "ACK", "INFO"]
    assert pkts[0].value == 0xDEADBEEF and pkts[2].value == 9
    assert board.gain_step == 9


def test_ping_answers_ack_with_token_then_status():
    board = small_board(has_temperature=True, temperature_c=31.5)
    board.read(0.0)
    board.receive(cmd("PING", 42, token=1234), now_s=2.5)
    ack, status = codec.StreamDecoder().feed(board.read(2.5))
    assert (ack.cmd_type, ack.cmd_seq, ack.value) == (0x86, 42, 1234)
    assert isinstance(status, codec.Status)
    assert status.temperature_cdeg == 3150 and status.uptime_s == 2 and status.t_us == 2_500_000
    assert status.gain_step == 64


def test_set_rate_applies_or_is_refused():
    board = small_board()
    dec = started(board)
    board.receive(cmd("SET_RATE", 2, rate_mhz=20000), now_s=0.0)
    board.receive(cmd("SET_RATE", 3, rate_mhz=100), now_s=0.0)  # 0.1 Hz: below 0.5 Hz
    board.receive(cmd("SET_RATE", 4, rate_mhz=1_000_000), now_s=0.0)  # 1 kHz: above 100 Hz
    pkts = dec.feed(board.read(1.0))
    acks = [(p.cmd_seq, p.value) for p in pkts if isinstance(p, codec.Ack)]
    naks = [(p.cmd_seq, p.reason) for p in pkts if isinstance(p, codec.Nak)]
    assert acks == [(1, 0), (2, 20000)]
    assert naks == [(3, codec.NAK_REASON["out_of_range"]), (4, codec.NAK_REASON["out_of_range"])]
    starts = [p.t_us for p in pkts if isinstance(p, codec.Row) and p.row == 0]
    assert np.diff(starts).tolist() == [50_000] * (len(starts) - 1)
    assert board.rate_hz == 20.0


def test_set_rate_beyond_the_scan_or_the_link_is_refused():
    slow_scan = small_board(rows=96, cols=4, row_time_us=1000.0, rate_hz=5, frames=None)  # 96 ms per scan
    assert slow_scan.max_rate_hz == pytest.approx(1 / 0.096)
    frame_bytes = VirtualBoard(rows=96, cols=96).frame_wire_bytes  # ~15.8 kB on the wire
    thin_link = VirtualBoard(rows=96, cols=96, rate_hz=10, link_bytes_per_s=13.5 * frame_bytes)
    for board, ok, refused in ((slow_scan, 10_000, 11_000), (thin_link, 13_500, 13_600)):
        board.read(0.0)
        board.receive(cmd("SET_RATE", 1, rate_mhz=ok) + cmd("SET_RATE", 2, rate_mhz=refused), now_s=0.0)
        a, n = codec.StreamDecoder().feed(board.read(0.0))
        assert isinstance(a, codec.Ack) and a.value == ok
        assert isinstance(n, codec.Nak) and n.reason == codec.NAK_REASON["out_of_range"]
    with pytest.raises(ValueError, match="outside"):
        VirtualBoard(rows=96, cols=96, link_bytes_per_s=13.5 * frame_bytes)  # 14 Hz does not fit


def test_set_gain_without_gain_control_is_unsupported():
    board = small_board(has_gain=False)
    board.read(0.0)
    board.receive(cmd("SET_GAIN", 3, gain_step=5) + cmd("PING", 4, token=0), now_s=0.0)
    nak, _, status = codec.StreamDecoder().feed(board.read(0.0))
    assert (nak.cmd_type, nak.cmd_seq, nak.reason) == (0x85, 3, codec.NAK_REASON["unsupported"])
    assert status.gain_step == 0xFFFF and status.temperature_cdeg == 2400  # 24.0 °C, the default
    board = small_board(gain_steps=128)
    board.read(0.0)
    board.receive(cmd("SET_GAIN", 1, gain_step=128), now_s=0.0)
    (nak,) = codec.StreamDecoder().feed(board.read(0.0))
    assert nak.reason == codec.NAK_REASON["out_of_range"]


def _raw_command(ptype: int, seq: int, payload: bytes, seed: int = codec.DEFINITION_HASH) -> bytes:
    body = bytes((ptype,)) + seq.to_bytes(2, "little") + payload
    return cobs.encode(body + binascii.crc_hqx(body, seed).to_bytes(2, "little")) + b"\x00"


def test_unknown_and_malformed_commands_are_nakked_and_counted():
    board = small_board()
    board.read(0.0)
    board.receive(_raw_command(0x9A, 11, b"xy"), now_s=0.0)  # no such command
    board.receive(codec.encode(codec.Ack(12, 0x82, 1, 0)), now_s=0.0)  # a device→host packet
    board.receive(_raw_command(0x84, 13, b"\x01\x02"), now_s=0.0)  # SET_RATE with 2 bytes, not 4
    bad_crc = _raw_command(0x82, 14, b"", seed=codec.DEFINITION_HASH ^ 0x0100)  # START, wrong CRC
    board.receive(bad_crc + b"\x07\x99garbage\x00" + cmd("PING", 15, token=7), now_s=0.0)
    pkts = codec.StreamDecoder().feed(board.read(0.0))
    naks = [(p.cmd_type, p.cmd_seq, p.reason) for p in pkts if isinstance(p, codec.Nak)]
    assert naks == [
        (0x9A, 11, codec.NAK_REASON["unknown_command"]),
        (0x05, 12, codec.NAK_REASON["unknown_command"]),
        (0x84, 13, codec.NAK_REASON["bad_length"]),
    ]
    status = pkts[-1]
    assert isinstance(status, codec.Status)
    assert status.rx_bad_crc == 1
    assert status.rx_bad_framing > 0  # the unknown, the wrong-direction, the short and the garbage bytes
    assert not board.streaming  # the START with a bad CRC was not obeyed


# ---------------------------------------------------------------- frames


def test_frames_decode_to_the_source_with_matching_crc32_and_timing():
    source = ramp_frames()
    board = small_board(row_time_us=250.0)
    dec = started(board)
    pkts = dec.feed(board.read(1.0))
    frames = frames_of(pkts)
    assert len(frames) == 15  # frames start at 0, 1/14, ..., 14/14 s; the last is complete at 1.00175 s
    complete = {k: v for k, v in frames.items() if v[1] is not None}
    assert len(complete) == 14
    for fseq, (rows, end) in complete.items():
        assert sorted(rows) == list(range(ROWS))
        assert [rows[r] for r in range(ROWS)] == source(fseq)
        assert end.frame_crc32 == crc_of(rows)
        assert end.rows == ROWS and end.scan_time_us == (ROWS - 1) * 250
    row_t = [p.t_us for p in pkts if isinstance(p, codec.Row) and p.frame_seq == 3]
    assert row_t == [round(3 * 1e6 / 14) + r * 250 for r in range(ROWS)]
    assert [p for p in pkts if isinstance(p, codec.Status)][0].t_us == 1_000_000
    assert dec.stats.missed == 0 and not dec.stats.dropped


@pytest.mark.parametrize(
    "bits,packing,cols",
    [(8, "u8", 7), (10, "packed12", 5), (12, "packed12", 6), (12, "u16", 3), (16, "u16", 4)],
)
def test_every_packing_round_trips(bits, packing, cols):
    source = ramp_frames(ROWS, cols, bits)
    board = VirtualBoard(rows=ROWS, cols=cols, adc_bits=bits, packing=packing, frames=source)
    dec = started(board)
    pkts = dec.feed(board.read(0.3))
    info = board.info_packet()
    assert info.adc_bits == bits and info.packing == codec.PACKING[packing]
    frames = frames_of(pkts)
    assert len(frames) >= 4
    check_frames_true(frames, source)


def test_numpy_frames_are_accepted_and_clamped_to_the_adc_range():
    def frames(k):
        f = np.full((ROWS, COLS), 2048.0)
        f[0, 0], f[1, 1] = -5.0, 9999.0
        return f

    board = small_board(frames=frames)
    dec = started(board)
    rows, end = frames_of(dec.feed(board.read(0.05)))[0]
    assert rows[0][0] == 0 and rows[1][1] == 4095 and rows[2][2] == 2048
    assert end.frame_crc32 == crc_of(rows)


def test_a_frame_of_the_wrong_shape_is_a_clear_error():
    board = small_board(frames=lambda k: [[0] * COLS] * (ROWS - 1))
    started(board)
    with pytest.raises(ValueError, match="rows"):
        board.read(0.01)


def test_default_frames_sit_near_mid_scale_and_are_deterministic():
    a, b = VirtualBoard(rows=32, cols=32, seed=3), VirtualBoard(rows=32, cols=32, seed=3)
    for board in (a, b):
        started(board)
    out_a, out_b = a.read(0.5), b.read(0.5)
    assert out_a == out_b
    rows, _ = frames_of(codec.StreamDecoder().feed(out_a))[2]
    vals = np.array([rows[r] for r in range(32)])
    assert abs(vals.mean() - 2048) < 1 and vals.min() >= 2045 and vals.max() <= 2051


def test_sequence_numbers_and_clock_cross_their_wraps_cleanly():
    source = ramp_frames()
    board = small_board(t_us_start=2**32 - 150_000, frame_seq_start=2**32 - 2, seq_start=65536 - 20)
    dec = started(board)
    pkts = dec.feed(board.read(0.5))
    ends = [p for p in pkts if isinstance(p, codec.FrameEnd)]
    assert [e.frame_seq for e in ends[:4]] == [2**32 - 2, 2**32 - 1, 0, 1]
    seqs = [p.seq for p in pkts]
    assert 65535 in seqs and 0 in seqs
    assert all((b - a) & 0xFFFF == 1 for a, b in zip(seqs, seqs[1:]))
    row0_t = [p.t_us for p in pkts if isinstance(p, codec.Row) and p.row == 0]
    assert row0_t[0] == 2**32 - 150_000 and row0_t[-1] < 400_000  # the clock wrapped
    assert {(b - a) & 0xFFFFFFFF for a, b in zip(row0_t, row0_t[1:])} <= {71428, 71429}
    assert dec.stats.missed == 0 and dec.stats.repeated == 0 and not dec.stats.dropped
    check_frames_true(frames_of(pkts), source, frame_seq_start=2**32 - 2)


def test_status_about_once_a_second_while_streaming_only():
    board = small_board()
    dec = started(board)
    pkts = dec.feed(board.read(3.5))
    status = [p for p in pkts if isinstance(p, codec.Status)]
    assert [s.t_us for s in status] == [1_000_000, 2_000_000, 3_000_000]
    assert status[-1].frames_scanned == 42 and status[-1].uptime_s == 3
    board.receive(cmd("STOP", 2), now_s=3.5)
    assert not [p for p in dec.feed(board.read(10.0)) if isinstance(p, codec.Status)]


def test_injected_clock_and_next_due():
    t = [100.0]
    board = small_board(clock=lambda: t[0])
    assert codec.StreamDecoder().feed(board.read())[0].NAME == "INFO"
    assert board.next_due_s() is None  # idle
    board.receive(cmd("START", 1))
    assert board.next_due_s() == 100.0  # the ACK and row 0 are due now
    board.read()
    assert board.next_due_s() == pytest.approx(100.0 + 100e-6)  # row 1

"""The virtual readout board's injected faults: lost bytes, flipped bits, garbage, stalls, torn, skipped and
duplicated frames, unplugs, and configurations it refuses."""

from __future__ import annotations

import pytest
from virtual_board_helpers import (
    ROWS,
    check_frames_true,
    cmd,
    crc_of,
    frames_of,
    ramp_frames,
    small_board,
    started,
)

from firmware_protocol import codec
from firmware_protocol.virtual_board import VirtualBoard


def test_a_host_that_stops_reading_loses_whole_frames_not_bytes():
    board = small_board(tx_buffer_bytes=2000)  # ~4 frames of 8x6
    dec = started(board)
    pkts = dec.feed(board.read(5.0))
    frames = frames_of(pkts)
    assert all(len(rows) == ROWS for rows, _ in frames.values())
    assert 0 < len(frames) < 70 and board.frames_dropped == board.frames_scanned - len(frames)
    assert dec.stats.missed == 0 and not dec.stats.dropped
    board.receive(cmd("PING", 2, token=0), now_s=5.0)
    status = dec.feed(board.read(5.0))[-1]
    assert status.frames_dropped == board.frames_dropped and status.tx_overflows > 0


# ---------------------------------------------------------------- faults


def test_drop_bytes_costs_the_packets_they_hit():
    source = ramp_frames()
    board = small_board()
    dec = started(board)
    dec.feed(board.read(0.1))
    board.drop_bytes(30)
    pkts = dec.feed(board.read(0.5))
    assert board.injected["dropped_bytes"] == 30
    assert 1 <= dec.stats.missed <= 2
    assert sum(dec.stats.dropped.values()) == 1  # the damaged remainder of one packet
    check_frames_true(frames_of(pkts), source)


def test_flip_bits_are_caught_by_the_crcs():
    source = ramp_frames()
    board = small_board()
    dec = started(board)
    dec.feed(board.read(0.1))
    for i in range(20):
        board.flip_bits(3)
        pkts = dec.feed(board.read(0.1 + 0.05 * (i + 1)))
        check_frames_true(frames_of(pkts), source)  # no false accepts
    assert board.injected["flipped_bits"] == 60
    # each burst of 3 damages one packet (two when a read had no bytes and bursts queued up)
    assert sum(dec.stats.dropped.values()) >= 10 and dec.stats.missed >= 10


@pytest.mark.parametrize("zeros", [True, False])
def test_garbage_bursts_are_dropped_and_the_stream_resynchronises(zeros):
    source = ramp_frames()
    board = small_board(seed=5)
    dec = started(board)
    dec.feed(board.read(0.1))
    junk = board.garbage(300, zeros=zeros)
    assert len(junk) == 300 and (zeros or 0 not in junk)
    pkts = dec.feed(board.read(0.5))
    assert board.injected["garbage_bytes"] == 300
    assert sum(dec.stats.dropped.values()) >= 1
    assert dec.stats.missed <= 1  # at most the packet the burst's tail ran into
    assert len(frames_of(pkts)) >= 5
    check_frames_true(frames_of(pkts), source)


def test_stall_holds_the_output_then_bursts():
    board = small_board()
    dec = started(board)
    dec.feed(board.read(0.1))
    board.stall(0.5, now_s=0.1)
    assert board.read(0.3) == b"" and board.read(0.59) == b""
    assert board.next_due_s() == pytest.approx(0.6)
    pkts = dec.feed(board.read(0.61))
    assert len([p for p in pkts if isinstance(p, codec.FrameEnd)]) >= 6
    assert dec.stats.missed == 0 and board.injected["stalls"] == 1


def test_torn_frame_loses_rows_but_keeps_its_frame_end():
    source = ramp_frames()
    board = small_board()
    dec = started(board)
    dec.feed(board.read(0.1))
    board.tear_next_frame(missing_rows=[2, 5])
    board.tear_next_frame()  # a seeded choice: max(1, 8 // 8) = 1 row
    frames = frames_of(dec.feed(board.read(0.5)))
    torn = [(fseq, sorted(set(range(ROWS)) - set(rows))) for fseq, (rows, end) in frames.items() if end and len(rows) < ROWS]
    assert len(torn) == 2 and torn[0][1] == [2, 5] and len(torn[1][1]) == 1
    for fseq, _ in torn:
        rows, end = frames[fseq]
        assert end is not None and end.rows == ROWS
        assert end.frame_crc32 == crc_of({r: source(fseq)[r] for r in range(ROWS)})
    assert dec.stats.missed == 3 == board.injected["torn_rows"]
    assert board.injected["torn_frames"] == 2


def test_skip_frames_leaves_a_frame_seq_gap():
    board = small_board()
    dec = started(board)
    pkts = dec.feed(board.read(0.1))
    board.skip_frames(3)
    pkts += dec.feed(board.read(0.8))
    seqs = [p.frame_seq for p in pkts if isinstance(p, codec.FrameEnd)]
    gaps = [b - a for a, b in zip(seqs, seqs[1:])]
    assert gaps.count(4) == 1 and set(gaps) == {1, 4}
    assert board.frames_dropped == 3 == board.injected["skipped_frames"]
    assert dec.stats.missed == 0
    board.receive(cmd("PING", 2, token=0), now_s=0.8)
    assert dec.feed(board.read(0.8))[-1].frames_dropped == 3


def test_duplicate_frame_is_sent_twice_with_new_packet_seqs():
    board = small_board()
    dec = started(board)
    dec.feed(board.read(0.1))
    board.duplicate_next_frame()
    pkts = dec.feed(board.read(0.4))
    ends = [p for p in pkts if isinstance(p, codec.FrameEnd)]
    seqs = [e.frame_seq for e in ends]
    (dup,) = [s for s in set(seqs) if seqs.count(s) == 2]
    first, second = [e for e in ends if e.frame_seq == dup]
    assert first.frame_crc32 == second.frame_crc32 and first.seq != second.seq
    rows = [p for p in pkts if isinstance(p, codec.Row) and p.frame_seq == dup]
    assert len(rows) == 2 * ROWS
    assert all((a.row, a.t_us, a.samples) == (b.row, b.t_us, b.samples) for a, b in zip(rows[:ROWS], rows[ROWS:]))
    assert dec.stats.missed == 0 and dec.stats.repeated == 0
    assert board.injected["duplicated_frames"] == 1


def test_unplug_of_a_bus_powered_board_is_a_power_cycle():
    board = small_board(seq_start=100)
    dec = started(board)
    dec.feed(board.read(0.5))
    board.unplug(now_s=0.5)
    assert not board.plugged and not board.powered and board.next_due_s() is None
    assert board.read(1.0) == b""
    board.receive(cmd("START", 2), now_s=1.0)  # nobody listens
    board.replug(now_s=2.0)
    assert board.plug_generation == 1 and board.injected["unplugs"] == board.injected["replugs"] == 1
    host = codec.StreamDecoder()
    (info,) = host.feed(board.read(3.0))  # it booted: INFO, not streaming
    assert info.seq == 100 and info.flags & 2 == 0
    board.receive(cmd("START", 3), now_s=3.0)
    frames = frames_of(host.feed(board.read(3.2)))
    assert min(frames) == 0  # frame counter restarted too


def test_unplug_of_a_self_powered_board_loses_what_it_sent_meanwhile():
    board = small_board(bus_powered=False)
    dec = started(board)
    dec.feed(board.read(0.5))
    board.unplug(now_s=0.5)
    assert board.read(1.5) == b"" and board.powered
    board.replug(now_s=1.5)
    pkts = dec.feed(board.read(2.0))
    seqs = sorted(frames_of(pkts))
    assert seqs[0] >= 20  # ~14 frames went nowhere
    assert board.injected["lost_unplugged_bytes"] > 0 and dec.stats.missed > 0


def test_faults_are_deterministic():
    def run():
        board = small_board(seed=9)
        out = bytearray(board.read(0.0))
        board.receive(cmd("START", 1), now_s=0.0)
        board.flip_bits(5)
        board.garbage(40)
        board.tear_next_frame()
        board.drop_bytes(7)
        out += board.read(0.5)
        return bytes(out), dict(board.injected)

    assert run() == run()


def test_a_board_of_another_definition_fails_loudly():
    board = small_board(definition_hash=codec.DEFINITION_HASH ^ 0x5A5A)
    dec = codec.StreamDecoder()
    (info,) = dec.feed(board.read(0.0))
    assert isinstance(info, codec.ForeignInfo)
    with pytest.raises(codec.ProtocolMismatchError, match=f"0x{codec.DEFINITION_HASH:04X}"):
        codec.check_compatible(info)
    board.receive(cmd("START", 1), now_s=0.0)  # its CRC check would fail this
    assert not board.streaming


def test_bad_configurations_are_refused_with_the_accepted_values():
    with pytest.raises(ValueError, match="packed12 holds at most 12"):
        VirtualBoard(adc_bits=16, packing="packed12")
    with pytest.raises(ValueError, match="adc_bits must be one of"):
        VirtualBoard(adc_bits=14, packing="u16")
    with pytest.raises(ValueError, match="packing must be one of"):
        VirtualBoard(packing="u12")
    with pytest.raises(ValueError, match="sign"):
        VirtualBoard(sign=0)
    with pytest.raises(ValueError, match="device_id"):
        VirtualBoard(device_id="x" * 17)
    with pytest.raises(ValueError, match="needs now_s"):
        VirtualBoard().read()

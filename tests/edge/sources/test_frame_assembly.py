"""Frame assembly: whole frames, torn frames, CRC, continuity and wrap-around."""

import numpy as np
import pytest
from frame_builders import frame_packets, info

from edge.frames import FrameAssembler, unpack_rows
from firmware_protocol import codec

PACKINGS = {"u8": (codec.PACKING["u8"], 255), "packed12": (codec.PACKING["packed12"], 4095), "u16": (codec.PACKING["u16"], 65535)}


def push_all(asm, pkts):
    out = []
    for p in pkts:
        out += asm.push(p)
    return out


@pytest.mark.parametrize("name", list(PACKINGS))
@pytest.mark.parametrize("cols", [6, 7, 1])
def test_whole_frame_round_trips_every_packing(name, cols):
    packing, top = PACKINGS[name]
    rng = np.random.default_rng(cols)
    counts = rng.integers(0, top + 1, (5, cols)).astype(np.uint16)
    counts[0, 0], counts[-1, -1] = 0, top  # extremes
    asm = FrameAssembler(info(5, cols, packing))
    frames = push_all(asm, frame_packets(counts, 10, 1000, packing))
    assert len(frames) == 1
    np.testing.assert_array_equal(frames[0].counts, counts)
    assert frames[0].counts.dtype == np.uint16 and frames[0].stale is None
    assert asm.counters["frames"] == 1


def test_unpack_rows_matches_stdlib_codec():
    rng = np.random.default_rng(0)
    vals = rng.integers(0, 4096, (3, 9))
    payloads = [codec.pack_samples(v.tolist(), codec.PACKING["packed12"]) for v in vals]
    np.testing.assert_array_equal(unpack_rows(payloads, codec.PACKING["packed12"], 9), vals)
    assert [codec.unpack_samples(p, codec.PACKING["packed12"], 9) for p in payloads] == vals.tolist()


def test_crc_mismatch_drops_the_frame():
    counts = np.full((4, 6), 2048, np.uint16)
    asm = FrameAssembler(info(4, 6))
    assert push_all(asm, frame_packets(counts, 1, 0, 1, crc_override=1234)) == []
    assert asm.counters["crc_mismatch"] == 1


def test_torn_frame_is_dropped_by_default_and_counted():
    counts = np.full((8, 6), 2048, np.uint16)
    asm = FrameAssembler(info())
    push_all(asm, frame_packets(counts, 1, 0, 1))
    assert push_all(asm, frame_packets(counts, 2, 71_000, 1, skip_rows=(3,))) == []
    assert asm.counters["torn_dropped"] == 1
    # the next whole frame still arrives, and the lost frame is not called a gap
    frames = push_all(asm, frame_packets(counts, 3, 142_000, 1))
    assert len(frames) == 1 and frames[0].index == 2


def test_torn_frame_flag_policy_fills_from_last_frame_and_marks_stale():
    first = np.full((8, 6), 2000, np.uint16)
    second = np.full((8, 6), 1000, np.uint16)
    asm = FrameAssembler(info(), missing_rows="flag", max_missing_rows=2)
    push_all(asm, frame_packets(first, 1, 0, 1))
    frames = push_all(asm, frame_packets(second, 2, 71_000, 1, skip_rows=(3, 5)))
    assert len(frames) == 1
    f = frames[0]
    assert f.stale[[3, 5]].all() and not f.stale[[0, 1, 2, 4, 6, 7]].any()
    assert (f.counts[[3, 5]] == 2000).all() and (f.counts[0] == 1000).all()
    # too many missing rows: dropped even under "flag"
    assert push_all(asm, frame_packets(second, 3, 142_000, 1, skip_rows=(0, 1, 2))) == []
    assert asm.counters["torn_flagged"] == 1 and asm.counters["torn_dropped"] == 1


def test_a_frame_without_its_frame_end_is_never_emitted():
    counts = np.arange(48, dtype=np.uint16).reshape(8, 6)
    asm = FrameAssembler(info())
    pkts = frame_packets(counts, 1, 0, 1)[:-1]  # no FRAME_END, so no CRC-32 to check the rows against
    assert push_all(asm, pkts) == []
    frames = push_all(asm, frame_packets(counts, 2, 71_000, 1))
    assert [f.frame_seq for f in frames] == [2]
    assert asm.counters["missing_frame_end"] == 1


def test_rows_of_two_frames_under_one_number_never_make_a_frame():
    first, second = np.full((8, 6), 1000, np.uint16), np.full((8, 6), 3000, np.uint16)
    asm = FrameAssembler(info(), missing_rows="flag", max_missing_rows=4)
    mixed = frame_packets(first, 1, 0, 1)[:4] + frame_packets(second, 1, 0, 1)[4:8]  # no FRAME_END
    assert push_all(asm, mixed) == []
    frames = push_all(asm, frame_packets(second, 2, 71_000, 1))
    assert [f.frame_seq for f in frames] == [2] and (frames[0].counts == 3000).all()


def test_duplicate_and_gap_and_restart():
    counts = np.full((8, 6), 2048, np.uint16)
    asm = FrameAssembler(info())
    push_all(asm, frame_packets(counts, 5, 0, 1))
    assert push_all(asm, frame_packets(counts, 5, 71_000, 1)) == []  # duplicate
    frames = push_all(asm, frame_packets(counts, 9, 5 * 71_000, 1))  # 3 frames missed
    assert frames[0].index == 4
    frames = push_all(asm, frame_packets(counts, 0, 6 * 71_000, 1))  # the board restarted
    assert frames[0].index == 5
    assert asm.counters["duplicate_frames"] == 1
    assert asm.counters["missed_frames"] == 3
    assert asm.counters["seq_restarts"] == 1


def test_frame_seq_and_microsecond_wrap_are_seamless_over_hours():
    """frame_seq crosses 2^32 and t_us wraps several times (a run longer than 2^32 µs)."""
    counts = np.full((2, 2), 7, np.uint16)
    asm = FrameAssembler(info(2, 2))
    period_us = 71_429
    seq0, t0 = 2**32 - 3, 2**32 - 100_000
    n = 3 * (2**32 // period_us) // 100  # sample a long run sparsely: every 100th frame
    last_t = None
    for k in range(n):
        seq = (seq0 + k) % 2**32
        frames = push_all(asm, frame_packets(counts, seq, (t0 + k * period_us) % 2**32, 1, row_dt_us=10))
        assert len(frames) == 1
        f = frames[0]
        assert f.index == k
        if last_t is not None:
            assert f.t_s - last_t == pytest.approx(period_us * 1e-6, abs=1e-6)
        last_t = f.t_s
    assert last_t > 2**32 * 1e-6 * 0.02  # well past one wrap of the sparse clock
    assert asm.counters["missed_frames"] == 0 and asm.counters["time_jumps"] == 0


def test_rows_of_the_wrong_size_or_index_are_counted_not_used():
    asm = FrameAssembler(info(4, 6))
    bad = [codec.make_row(0, 1, 0, 9, [1] * 6, 1), codec.make_row(1, 1, 0, 0, [1] * 5, 1)]
    assert push_all(asm, bad) == []
    assert asm.counters["bad_rows"] == 2


def test_wiring_map_of_the_wrong_grid_is_refused():
    from edge.wiring import WiringMap

    with pytest.raises(ValueError, match="wire grid"):
        FrameAssembler(info(4, 6), WiringMap.identity(6, 4))

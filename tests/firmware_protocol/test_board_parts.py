"""The virtual board's separated parts: its settings (checked, resolved, frozen) and its pending faults."""

from __future__ import annotations

import dataclasses

import pytest

from firmware_protocol import codec
from firmware_protocol.board_faults import PendingFaults
from firmware_protocol.board_settings import BoardSettings
from firmware_protocol.virtual_board import VirtualBoard


def test_settings_resolve_tiles_packing_and_wrapped_starts():
    s = BoardSettings(96, 64, packing=codec.PACKING["u16"], adc_bits=16, seq_start=0x1_0002, t_us_start=-1)
    assert (s.tile_rows, s.tile_cols) == (3, 2)
    assert s.packing == "u16" and s.packing_code == codec.PACKING["u16"]
    assert (s.seq_start, s.t_us_start) == (2, 0xFFFFFFFF)
    assert (s.protocol_version, s.definition_hash) == (codec.PROTOCOL_VERSION, codec.DEFINITION_HASH)
    with pytest.raises(dataclasses.FrozenInstanceError):
        s.rows = 32  # type: ignore[misc]
    with pytest.raises(TypeError):
        BoardSettings(96, 96, 12)  # everything past the grid is keyword-only


def test_board_from_settings_equals_board_from_keywords():
    s = BoardSettings(32, 32, seed=4, rate_hz=10)
    a, b = VirtualBoard(settings=s), VirtualBoard(32, 32, seed=4, rate_hz=10)
    assert a.settings == b.settings and a.max_rate_hz == s.fastest_rate_hz
    for board in (a, b):
        board.receive(codec.encode_command("START", 1), now_s=0.0)
    assert a.read(1.0) == b.read(1.0)
    with pytest.raises(TypeError, match="not both"):
        VirtualBoard(32, settings=s)


def test_pending_faults_hit_the_next_bytes_in_the_order_asked():
    faults = PendingFaults(seed=1)
    junk = faults.garbage(3, zeros=False)
    faults.drop_bytes(2)
    assert faults.link_ops_waiting
    assert faults.apply_to_link(b"abcdef") == junk + b"cdef"
    assert not faults.link_ops_waiting
    assert faults.injected == {"garbage_bytes": 3, "dropped_bytes": 2}
    faults.drop_bytes(5)  # longer than what goes out: the rest waits for the next bytes
    assert faults.apply_to_link(b"xyz") == b"" and faults.apply_to_link(b"1234") == b"34"


def test_pending_frame_faults_are_taken_once_each():
    faults = PendingFaults(seed=1)
    faults.skip_frames(1)
    faults.tear_next_frame([0, 7, 99])
    faults.duplicate_next_frame()
    assert faults.take_skip() and not faults.take_skip()
    assert faults.take_tear(8) == frozenset({0, 7}) and faults.take_tear(8) == frozenset()
    assert faults.take_duplicate() and not faults.take_duplicate()
    assert faults.injected == {"skipped_frames": 1, "torn_frames": 1}

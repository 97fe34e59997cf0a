"""A carpet source's reading of INFO: identity changes, range problems, why no INFO came."""

from __future__ import annotations

import dataclasses

import pytest

from edge.sources.board_info import identity_changes, info_problems, is_info, no_info_message
from firmware_protocol import codec
from firmware_protocol.virtual_board import VirtualBoard


def test_identity_changes_name_each_field_that_differs():
    info = VirtualBoard(32, 32, device_id="carpet-A").info_packet()
    other = dataclasses.replace(info, device_id="carpet-B", sign=1, rate_mhz=1000)  # the rate is no identity
    assert identity_changes(info, info) == []
    assert identity_changes(info, other) == ["device_id 'carpet-B' (was 'carpet-A')", "sign 1 (was -1)"]


def test_info_problems_refuse_another_definition_and_list_insane_fields():
    info = VirtualBoard(32, 32).info_packet()
    assert is_info(info) and info_problems(info) == []
    assert info_problems(dataclasses.replace(info, rows=0)) == [f"rows 0 (1..{codec.MAX_GRID})"]
    foreign = codec.ForeignInfo(0, codec.PROTOCOL_VERSION, codec.DEFINITION_HASH ^ 1)
    assert is_info(foreign) and not is_info(codec.Ack(0, 1, 2, 3))
    with pytest.raises(codec.ProtocolMismatchError):
        info_problems(foreign)


def test_no_info_message_guesses_from_what_the_decoder_saw():
    stats = codec.DecoderStats()
    assert "no bytes from the board" in no_info_message("serial:///dev/x", stats, 3.0)
    stats.bytes_in, stats.dropped["bad_crc"] = 100, 3
    assert "another protocol definition" in no_info_message("serial:///dev/x", stats, 3.0)
    stats.dropped["bad_crc"] = 0
    assert "wrong baud rate" in no_info_message("serial:///dev/x", stats, 3.0)

"""Board health (issue 17, finding 1): frames arriving or not → connected / lost, each transition once, with a
reason that tells an unplugged board from one whose frames fail their checks."""

import pytest

from edge.runtime.board_health import CONNECTED, LOST, BoardHealth


def stats(disconnects=0, crc=0, torn=0, decoder=0):
    return {"source": {"disconnects": disconnects}, "frames": {"crc_mismatch": crc, "torn_dropped": torn},
            "decoder": {"dropped_total": decoder}}


def test_lost_after_the_timeout_once_and_back_at_the_first_frame_once():
    h = BoardHealth(5.0, now_s=100.0)
    assert not h.due(104.9) and h.due(105.0)
    assert h.connected and h.check(104.9) is None
    change = h.check(105.0)
    assert change is not None and change.state == LOST and change.reason == "no frames for 5 s"
    assert h.check(106.0) is None and h.check(200.0) is None  # said once, however long it lasts
    assert h.as_dict(110.0) == {"connected": False, "state": LOST, "reason": "no frames for 5 s",
                                "last_frame_age_s": 10.0, "timeout_s": 5.0}
    assert not h.due(210.0)
    h.frame(210.0)
    assert h.due(210.0)
    back = h.check(210.0)
    assert back is not None and back.state == CONNECTED and back.after_s == pytest.approx(105.0)
    assert h.check(211.0) is None and h.as_dict(211.0)["reason"] is None


def test_frames_keep_it_connected():
    h = BoardHealth(1.0, now_s=0.0)
    for k in range(100):
        h.frame(k * 0.5)
        assert h.check(k * 0.5 + 0.9) is None


def test_the_reason_names_an_unplugged_board_or_frames_failing_their_checks():
    unplugged = BoardHealth(2.0, now_s=0.0)
    unplugged.frame(1.0, stats(disconnects=0, crc=3))
    assert "link dropped" in unplugged.check(3.5, stats(disconnects=1, crc=3)).reason
    corrupt = BoardHealth(2.0, now_s=0.0)
    corrupt.frame(1.0, stats(crc=3))
    reason = corrupt.check(3.5, stats(crc=20, torn=2)).reason
    assert "19 frames/packets failed their checks" in reason and "CRC" in reason
    silent = BoardHealth(2.0, now_s=0.0)
    silent.frame(1.0, stats())
    assert silent.check(3.5, stats()).reason == "no frames for 2 s"


def test_a_board_that_never_sends_a_frame_is_lost_after_the_timeout():
    h = BoardHealth(3.0, now_s=10.0)
    assert h.check(13.0).state == LOST


@pytest.mark.parametrize("bad", [0.0, -1.0])
def test_the_timeout_must_be_positive(bad):
    with pytest.raises(ValueError, match="board timeout"):
        BoardHealth(bad, now_s=0.0)

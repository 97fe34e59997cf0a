"""Another board answering is the runtime's state, on the status file and in the sinks' info (issue 18, finding 1)."""

from edge.runtime import Runtime
from edge.runtime.status import format_status


class SwappedBoard:
    """A source whose pinned board was replaced by another (what CarpetSource.stats() then says)."""

    info = None
    last_status = None
    ended = False

    def start(self):
        pass

    def stop(self):
        pass

    def frames(self, timeout_s=None):
        return iter(())

    def queue_depth(self):
        return 0, 4

    def stats(self):
        return {"source": {"board_mismatch": 1}, "board_mismatch": "another board answered: device_id 'carpet-B'"}


def test_a_swapped_board_is_the_state_on_status_and_info(config):
    rt = Runtime(config(), source=SwappedBoard())
    rt.state = "running"
    snap = rt.snapshot()
    assert snap["state"] == "board_mismatch"
    assert "carpet-B" in snap["source"]["board_mismatch"]
    assert rt.info()["state"] == "board_mismatch"
    assert "BOARD MISMATCH" in format_status(snap)

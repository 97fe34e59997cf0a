"""The runtime reads its source through one typed interface (edge.sources.base.FrameSource, issue 15): a source
lacking a member is refused when the runtime is built or set up, naming what is missing, never mid-run."""

import pytest

from edge.runtime import Runtime
from edge.sources import CarpetSource
from edge.sources.base import FRAME_SOURCE_MEMBERS, Link, require_frame_source


class QuietLink(Link):
    def open(self):
        pass

    def read(self, timeout_s):
        return b""

    def write(self, data):
        pass

    def close(self):
        pass


class NoEndSource:
    """Everything but ``ended`` and ``queue_depth`` (what the loop used to probe with getattr)."""

    info = None
    last_status = None

    def start(self):
        pass

    def stop(self):
        pass

    def frames(self, timeout_s=None):
        return iter(())

    def stats(self):
        return {}


def test_the_interface_lists_what_the_loop_reads():
    assert set(FRAME_SOURCE_MEMBERS) == {"info", "last_status", "start", "stop", "frames", "ended", "queue_depth",
                                         "stats"}


def test_a_carpet_source_is_a_frame_source():
    source = CarpetSource(QuietLink())
    assert require_frame_source(source) is source


def test_a_source_without_ended_is_refused_at_construction(config):
    with pytest.raises(TypeError, match=r"NoEndSource is not a frame source: it lacks ended, queue_depth \("):
        Runtime(config(), source=NoEndSource())


def test_a_member_that_cannot_be_called_is_named():
    source = NoEndSource()
    source.ended = False
    source.queue_depth = (0, 4)
    with pytest.raises(TypeError, match=r"lacks queue_depth \(not callable\)"):
        require_frame_source(source)


def test_a_source_set_after_construction_is_refused_at_setup(config):
    rt = Runtime(config(), say=lambda text: None)
    rt.source = NoEndSource()
    with pytest.raises(TypeError, match="lacks ended, queue_depth"):
        rt.setup()
    assert rt.seqs is None  # the seq ledger was given back: nothing left behind

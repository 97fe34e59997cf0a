"""A source reports each frame's decoding time (``on_decoded``) and its queue (``queue_depth``, ``ended``) through
public names: the runtime's reader (edge/runtime/reader.py) no longer wraps its decoder or private methods."""

from edge.runtime.counters import StageTimes
from edge.runtime.reader import open_timed_source
from edge.sources import open_source

URL = "sim://?world=footsteps&people=1&seed=3&speed=0&grid=32"


def test_on_decoded_is_called_once_per_frame_with_its_decoding_time():
    decoded = []
    with open_source(URL, on_decoded=decoded.append, queue_frames=3) as source:
        assert source.queue_depth()[1] == 3
        frames = [source.read_frame(timeout_s=5.0) for _ in range(6)]
        assert not source.ended
    assert all(f is not None for f in frames)
    assert len(decoded) >= 6  # the reader may have assembled a few more into the queue
    assert all(0.0 <= ms < 1000.0 for ms in decoded) and sum(decoded) > 0.0


def test_the_runtime_reader_records_decode_stage_times():
    times = StageTimes()
    with open_timed_source(URL, times, queue_frames=2) as source:
        for _ in range(4):
            assert source.read_frame(timeout_s=5.0) is not None
    summary = times.summary()["decode"]
    assert summary["n"] >= 4 and summary["median_ms"] >= 0.0

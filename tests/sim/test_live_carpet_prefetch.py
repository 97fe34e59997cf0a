"""The live carpet places its next scene in a helper process, so a real-time stream does not pause.

Without it, ``sim://`` at speed=1 stopped for the scene's placement (0.3 s to seconds) at every
scene change (the runtime's demo dropped frames there).
"""

import multiprocessing
import time

import numpy as np
import pytest

from edge.sources import open_source
from sim.live import LiveCarpet

RATE_HZ = 14.0


def helpers():
    return [p for p in multiprocessing.active_children() if p.name == "live-carpet-scenes"]


def test_prefetched_scenes_are_the_in_process_ones_and_close_ends_the_helper():
    plain = LiveCarpet(people=2, seed=7, chunk_s=1.0, extend=False)  # scenes of exactly 14 frames
    with LiveCarpet(people=2, seed=7, chunk_s=1.0, prefetch=True, extend=False) as ahead:
        assert len(helpers()) == 1
        for k in (0, 13, 14, 20, 27, 28, 41):  # three 14-frame scenes
            np.testing.assert_array_equal(ahead(k), plain(k))
            assert [t["activity"] for t in ahead.truth(k)] == [t["activity"] for t in plain.truth(k)]
        assert ahead.scenes_from_helper == 2 and plain.scenes_from_helper == 0  # scenes 1 and 2
        np.testing.assert_array_equal(ahead(3), plain(3))  # going back: placed here again, the same
    assert helpers() == []  # close() ended it
    assert plain._helper is None  # no helper unless asked for


@pytest.mark.slow  # 5 s of real-time streaming: ~10 s
def test_a_real_time_stream_does_not_pause_at_a_scene_change():
    scene_s = 4.0
    url = f"sim://?people=2&seed=7&speed=1&scene_s={scene_s:g}"
    with open_source(url) as source:
        carpet = source.link.carpet
        frames = []
        deadline = time.monotonic() + scene_s + 6.0
        while len(frames) < int((scene_s + 1.0) * RATE_HZ) and time.monotonic() < deadline:  # one scene change
            frame = source.read_frame(timeout_s=2.0)
            if frame is not None:
                frames.append(frame)
    assert helpers() == []  # closing the link ended the helper
    assert len(frames) == int((scene_s + 1.0) * RATE_HZ), f"{len(frames)} frames"
    seqs = [f.frame_seq for f in frames]
    assert seqs == list(range(seqs[0], seqs[0] + len(seqs)))  # none dropped or lost
    gaps = np.diff([f.host_time_s for f in frames])  # gaps[i]: frames[i] → frames[i + 1]
    change = int(scene_s * RATE_HZ) - seqs[0]  # index of the first frame of the second scene
    around = gaps[change - int(RATE_HZ):change + int(RATE_HZ)]  # one second either side of the change
    print(f"\nlargest gap within 1 s of the scene change {around.max() * 1e3:.0f} ms, at it "
          f"{np.round(gaps[change - 2:change + 2] * 1e3).tolist()} ms; largest anywhere {gaps.max() * 1e3:.0f} ms "
          f"(frame {seqs[int(np.argmax(gaps)) + 1]}; the helper's start-up shares the CPU with the first second)")
    assert around.max() < 3 / RATE_HZ  # without the helper: ~300 ms here (placing this scene takes ~0.3 s)
    assert carpet.scenes_from_helper == 1

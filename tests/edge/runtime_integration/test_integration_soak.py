"""Soak: 5,000 frames through the in-process runtime as fast as it goes, into a rotated JSON-lines file.

The same function as bench/runtime_soak.py (which runs 50,000 frames and writes
bench/results/runtime_soak.json), with the same assertions: resident memory grows < 10 MB after
a 2,000-frame warm-up, the reader → pipeline and pipeline → publisher queues never pass their
bounds (sampled after every frame), and the lines written are exactly the records the runtime counted.
"""

import pytest

from bench.runtime_soak import GOALS, soak

FRAMES, WARMUP = 5000, 2000

pytestmark = pytest.mark.slow  # ~25 s here


def test_5000_frames_memory_flat_queues_bounded_every_record_written(tmp_path, sim_calibration, one_person_frames):
    out = tmp_path / "out"
    out.mkdir()
    r = soak(FRAMES, out, sim_calibration, list(one_person_frames.counts), warmup=WARMUP, rotate_mb=1.0)
    print(f"\n{r['frames']} frames in {r['seconds']} s ({r['frames_per_s']}/s); RSS MB {r['rss_mb']}; "
          f"queues {r['queues']}; records {r['records']}; work {r['work']}")
    assert r["state"] == "stopped" and r["frames"] == FRAMES
    w = r["work"]
    assert w["frames_failed"] == 0 and w["frames_invalid"] == 0
    assert w["frames_people"] >= 0.95 * FRAMES and w["encoder_runs"] >= 0.5 * FRAMES  # the model ran
    assert w["tracks_freed"] >= 3 and w["tracks_open"] <= 2  # scenes changed; windows were freed, not piled up
    # memory: flat after the warm-up
    assert r["rss_mb"]["growth_after_warmup"] < GOALS["rss_growth_mb"], r["rss_mb"]
    # queues: sampled after every frame, never past their bounds (the reader is faster: its queue runs full)
    q = r["queues"]
    assert q["frames_bound"] == 4 and q["records_bound"] == 256
    assert 1 <= q["frames_max"] <= q["frames_bound"] and q["records_max"] <= q["records_bound"]
    assert r["dropped_slow_consumer"] == 0  # not paced: the reader waited instead of dropping
    # every record counted was written, once, as a whole line, across the rotated files
    rec = r["records"]
    assert rec["files"] >= 3  # rotation happened
    assert rec["lines_written"] == rec["counted"] == rec["published"] == rec["sink_sent"] >= 0.95 * FRAMES
    assert rec["queue_dropped"] == 0 and rec["sink_dropped"] == 0 and rec["sink_errors"] == 0

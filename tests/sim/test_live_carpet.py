"""The live virtual carpet: simulated people streamed through the real protocol."""

import numpy as np

from edge.sources import open_source
from sim.live import LiveCarpet


def test_live_carpet_is_deterministic_and_people_load_the_sensor():
    a, b = LiveCarpet(people=2, seed=3), LiveCarpet(people=2, seed=3)
    frames_a = [a(k) for k in range(5)]
    frames_b = [b(k) for k in range(5)]
    for x, y in zip(frames_a, frames_b):
        np.testing.assert_array_equal(x, y)
    truth = a.truth(4)
    assert len(truth) == 2 and all(t["pose_aa"].shape == (72,) for t in truth)
    p = a.pressure_kpa(4)
    force_n = p.sum() * a.pitch_m**2 * 1e3
    weight_n = sum(a.mass_kg) * 9.81
    assert 0.5 * weight_n < force_n < 1.5 * weight_n  # both people stand on the carpet


def test_empty_live_carpet():
    c = LiveCarpet(people=0, seed=1)
    assert c.truth(0) == [] and c.pressure_kpa(0).max() == 0


def test_sim_url_streams_simulated_bodies():
    with open_source("sim://?people=1&seed=2&speed=0") as source:
        frames = [source.read_frame(timeout_s=10) for _ in range(3)]
        info = source.info
    assert all(f is not None and f.counts.shape == (96, 96) for f in frames)
    assert info.sign in (-1, 1) and info.adc_bits == 12


def test_a_scene_lasts_as_long_as_its_activity_needs():
    """A sit-up (getting down, a repetition, getting up at the person's pace: ~17 s) is not squeezed into a
    5-s scene: its scene lasts longer; frames find their scene whichever way the stream goes."""
    from sim.motion import ACTIVITIES

    c = LiveCarpet(people=1, seed=2, activities=("sit_up", "stepping"), chunk_s=5.0)
    starts = [k for k in range(500) if c.locate(k)[1] == 0]
    lengths = np.diff(starts)
    assert len(lengths) >= 2 and lengths.min() >= c.chunk_frames
    kinds = [c.truth(s + 40)[0]["activity"] for s in starts[:-1]]
    assert "sit_up" in kinds and "stepping" in kinds
    for start, n, kind in zip(starts, lengths, kinds):
        assert (n > 12 * c.rate_hz) == (kind == "sit_up")  # only the sit-up needs more than 5 s
        assert c.truth(start)[0]["scene"] == c.truth(start + n - 1)[0]["scene"] == c.locate(start)[0]
    first = c.truth(3)[0]  # going back: the same scene again
    assert first["scene"] == 0 and ACTIVITIES.index(first["activity"]) >= 0
    exact = LiveCarpet(people=1, seed=2, activities=("sit_up", "stepping"), chunk_s=5.0, extend=False)
    assert [exact.locate(k) for k in (0, 69, 70, 141)] == [(0, 0), (0, 69), (1, 0), (2, 1)]

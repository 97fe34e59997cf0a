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

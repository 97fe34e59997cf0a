"""Frame-stream faults at the configured rates; jittered, monotonic timestamps."""

import numpy as np
import pytest

from sim.sensor import CarpetSensor, FrameStream, GridConfig, SensorConfig, StreamConfig


def run(n=4000, **rates):
    s = CarpetSensor(SensorConfig(grid=GridConfig(rows=32, cols=32)), seed=9)
    rng = np.random.default_rng(0)
    frames = [rng.uniform(0, 20, (32, 32)) for _ in range(16)]
    cfg = StreamConfig(**rates)
    return s, cfg, list(FrameStream(s, cfg).frames(frames[k % 16] for k in range(n)))


def within(count, n, rate, z=5.0):
    sd = np.sqrt(n * rate * (1 - rate))
    return abs(count - n * rate) <= z * sd + 1


def test_fault_rates_and_timestamps():
    n = 4000
    s, cfg, out = run(n, drop_rate=0.03, duplicate_rate=0.04, tear_rate=0.05, corrupt_rate=0.02, jitter_s=0.003)
    flags = [f for _, _, f in out]
    drops = sum(f.dropped_before for f in flags)
    dups = sum(f.duplicate for f in flags)
    torn = sum(f.torn is not None for f in flags)
    bad = sum(f.corrupt is not None for f in flags)
    assert within(drops, n, 0.03) and within(dups, n, 0.04) and within(torn, n, 0.05) and within(bad, n, 0.02)
    # every true frame is accounted for exactly once (apart from duplicates)
    seqs = [f.seq for f in flags if not f.duplicate]
    assert len(seqs) + drops == n and seqs == sorted(set(seqs))
    # timestamps: strictly increasing except a duplicate, which repeats the previous one
    ts = np.array([t for _, t, _ in out])
    for i in range(1, len(out)):
        if flags[i].duplicate:
            assert ts[i] == ts[i - 1]
        else:
            assert ts[i] > ts[i - 1]
    jit = np.array([t - f.true_t_s for _, t, f in out if not f.duplicate])
    assert np.std(jit) == pytest.approx(0.003, rel=0.1)
    assert np.abs(jit).max() <= 0.45 / 14 + 1e-12


def test_torn_and_corrupt_frames_look_as_flagged():
    s, cfg, out = run(600, tear_rate=0.2, corrupt_rate=0.05, jitter_s=0.0)
    fs = s.carpet.full_scale
    kinds = set()
    for i, (c, t, f) in enumerate(out):
        assert t == pytest.approx(f.true_t_s)
        if f.torn == "old":
            prev = out[i - 1][0]  # the previous yielded frame is the previous true frame here
            assert out[i - 1][2].seq == f.seq - 1
            if out[i - 1][2].clean:
                np.testing.assert_array_equal(c[f.tear_row :], prev[f.tear_row :])
            kinds.add("old")
        elif f.torn == "shift":
            assert f.shift != 0
            kinds.add("shift")
        elif f.corrupt == "constant":
            assert np.all(c == c.flat[0])
            kinds.add("constant")
        elif f.corrupt == "out_of_range":
            assert np.all(c > fs)
            kinds.add("out_of_range")
        else:
            assert c.max() <= fs
    assert kinds == {"old", "shift", "constant", "out_of_range"}


def test_shifted_frame_is_a_roll_of_the_true_frame():
    # same seed: the sensor produces the same counts with and without tearing
    s1, _, clean = run(300, jitter_s=0.0)
    s2, _, torn = run(300, tear_rate=0.3, tear_shift_fraction=1.0, jitter_s=0.0)
    by_seq = {f.seq: c for c, _, f in clean}
    n = 0
    for c, _, f in torn:
        if f.torn == "shift":
            np.testing.assert_array_equal(c, np.roll(by_seq[f.seq], f.shift, axis=0))
            n += 1
    assert n > 50


def test_stream_is_deterministic():
    a = run(200, drop_rate=0.05, duplicate_rate=0.05)[2]
    b = run(200, drop_rate=0.05, duplicate_rate=0.05)[2]
    assert [f for _, _, f in a] == [f for _, _, f in b]
    assert all(np.array_equal(x[0], y[0]) for x, y in zip(a, b))

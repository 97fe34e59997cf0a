"""Scene step on hard inputs: NaN/∞/huge frames, a one-euro filter fed dt ≤ 0 and NaN, and a
person at the carpet's edge and corners.

Documented behaviour (docs/stability.md): a frame is either rejected with a counted reason or
accepted with its few bad sensels masked; no NaN ever reaches the filters' or the tracks' state,
so the frames after a bad one are tracked as if it never came.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from edge.scene import FilterChain, OneEuroFilter, SceneConfig, SceneTracker

N, PITCH_M, DT_S = 96, 0.01905, 1 / 14
FOOT_A_M, FOOT_B_M = 0.125, 0.045


def feet(centres_m: list[tuple[float, float]], mass_kg: float = 70.0) -> np.ndarray:
    """(N, N) kPa: elliptic feet (25 × 9 cm, along x) at the given centres, sampled at sensel centres."""
    c = (np.arange(N) + 0.5) * PITCH_M
    x, y = np.meshgrid(c, c)
    p = np.zeros((N, N), np.float32)
    per_foot_kpa = mass_kg * 9.81 / len(centres_m) / (math.pi * FOOT_A_M * FOOT_B_M) / 1e3
    for fx, fy in centres_m:
        p[((x - fx) / FOOT_A_M) ** 2 + ((y - fy) / FOOT_B_M) ** 2 <= 1.0] += per_foot_kpa
    return p


def noisy(p: np.ndarray, i: int) -> np.ndarray:
    return p + np.random.default_rng(i).normal(0.0, 0.02, p.shape).astype(np.float32)


def assert_state_finite(tracker: SceneTracker) -> None:
    f = tracker.filters
    if f._ema is not None:
        assert np.isfinite(f._ema).all() and math.isfinite(f._ema_peak)
    assert all(np.isfinite(h).all() for h in f._history)
    for tr in tracker.people.tracks.values():
        assert np.isfinite(tr.cop_m).all() and math.isfinite(tr.force_n) and np.isfinite(tr.velocity_m_s).all()
        for flt in (tr.cop_filter, tr.force_filter):
            x, dx = (flt._x, flt._dx) if flt._sx is None else (flt._sx, flt._sdx)  # array or scalar state
            assert np.isfinite(x).all() and np.isfinite(dx).all() and math.isfinite(flt._t_s)


CENTRE = [(0.9, 0.8), (0.9, 1.0)]


def _bad(kind: str) -> np.ndarray:
    p = noisy(feet(CENTRE), 99)
    if kind == "few_nan":
        p[40:44, 45:49] = np.nan  # 16 sensels under a foot (< 1 %): masked and filled for this frame
    elif kind == "all_nan":
        p[:] = np.nan
    elif kind == "few_inf":
        p[41, 47], p[5, 5] = np.inf, -np.inf
    elif kind == "many_inf":
        p[:20] = np.inf
    elif kind == "huge":
        p[42, 46] = 1e30
    elif kind == "negative_huge":
        p[42, 46] = -1e30
    return p


BAD_FRAMES = {"few_nan": None, "few_inf": None, "all_nan": "non_finite", "many_inf": "non_finite",
              "huge": "out_of_range", "negative_huge": "out_of_range"}


@pytest.mark.parametrize("kind", list(BAD_FRAMES))
def test_a_bad_frame_is_rejected_or_masked_and_never_poisons_later_frames(kind):
    tracker = SceneTracker(N, N, PITCH_M)
    t = 0.0
    for i in range(5):
        t += DT_S
        frame = tracker.update(noisy(feet(CENTRE), i), t)
    (person,) = frame.people
    t += DT_S
    frame = tracker.update(_bad(kind), t)
    reason = BAD_FRAMES[kind]
    assert frame.reason == reason and frame.valid == (reason is None)
    if reason is None:
        assert np.isfinite(frame.pressure_kpa).all() and [p.track_id for p in frame.people] == [person.track_id]
        assert all(np.isfinite(p.cop_m).all() and math.isfinite(p.force_n) for p in frame.people)
    else:
        assert frame.pressure_kpa is None and frame.counters[f"rejected_{reason}"] == 1
    assert_state_finite(tracker)
    for i in range(3):
        t += DT_S
        frame = tracker.update(noisy(feet(CENTRE), 10 + i), t)
        assert frame.valid and [p.track_id for p in frame.people] == [person.track_id]
        (now,) = frame.people
        assert np.isfinite(now.cop_m).all() and np.abs(now.cop_m - [0.9, 0.9]).max() < 0.03
        assert 500 < now.force_n < 800  # 70 kg: ~690 N
    assert_state_finite(tracker)


def test_a_non_finite_time_is_rejected_as_bad_time():
    tracker = SceneTracker(N, N, PITCH_M)
    tracker.update(feet(CENTRE), 1.0)
    for t in (math.nan, math.inf):
        assert tracker.update(feet(CENTRE), t).reason == "bad_time"
    assert tracker.counters["rejected_bad_time"] == 2
    assert tracker.update(feet(CENTRE), 1.1).valid  # the clock was not moved to ∞


def test_filter_chain_refuses_nan_before_touching_its_state():
    chain = FilterChain(PITCH_M, SceneConfig(temporal_median=True))
    good = feet(CENTRE)
    chain(good, 0.0, 0.1)
    ema, history = chain._ema.copy(), [h.copy() for h in chain._history]
    bad = good.copy()
    bad[3, 3] = np.nan
    with pytest.raises(ValueError, match="1 NaN/∞ sensel.*check_frame"):
        chain(bad, DT_S, 0.1)
    np.testing.assert_array_equal(chain._ema, ema)
    assert len(chain._history) == len(history)


# ------------------------------------------------------------------ one-euro filter


def test_one_euro_ignores_dt_zero_and_negative_dt():
    f = OneEuroFilter(1.0, 0.5, 1.0)
    assert f(1.0, 0.0) == 1.0
    assert f(5.0, 0.0) == 1.0  # dt = 0: the last estimate, unchanged
    assert f(5.0, -1.0) == 1.0  # time went back: the same
    assert f.skipped == 0
    ref = OneEuroFilter(1.0, 0.5, 1.0)
    ref(1.0, 0.0)
    assert f(2.0, 0.1) == ref(2.0, 0.1)  # as if the two samples never came


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_one_euro_skips_non_finite_samples_and_times_and_stays_finite(bad):
    f, ref = OneEuroFilter(1.0, 2.0, 1.0), OneEuroFilter(1.0, 2.0, 1.0)
    x = np.array([0.5, 0.7])
    np.testing.assert_array_equal(f(np.array([bad, 0.0]), 0.0), [bad, 0.0])  # nothing held yet: returned as is
    assert f._x is None  # ... and not stored
    np.testing.assert_array_equal(f(x, 0.0), ref(x, 0.0))
    np.testing.assert_array_equal(f(np.array([bad, 0.0]), 0.1), x)  # the last estimate
    np.testing.assert_array_equal(f(x + 0.1, bad), x)  # a NaN/∞ time: the same
    assert f.skipped == 3
    for k in range(1, 5):  # later samples filter exactly as if the bad ones never came
        np.testing.assert_array_equal(f(x + 0.01 * k, 0.1 * k), ref(x + 0.01 * k, 0.1 * k))
    assert np.isfinite(f._x).all() and np.isfinite(f._dx).all()


def test_one_euro_skips_a_jump_that_would_overflow_its_derivative():
    f = OneEuroFilter(1.0, 1.0, 1.0)
    f(0.0, 0.0)
    assert f(1e308, 1e-300) == 0.0 and f.skipped == 1  # (1e308 − 0) / 1e-300 is ∞
    assert math.isfinite(f(1.0, 0.1))


# ------------------------------------------------------------------ a person at the edge


EDGE_CASES = {
    "corner_row0_col0": [(0.05, 0.02), (0.05, 0.20)],
    "corner_last_row_last_col": [(N * PITCH_M - 0.05, N * PITCH_M - 0.02), (N * PITCH_M - 0.05, N * PITCH_M - 0.20)],
    "edge_row0": [(0.80, 0.02), (1.00, 0.02)],
    "edge_last_col": [(N * PITCH_M - 0.05, 0.8), (N * PITCH_M - 0.05, 1.0)],
}


@pytest.mark.parametrize("case", list(EDGE_CASES))
def test_a_person_at_the_edge_or_a_corner_is_tracked_inside_the_carpet(case):
    p = feet(EDGE_CASES[case])
    touched = [(0, slice(None)), (slice(None), 0), (-1, slice(None)), (slice(None), -1)]
    edges = [bool(p[ix].max() > 0) for ix in touched]
    assert any(edges)  # the pressure really touches the border it is meant to
    tracker = SceneTracker(N, N, PITCH_M)
    for i in range(6):
        frame = tracker.update(noisy(p, i), (i + 1) * DT_S)
    assert frame.valid and len(frame.people) == 1
    person = frame.people[0]
    lo, hi = 0.5 * PITCH_M, (N - 0.5) * PITCH_M  # sensel centres: no CoP can lie beyond them
    assert np.isfinite(person.cop_m).all() and ((lo <= person.cop_m) & (person.cop_m <= hi)).all(), person.cop_m
    assert np.isfinite(person.cop_raw_m).all() and ((lo <= person.cop_raw_m) & (person.cop_raw_m <= hi)).all()
    assert person.mask.shape == (N, N) and person.mask[p > 1.0].all()  # the border sensels are theirs
    rows, cols = person.bbox
    assert 0 <= rows.start < rows.stop <= N and 0 <= cols.start < cols.stop <= N
    for (ix, touches) in zip(touched, edges):
        if touches:
            assert person.mask[ix].any()
    true_n = float(p.sum()) * PITCH_M**2 * 1e3
    assert math.isfinite(person.force_raw_n) and abs(person.force_raw_n - true_n) < 0.1 * true_n

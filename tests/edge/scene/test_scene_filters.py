"""Filters: exact fast median, salt removal, force kept, masked fill, one-euro behaviour."""

import numpy as np
from scene_worlds import noisy, render
from scipy import ndimage

from edge.scene import MaskedFill, OneEuroFilter, SceneConfig, SceneTracker, median3x3
from edge.scene.filters import FilterChain, gaussian_kernel, gaussian_with

PITCH = 0.01905
PERSON = {"centre_m": (0.9, 0.8), "heading_rad": 0.4, "mass_kg": 70.0}


def test_fast_median_equals_ndimage():
    rng = np.random.default_rng(0)
    for shape in ((96, 96), (7, 5), (1, 4)):
        p = rng.normal(size=shape).astype(np.float32)
        p[rng.random(shape) < 0.2] = 3.0  # ties
        assert np.array_equal(median3x3(p), ndimage.median_filter(p, size=3, mode="nearest"))


def test_gaussian_with_cached_taps_equals_ndimage():
    """The chain's Gaussian (taps computed once) gives ndimage.gaussian_filter's frame bit for bit."""
    rng = np.random.default_rng(3)
    for sigma in (0.4, 1.05, 2.6):
        p = (rng.random((40, 33)) * 80).astype(np.float32)
        want = ndimage.gaussian_filter(p, sigma, mode="reflect", truncate=3.0)
        got = gaussian_with(p, gaussian_kernel(sigma))
        assert got.dtype == np.float32
        np.testing.assert_array_equal(got, want)


def test_one_euro_scalars_match_the_array_path():
    """Plain floats take a numpy-free path: the same values as a 1-element array, bad samples skipped alike."""
    a, b = OneEuroFilter(1.0, 0.8, 1.0), OneEuroFilter(1.0, 0.8, 1.0)
    rng = np.random.default_rng(5)
    t = 0.0
    for i in range(200):
        t += 1 / 14 if i != 50 else 0.0  # one repeated time
        x = float(700 + 40 * np.sin(i / 9) + rng.normal(0, 5)) if i != 90 else float("nan")
        got, want = a(x, t), b(np.array([x]), t)
        assert isinstance(got, float)
        assert got == float(want[0])
    assert a.skipped == b.skipped == 1


def test_salt_noise_is_removed_and_empty_stays_empty():
    rng = np.random.default_rng(1)
    st = SceneTracker(96, 96, PITCH, SceneConfig(noise_kpa=0.05))
    for i in range(20):
        out = st.update(noisy(np.zeros((96, 96), np.float32), rng, 0.05, salt=30), i / 14)
        assert out.valid and out.empty and out.people == []
    without = SceneTracker(96, 96, PITCH, SceneConfig(noise_kpa=0.05, median_3x3=False, gaussian_sigma_mm=0, min_blob_area_cm2=0))
    out = without.update(noisy(np.zeros((96, 96), np.float32), rng, 0.05, salt=30), 0.0)
    assert not out.empty  # the spikes are contacts when the median is off: the median is what removes them


def test_filter_chain_keeps_total_force():
    rng = np.random.default_rng(2)
    true = render(96, 96, PITCH, [PERSON])
    force_true_n = true.sum() * PITCH**2 * 1e3
    assert abs(force_true_n - 70 * 9.81) / (70 * 9.81) < 0.02
    for cfg in (SceneConfig(noise_kpa=0.05), SceneConfig(noise_kpa=0.05, temporal_median=True, ema_tau_s=0.2)):
        st = SceneTracker(96, 96, PITCH, cfg)
        for i in range(12):
            out = st.update(noisy(true, rng, 0.05, salt=10), i / 14)
        (person,) = out.people
        assert abs(person.force_raw_n - force_true_n) / force_true_n < 0.03
        assert abs(person.force_n - force_true_n) / force_true_n < 0.03


def test_masked_fill_restores_a_dead_row_and_column():
    true = render(96, 96, PITCH, [PERSON])
    rows_hit = np.nonzero(true.any(axis=1))[0]
    bad = np.zeros((96, 96), bool)
    bad[rows_hit[len(rows_hit) // 2], :] = True
    bad[:, 40:42] = True  # two adjacent dead columns
    bad[80:96, 80:96] = True  # a dead block: far sensels are not invented
    corrupted = np.where(bad, np.float32(0), true)
    fill = MaskedFill(bad, PITCH, 0.04)
    filled = fill(corrupted)
    assert abs(filled.sum() - true.sum()) / true.sum() < 0.03
    assert abs(corrupted.sum() - true.sum()) / true.sum() > 0.05  # the fault mattered
    assert np.array_equal(filled[~bad], true[~bad]) and filled[90, 90] == 0.0
    st = SceneTracker(96, 96, PITCH, SceneConfig(noise_kpa=0.05))
    for i in range(4):
        out = st.update(np.where(bad, np.nan, true), i / 14, masks=bad)
    assert out.valid and abs(out.people[0].force_raw_n - true.sum() * PITCH**2 * 1e3) / (70 * 9.81) < 0.04


def test_chain_skips_coarse_median_and_tiny_gaussian():
    fine = FilterChain(0.01905, SceneConfig())
    coarse = FilterChain(0.0381, SceneConfig())
    assert fine.median and fine.gauss and not coarse.median and coarse.gauss
    assert not FilterChain(0.06, SceneConfig()).gauss


def test_one_euro_smooths_still_and_follows_motion():
    rng = np.random.default_rng(3)
    f = OneEuroFilter(min_cutoff_hz=1.0, beta=2.0)
    t = np.arange(200) / 14
    noisy_still = 0.5 + rng.normal(0, 0.01, len(t))
    out = np.array([f(x, ti) for x, ti in zip(noisy_still, t)])
    assert out[50:].std() < 0.6 * noisy_still[50:].std()
    f = OneEuroFilter(min_cutoff_hz=1.0, beta=2.0)
    ramp = np.stack([t * 1.0, np.zeros_like(t)], axis=1)  # 1 m/s
    out = np.array([f(x, ti) for x, ti in zip(ramp, t)])
    lag = ramp[-1, 0] - out[-1, 0]
    slow = OneEuroFilter(min_cutoff_hz=1.0, beta=0.0)
    slow_out = [slow(x, ti) for x, ti in zip(ramp, t)]
    assert 0 <= lag < 0.05 and lag < 0.5 * (ramp[-1, 0] - slow_out[-1][0])


def test_mask_margin_dilation_equals_ndimage():
    """The masks' margin (shifted maxima over the labels' box) grows labels exactly as ndimage.maximum_filter."""
    from edge.scene.pipeline import _grow, _window_max

    rng = np.random.default_rng(2)
    for shape in ((96, 96), (5, 7), (1, 9), (20, 33)):
        for r in (1, 2, 3):
            labels = (rng.random(shape) < 0.05) * rng.integers(1, 5, shape)
            want = ndimage.maximum_filter(labels, size=2 * r + 1)
            np.testing.assert_array_equal(_window_max(labels, r), want)
            np.testing.assert_array_equal(_grow(labels, r), np.where(labels > 0, labels, want))

"""Inverting the sensor model with its true parameters recovers the true pressure."""

from dataclasses import replace

import numpy as np
import pytest
from scipy import ndimage

from sim.sensor import (
    CarpetSensor,
    CrosstalkConfig,
    FrontEndConfig,
    SensorConfig,
    SessionConfig,
    true_pressure_estimate,
)


def smooth_field(shape, seed, lo=0.0, hi=6.0):
    rng = np.random.default_rng(seed)
    f = ndimage.gaussian_filter(rng.standard_normal(shape), 4.0)
    f = (f - f.min()) / (f.max() - f.min())
    return lo + (hi - lo) * f


def feet(shape, kpa=30.0):
    yy, xx = np.mgrid[0 : shape[0], 0 : shape[1]]
    r = shape[0] / 96
    m = (((yy - 40 * r) / (12 * r)) ** 2 + ((xx - 30 * r) / (4 * r)) ** 2 <= 1) | (
        ((yy - 46 * r) / (12 * r)) ** 2 + ((xx - 45 * r) / (4 * r)) ** 2 <= 1
    )
    return np.where(m, kpa, 0.0)


def test_noise_free_16bit_inverse_is_tight():
    # gains, curve, crosstalk and offsets on; noise, smear, dynamics off; 16 bit
    cfg = replace(SensorConfig(frontend=FrontEndConfig(adc_bits=16)).ideal())
    s = CarpetSensor(cfg, seed=1)
    p = smooth_field(s.shape, 1, 0.0, 6.0)
    counts = s.counts(p, 0.0)
    est = true_pressure_estimate(counts, s.params, s.last.state)
    assert est.converged
    assert est.exact.mean() > 0.9
    e = est.exact
    # tolerance: 16-bit quantisation, ≤ 0.1 % + 2 Pa
    np.testing.assert_allclose(est.pressure_kpa[e], p[e], rtol=1e-3, atol=2e-3)


@pytest.mark.parametrize("sign", [1, -1])
def test_full_dynamics_10bit_inverse_within_quantisation(sign):
    # everything but noise: hysteresis, creep, smear, temperature, drift, crosstalk
    cfg = SensorConfig(
        frontend=FrontEndConfig(adc_bits=10, sign=sign),
        session=SessionConfig(temperature_c=28.0, temperature_slope_c_per_h=3.0, drift_lsb10_per_h=5.0),
    )
    cfg = replace(cfg, noise=replace(cfg.noise, white_lsb10=0.0, row_lsb10=0.0))
    assert cfg.noise.smear_fraction > 0 and cfg.dynamics.hysteresis > 0 and cfg.dynamics.creep_per_decade > 0
    s = CarpetSensor(cfg, seed=2)
    base = smooth_field(s.shape, 2, 0.0, 1.0)
    worst = 0.0
    n_checked = 0
    # load up then down: exercises both hysteresis branches and creep
    for k, level in enumerate(list(np.linspace(0, 6, 15)) + list(np.linspace(6, 0.5, 15))):
        p = base * level
        counts = s.counts(p, k * 2.0)
        est = true_pressure_estimate(counts, s.params, s.last.state)
        e = est.exact
        assert e.mean() > 0.8
        err = np.abs(est.pressure_kpa[e] - p[e])
        # tolerance: half a count at 10 bit ≈ 0.02–0.05 kPa over 0–6 kPa; allow 0.06 kPa + 1 %
        assert np.all(err <= 0.06 + 0.01 * p[e]), float(err.max())
        worst = max(worst, float(err.max()))
        n_checked += int(e.sum())
    assert n_checked > 20000


def test_saturated_sensels_are_censored_and_the_rest_exact():
    cfg = replace(SensorConfig(frontend=FrontEndConfig(adc_bits=12)).ideal())
    s = CarpetSensor(cfg, seed=3)
    p = feet(s.shape, 30.0) + 0.5 * smooth_field(s.shape, 3, 0.0, 1.0)
    counts = s.counts(p, 0.0)
    truth = s.last.saturated
    assert truth.sum() > 20  # 30 kPa is well above P_sat ≈ 14 kPa
    est = true_pressure_estimate(counts, s.params, s.last.state)
    # the inverse finds the saturated sensels (within one count of the rail)
    assert np.all(est.saturated[truth])
    assert (est.saturated & ~truth).sum() <= 0.05 * truth.sum()
    # a saturated estimate is a lower bound: never above the truth
    assert np.all(est.pressure_kpa[truth] <= p[truth] + 1e-6)
    # all saturated sensels are at the rail, never beyond
    assert np.all(counts[truth] == s.carpet.rail_counts)
    e = est.exact
    assert e.sum() > 3000
    np.testing.assert_allclose(est.pressure_kpa[e], p[e], rtol=5e-3, atol=0.01)


def test_floating_readout_ghosts_are_inverted():
    cfg = SensorConfig(frontend=FrontEndConfig(adc_bits=16), crosstalk=CrosstalkConfig(readout="floating")).ideal()
    s = CarpetSensor(cfg, seed=4)
    p = np.zeros(s.shape)
    p[10:14, 10:14] = 5.0
    p[10:14, 60:64] = 5.0
    p[50:54, 10:14] = 5.0
    counts = s.counts(p, 0.0)
    est = true_pressure_estimate(counts, s.params, s.last.state)
    assert est.converged
    e = est.exact
    np.testing.assert_allclose(est.pressure_kpa[e], p[e], rtol=2e-3, atol=5e-3)


def test_faulty_sensels_are_not_measurable():
    s = CarpetSensor.random(5, faults=True, fault_rates={k: 1.0 for k in ("dead", "stuck", "mux_bank", "short")})
    counts = s.counts(np.zeros(s.shape), 0.0)
    est = true_pressure_estimate(counts, s.params, s.last.state)
    m = s.fault_masks
    bad = m["dead"] | m["stuck"] | m["mux_bank"] | m["short"]
    assert bad.any()
    assert np.all(np.isnan(est.pressure_kpa[bad]))
    assert not est.exact[bad].any()

"""Temperature, drift, creep and hysteresis move readings the documented way."""


import numpy as np
import pytest

from sim.sensor import (
    CarpetSensor,
    CrosstalkConfig,
    DynamicsConfig,
    FrontEndConfig,
    NoiseConfig,
    SensorConfig,
    SessionConfig,
)

QUIET = NoiseConfig(white_lsb10=0.0, row_lsb10=0.0, smear_fraction=0.0)
NO_X = CrosstalkConfig(line_resistance_ohm=0.0)


def make(session=SessionConfig(), dynamics=None, bits=16, sign=1):
    dyn = dynamics if dynamics is not None else DynamicsConfig(hysteresis=0.0, creep_per_decade=0.0)
    cfg = SensorConfig(frontend=FrontEndConfig(adc_bits=bits, sign=sign), noise=QUIET, crosstalk=NO_X,
                       dynamics=dyn, session=session)
    return CarpetSensor(cfg, seed=0)


def defl(s, p, t):
    c = s.counts(p, t).astype(float)
    return (c - s.carpet.offset_counts) * s.config.frontend.sign  # offset at reference, t = 0


P = np.zeros((96, 96))
P[30:60, 30:60] = 5.0


@pytest.mark.parametrize("sign", [1, -1])
def test_temperature_raises_gain_and_shifts_baseline(sign):
    ref = make(SessionConfig(temperature_c=22.0), sign=sign)
    hot = make(SessionConfig(temperature_c=32.0), sign=sign)
    k = 2.0 ** 6  # 16-bit counts per 10-bit count
    e_ref, e_hot = defl(ref, np.zeros_like(P), 0.0), defl(hot, np.zeros_like(P), 0.0)
    # baseline: +0.3 LSB10/°C toward +counts → +3 LSB10 at +10 °C
    np.testing.assert_allclose((e_hot - e_ref) * sign, 3.0 * k, atol=1.0)
    d_ref = defl(ref, P, 1.0) - e_ref
    d_hot = defl(hot, P, 1.0) - e_hot
    ratio = d_hot[30:60, 30:60] / d_ref[30:60, 30:60]
    # +0.25 %/°C on conductance → +2.5 % of the deflection (toward the rail)
    np.testing.assert_allclose(ratio, 1.025, rtol=2e-3)


def test_drift_and_temperature_slope_within_a_session():
    s = make(SessionConfig(drift_lsb10_per_h=4.0, temperature_slope_c_per_h=2.0))
    k = 2.0 ** 6
    e0 = defl(s, np.zeros_like(P), 0.0)
    e1 = defl(s, np.zeros_like(P), 3600.0)
    # after 1 h: +4 LSB10 drift + 2 °C × 0.3 LSB10/°C
    np.testing.assert_allclose(e1 - e0, (4.0 + 0.6) * k, atol=1.0)
    assert s.temperature_c(3600.0) == pytest.approx(24.0)


def test_creep_under_constant_load_grows_per_decade():
    c = 0.03
    s = make(dynamics=DynamicsConfig(hysteresis=0.0, creep_per_decade=c))
    e = defl(s, np.zeros_like(P), 0.0)  # noise-free baseline
    t, dt = 0.0, 10.0
    first = defl(s, P, t) - e
    series = {}
    while t < 1800.0:
        t += dt
        series[t] = defl(s, P, t)[30:60, 30:60] - e[30:60, 30:60]
    first = first[30:60, 30:60]
    age = 1800.0 - dt  # load age before the last frame
    ok = series[1800.0] < 0.95 * (s.carpet.full_scale - s.carpet.offset_counts[30:60, 30:60])  # off the rail
    assert ok.mean() > 0.95
    np.testing.assert_allclose(series[1800.0][ok] / first[ok], 1 + c * np.log10(1 + age), rtol=2e-3)
    # toward the rail and < 5 % per decade: 180 s → 1800 s
    dec = (series[1800.0] / series[180.0] - 1)[ok]
    assert np.all(dec > 0.02) and np.all(dec < 0.05)
    # unloaded, it recovers
    s.counts(np.zeros_like(P), 2000.0)
    s.counts(np.zeros_like(P), 2200.0)
    again = defl(s, P, 2201.0)[30:60, 30:60] - e[30:60, 30:60]
    np.testing.assert_allclose(again[ok] / first[ok], 1.0, atol=0.002)


def test_hysteresis_unloading_reads_higher_by_at_most_h():
    h = 0.08
    s = make(dynamics=DynamicsConfig(hysteresis=h, creep_per_decade=0.0))
    e = defl(s, np.zeros_like(P), 0.0)[30:60, 30:60]
    up = {}
    down = {}
    levels = np.linspace(0, 8, 9)
    t = 0.0
    for lv in levels:
        t += 0.07
        up[lv] = defl(s, P / 5 * lv, t)[30:60, 30:60] - e
    peak = up[8.0]
    for lv in levels[::-1]:
        t += 0.07
        down[lv] = defl(s, P / 5 * lv, t)[30:60, 30:60] - e
    gaps = np.array([np.median((down[lv] - up[lv]) / peak) for lv in levels[1:-1]])
    assert np.all(gaps > 0)  # the unloading branch lies above
    assert gaps.max() <= h + 1e-3 and gaps.max() > 0.5 * h
    # the memory fades: after a minute unloaded the loading branch is back
    s.counts(np.zeros_like(P), t + 60.0)
    s.counts(np.zeros_like(P), t + 120.0)
    back = defl(s, P / 5 * 4.0, t + 120.1)[30:60, 30:60] - e
    np.testing.assert_allclose(back, up[4.0], rtol=1e-3, atol=2)

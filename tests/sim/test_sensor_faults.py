"""Each fault appears exactly where it was configured."""


import numpy as np
import pytest

from sim.sensor import (
    FAULT_KINDS,
    CarpetSensor,
    CrosstalkConfig,
    FaultConfig,
    FrontEndConfig,
    LineFault,
    MuxBankFault,
    SensorConfig,
    ShortFault,
)


def sensor(faults=FaultConfig(), ideal=True, seed=0, **kw):
    cfg = SensorConfig(faults=faults, **kw)
    return CarpetSensor(cfg.ideal() if ideal else cfg, seed=seed)


def deflection(s, p, t=0.0):
    c = s.counts(p, t).astype(float)
    return (c - s.last.state.offset_counts) * s.config.frontend.sign


def test_masks_are_exactly_the_configured_sensels():
    shape = (96, 96)
    mask = np.ones(shape, bool)
    mask[:20, :20] = False
    f = FaultConfig(
        lines=(LineFault("dead", "row", 10), LineFault("dead", "col", 70, start=40),
               LineFault("half_dead", "col", 5), LineFault("stuck", "col", 33),
               LineFault("noisy", "row", 80)),
        shorts=(ShortFault(60, 50),), mux_banks=(MuxBankFault("col", 16, 16),), mask=mask,
    )
    m = sensor(f).fault_masks
    assert set(m) == set(FAULT_KINDS)
    exp = {k: np.zeros(shape, bool) for k in FAULT_KINDS}
    exp["dead"][10, :] = True
    exp["dead"][40:, 70] = True
    exp["half_dead"][:, 5] = True
    exp["stuck"][:, 33] = True
    exp["noisy"][80, :] = True
    exp["short"][60, 50] = True
    exp["short_lines"][60, :] = True
    exp["short_lines"][:, 50] = True
    exp["mux_bank"][:, 16:32] = True
    exp["outside"] = ~mask
    for k in FAULT_KINDS:
        np.testing.assert_array_equal(m[k], exp[k], err_msg=k)


def test_dead_row_reads_baseline_under_load_and_is_invisible_when_empty():
    s = sensor(FaultConfig(lines=(LineFault("dead", "row", 10),)), ideal=False, seed=1)
    empty = np.stack([s.counts(np.zeros(s.shape), k / 14) for k in range(30)]).astype(float)
    # empty: the dead row is within a count of its neighbours (leakage ≈ 2 counts is all it lacks)
    row_med = np.median(empty, axis=(0, 2))
    assert abs(row_med[10] - np.median(row_med[[9, 11]])) < 4
    load = np.full(s.shape, 5.0)
    loaded = np.stack([s.counts(load, 3 + k / 14) for k in range(10)]).astype(float).mean(0)
    off = s.last.state.offset_counts
    d = (loaded - off) * s.config.frontend.sign
    assert np.all(np.abs(d[10, 1:]) < 3)  # baseline-like under load
    assert abs(d[10, 0]) < 0.04 * abs(d[9, -1]) + 3  # the first sample: 2 % smear of the one before
    assert np.median(d[9]) > 100 and np.median(d[11]) > 100


def test_half_dead_line_responds_with_its_factor():
    f = FaultConfig(lines=(LineFault("half_dead", "col", 40, factor=0.25),))
    cfg_x = dict(crosstalk=CrosstalkConfig(line_resistance_ohm=0.0), frontend=FrontEndConfig(adc_bits=16))
    a, b = sensor(f, **cfg_x), sensor(FaultConfig(), **cfg_x)
    p = np.full(a.shape, 4.0)
    da, db = deflection(a, p), deflection(b, p)
    np.testing.assert_allclose(da[:, 40] / db[:, 40], 0.25, rtol=2e-3)
    np.testing.assert_allclose(da[:, :40], db[:, :40], atol=1)


@pytest.mark.parametrize("sign", [1, -1])
def test_stuck_column_at_the_rail(sign):
    s = sensor(FaultConfig(lines=(LineFault("stuck", "col", 33),)), ideal=False,
               frontend=FrontEndConfig(sign=sign))
    rail = s.carpet.rail_counts
    for k, load in enumerate((0.0, 3.0, 40.0)):
        c = s.counts(np.full(s.shape, load), k / 14)
        assert np.all(c[:, 33] == rail)
        if load == 0.0:
            assert np.all(np.abs(c[:, [32, 34]].astype(int) - 513) < 40)


def test_noisy_line_has_high_temporal_sigma():
    s = sensor(FaultConfig(lines=(LineFault("noisy", "row", 80, noise_lsb10=12.0),)), ideal=False)
    fr = np.stack([s.counts(np.zeros(s.shape), k / 14) for k in range(200)]).astype(float)
    sd = fr.std(axis=0)
    assert np.median(sd[80]) > 10
    assert np.median(np.delete(sd, 80, axis=0)) < 2.0


def test_shorted_crossing_couples_its_row_and_column():
    r0, c0 = 60, 50
    kw = dict(frontend=FrontEndConfig(adc_bits=16), crosstalk=CrosstalkConfig(line_resistance_ohm=200.0))
    shorted = sensor(FaultConfig(shorts=(ShortFault(r0, c0),)), **kw)
    clean = sensor(FaultConfig(), **kw)
    base = np.zeros(shorted.shape)
    base[r0, :] = 3.0  # a light load along the shorted row
    bar = base.copy()
    bar[10:40, c0] = 30.0  # heavy load on the shorted column, away from the row
    others = np.ones(shorted.shape[1], bool)
    others[c0] = False
    for s in (shorted, clean):
        d0, d1 = deflection(s, base, 0.0), deflection(s, bar, 1.0)
        change = (d1[r0, others] - d0[r0, others]) / d0[r0, others]
        if s is clean:
            np.testing.assert_allclose(change, 0.0, atol=1e-3)  # lines independent
        else:
            assert np.all(change < -0.05)  # the column's load depresses the row
    # the crossing itself reads the rail, loaded or not
    assert shorted.counts(np.zeros(shorted.shape), 2.0)[r0, c0] == shorted.carpet.rail_counts


def test_dead_mux_bank_of_16_columns():
    s = sensor(FaultConfig(mux_banks=(MuxBankFault("col", 32, 16),)), ideal=False)
    load = np.full(s.shape, 5.0)
    d = deflection(s, load)
    assert np.all(np.abs(d[:, 32:48]) < 8)
    assert np.median(d[:, 31]) > 100 and np.median(d[:, 48]) > 100
    np.testing.assert_array_equal(s.fault_masks["mux_bank"].any(axis=0), np.isin(np.arange(96), np.arange(32, 48)))


def test_non_rectangular_mask_does_not_respond():
    mask = np.ones((96, 96), bool)
    mask[64:, 64:] = False
    s = sensor(FaultConfig(mask=mask))
    d = deflection(s, np.full(s.shape, 5.0))
    assert np.all(np.abs(d[~mask]) <= 1)
    assert np.all(d[mask] > 50)


def test_floating_readout_ghosts_at_the_fourth_corner():
    p = np.zeros((96, 96))
    for r, c in ((10, 10), (10, 60), (50, 10)):
        p[r : r + 4, c : c + 4] = 30.0
    kw = dict(frontend=FrontEndConfig(adc_bits=12))
    ghosty = sensor(crosstalk=CrosstalkConfig(readout="floating"), **kw)
    plain = sensor(crosstalk=CrosstalkConfig(readout="zero_potential"), **kw)
    e = np.zeros_like(p)
    dg = -deflection(ghosty, e, 0.0) + deflection(ghosty, p, 1.0)  # relative to the empty carpet
    dp = -deflection(plain, e, 0.0) + deflection(plain, p, 1.0)
    real = np.median(dg[10:14, 10:14])
    assert np.median(dg[50:54, 60:64]) > 0.3 * real  # the ghost
    assert np.all(np.abs(dp[50:54, 60:64]) <= 1)  # none without floating lines (leakage × line load: ≤ 1 count)
    assert np.all(np.abs(dg[80:, 80:]) < 1)  # nothing off the pressed lines


def test_random_faults_all_kinds_and_mux_alignment():
    rates = {k: 1.0 for k in ("dead", "half_dead", "stuck", "noisy", "short", "mux_bank", "mask")}
    for seed in range(5):
        s = CarpetSensor.random(seed, faults=True, fault_rates=rates)
        m = s.fault_masks
        for k in FAULT_KINDS:
            assert m[k].any(), (seed, k)
        (bank,) = s.config.faults.mux_banks
        assert bank.size in (8, 16) and bank.start % bank.size == 0
    s = CarpetSensor.random(1, faults=False)
    assert not any(v.any() for v in s.fault_masks.values())

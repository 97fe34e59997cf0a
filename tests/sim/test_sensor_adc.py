"""Rails, sign, bit depth, empty-frame statistics, determinism and grid sizes."""


import numpy as np
import pytest

from sim.sensor import CarpetSensor, FrontEndConfig, GridConfig, SensorConfig


def explicit(bits=10, sign=1, **kw):
    fe = FrontEndConfig(adc_bits=bits, sign=sign, tile_offset_sigma_lsb10=0.0, sensel_offset_sigma_lsb10=0.0)
    return CarpetSensor(SensorConfig(frontend=fe, **kw), seed=0)


@pytest.mark.parametrize("bits", [8, 10, 12, 16])
@pytest.mark.parametrize("sign", [1, -1])
def test_saturation_at_the_rail_never_beyond(bits, sign):
    s = explicit(bits, sign)
    fs = (1 << bits) - 1
    rail = fs if sign > 0 else 0
    empty = s.counts(np.zeros(s.shape), 0.0)
    assert empty.dtype == np.uint16
    assert abs(np.median(empty) - 0.5 * fs) < 0.02 * fs
    for k, load in enumerate((30.0, 1e3, 1e6)):
        c = s.counts(np.full(s.shape, load), 1 + k)
        assert c.dtype == np.uint16 and c.max() <= fs
        # a fully loaded carpet: every line heavily loaded, so crosstalk keeps readings
        # off the rail (line loading), but they move toward it
        assert np.all((c.astype(float) - np.median(empty)) * sign > 0)
    # a single hard press saturates without the lines around it reading beyond range
    p = np.zeros(s.shape)
    p[40:45, 40:45] = 500.0
    c = s.counts(p, 10.0)
    press = np.zeros(s.shape, bool)
    press[40:45, 40:45] = True
    # u → 1 is 1/u(P_sat) ≈ 1.5 × the span: every sensel of normal gain reaches the rail
    # (a weak sensel, gain < ~0.7, may stay short of it: the Hill curve has a ceiling)
    strong = press & (s.carpet.film_gain * s.carpet.tile_gain > 0.8)
    assert strong.sum() > 15
    assert np.all(c[strong] == rail)
    assert np.all(s.last.saturated[strong])
    # the truth's saturation mask and the rail agree (noise moves a sample off the rail
    # by at most a few σ)
    at_rail = c == rail
    assert np.all(s.last.saturated[at_rail & press])
    assert np.all(np.abs(c[press].astype(float) - rail) < 0.5 * fs)
    assert c.max() <= fs


def test_sign_flip_mirrors_the_deflection():
    p = np.zeros((96, 96))
    p[20:40, 30:50] = 6.0
    up, down = explicit(12, 1), explicit(12, -1)
    cu = up.counts(p, 0.0).astype(float)
    cd = down.counts(p, 0.0).astype(float)
    du = cu - up.last.state.offset_counts
    dd = cd - down.last.state.offset_counts
    assert np.all(du[20:40, 30:50] > 100)
    assert np.all(dd[20:40, 30:50] < -100)
    # same magnitude, opposite direction: only noise differs (σ ≈ 1.7 LSB10 = 7 counts at 12 bit)
    assert np.median(np.abs(du + dd)) <= 12
    assert abs(np.median(du + dd)) <= 2


def test_noise_scales_with_bit_depth():
    sd = {}
    for bits in (10, 12, 16):
        s = explicit(bits)
        fr = np.stack([s.counts(np.zeros(s.shape), k / 14) for k in range(100)]).astype(float)
        sd[bits] = np.median(fr.std(axis=0))
    assert sd[12] / sd[10] == pytest.approx(4.0, rel=0.1)
    assert sd[16] / sd[10] == pytest.approx(64.0, rel=0.1)


def test_empty_frame_statistics_match_the_prototype():
    # note: 10-bit prototype, empty median 513 counts, temporal σ 1.6 counts
    s = explicit(10)
    fr = np.stack([s.counts(np.zeros(s.shape), k / 14) for k in range(300)]).astype(float)
    assert abs(np.median(fr) - 513) <= 1
    assert np.median(fr.std(axis=0)) == pytest.approx(1.6, abs=0.15)
    # a random 10-bit carpet: baselines within the note's 500–560
    for seed in range(4):
        r = CarpetSensor.random(seed, adc_bits=10, faults=False)
        med = np.median(r.counts(np.zeros(r.shape), 0.0))
        assert 495 <= med <= 565, (seed, med)


def test_deterministic_for_a_seed():
    p = np.zeros((96, 96))
    p[30:50, 30:40] = 20.0
    def run(seed):
        s = CarpetSensor.random(seed)
        s.start_session(3)
        return np.stack([s.counts(p * (k % 3), k / 14) for k in range(5)])
    a, b, c = run(11), run(11), run(12)
    np.testing.assert_array_equal(a, b)
    assert not np.array_equal(a, c)
    # sessions of one carpet share gains but differ in temperature and noise
    s = CarpetSensor.random(11)
    g = s.carpet.film_gain.copy()
    t0 = s.session.config.temperature_c
    s.start_session(1)
    np.testing.assert_array_equal(g, s.carpet.film_gain)
    assert s.session.config.temperature_c != t0


@pytest.mark.parametrize("n", [48, 32])
def test_smaller_grids(n):
    s = CarpetSensor.random(4, grid=n, faults=True, fault_rates={"mux_bank": 1.0, "dead": 1.0})
    assert s.shape == (n, n)
    assert s.carpet.tile_index.max() == 8  # still 3×3 tiles
    sizes = np.bincount(s.carpet.tile_index.ravel())
    assert sizes.max() - sizes.min() <= 2 * n // 3 + 1
    p = np.zeros((n, n))
    p[n // 4 : n // 2, n // 4 : n // 2] = 20.0
    c = s.counts(p, 0.0)
    assert c.shape == (n, n) and c.dtype == np.uint16
    # the smooth gain field is set in mm: with the same pitch its length in sensels is the same
    g = GridConfig(rows=n, cols=n, pitch_mm=19.05 * 96 / n)
    s2 = CarpetSensor(SensorConfig(grid=g), seed=0)
    assert s2.counts(p, 0.0).shape == (n, n)
    if n == 48:
        assert set(np.bincount(s2.carpet.tile_index.ravel())) == {16 * 16}


def test_bad_inputs_are_refused():
    s = explicit()
    with pytest.raises(ValueError, match="shape"):
        s.counts(np.zeros((10, 10)), 0.0)
    p = np.zeros(s.shape)
    p[0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN"):
        s.counts(p, 0.0)
    s.counts(np.zeros(s.shape), 1.0)
    with pytest.raises(ValueError, match="back"):
        s.counts(np.zeros(s.shape), 0.5)
    with pytest.raises(ValueError, match="adc_bits"):
        FrontEndConfig(adc_bits=11)
    with pytest.raises(ValueError, match="sign"):
        FrontEndConfig(sign=0)

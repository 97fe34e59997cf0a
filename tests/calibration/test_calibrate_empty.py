"""Empty capture hard cases on simulator output: baseline, noise, people and garbage on the carpet."""

import numpy as np
import pytest

from calibration.actor import Actor
from calibration.capture import Capture
from calibration.empty import empty_capture
from calibration.selftest import self_test
from sim.sensor import CarpetSensor, NoiseConfig, SensorConfig


def carpet(seed=3, **kw):
    return CarpetSensor.random(seed, grid=96, faults=False, adc_bits=10, **kw)


def baseline_error(sensor, actor, res):
    true = sensor.expected_empty_counts(actor.t_s + 0.1)
    return np.abs(res.arrays["baseline_counts"] - true)


def test_clean_empty_capture_gives_baseline_and_noise():
    s = carpet()
    a = Actor(s)
    res = empty_capture(a.empty())
    assert res.ok and not res.retry
    err = baseline_error(s, a, res)
    assert np.median(err) < 0.5 and err.max() < 3.0
    true_sigma = np.hypot(s.config.noise.white_lsb10, s.config.noise.row_lsb10)
    assert abs(res.numbers["noise_median_counts"] - true_sigma) < 0.5
    assert (res.arrays["noise_counts"] >= 0.5).all()
    assert res.arrays["fault"].sum() == 0


@pytest.mark.parametrize("intruder", ["standing"])
def test_someone_standing_through_the_baseline_is_asked_to_step_off_with_where(intruder):
    s = carpet()
    a = Actor(s)
    res = empty_capture(a.empty(intruder=intruder))
    assert not res.ok and res.retry
    msg = res.findings[-1]
    assert "step off" in msg and "x = " in msg and "rows" in msg
    blob = res.numbers["people_blobs"][0]
    # the actor stands at x = 0.3·W, y = 0.7·H
    r_mid, c_mid = np.mean(blob["rows"]), np.mean(blob["cols"])
    assert abs(r_mid - 0.7 * 96) < 10 and abs(c_mid - 0.3 * 96) < 10
    # the retry, once they stepped off, is accepted
    assert empty_capture(a.empty()).ok


def test_saturated_sensels_during_baseline_an_object_at_the_rail_is_refused_a_lone_one_masked():
    s = carpet()
    a = Actor(s)
    heavy = np.zeros(s.shape)
    heavy[20:23, 60:63] = 300.0  # a table leg: rail-saturated patch
    cap = a._record("leg", [heavy] * 140)
    res = empty_capture(cap)
    assert not res.ok and "rows 20–22" in res.findings[-1]
    clean = a.empty()
    frames = clean.frames.copy()
    frames[:, 70, 33] = clean.full_scale if s.config.frontend.sign > 0 else 0  # one crossing at the rail
    res = empty_capture(Capture(frames, clean.t_s, a.device))  # a short: masked, not a person
    assert res.ok and res.arrays["fault"][70, 33] and res.arrays["fault"].sum() > 0


@pytest.mark.parametrize("intruder", ["walking", "present80"])
def test_someone_walking_through_or_present_80_percent_leaves_baseline_within_3_counts(intruder):
    s = carpet()
    a = Actor(s)
    res = empty_capture(a.empty(intruder=intruder))
    assert res.ok, res.findings
    err = baseline_error(s, a, res)
    assert err.max() <= 3.0, err.max()
    assert res.numbers["occupied_frame_fraction"] > 0.5
    assert any("baseline uses only the frames" in f for f in res.findings)


def test_nan_constant_and_out_of_range_frames_are_dropped_and_counted():
    s = carpet()
    a = Actor(s)
    cap = a.empty()
    f = cap.frames.copy()
    f[3, 10, 10] = np.nan
    f[7] = 512.0
    f[9, 0, 0] = 5000.0
    f[12] = f[11]
    bad = Capture(f, cap.t_s, cap.device)
    res = empty_capture(bad)
    assert res.ok
    assert res.numbers["frames_dropped"] == 4
    assert baseline_error(s, a, res).max() < 3.0
    st = self_test(bad)
    assert st.numbers["garbage_reasons"] == {"non_finite": 1, "constant": 1, "out_of_range": 1, "duplicate": 1}


def test_too_short_or_too_noisy_empty_capture_is_refused():
    s = carpet()
    a = Actor(s)
    res = empty_capture(a.empty(seconds=3.0))
    assert not res.ok and "at least 5 s" in res.findings[-1]
    cfg = SensorConfig.for_grid(48)
    from dataclasses import replace
    noisy = CarpetSensor(replace(cfg, noise=NoiseConfig(white_lsb10=9.0)), 1)
    res = empty_capture(Actor(noisy).empty())
    assert not res.ok and "too noisy" in res.findings[-1]


def test_self_test_reports_rate_and_lost_frames():
    s = carpet()
    a = Actor(s)
    cap = a.empty()
    keep = np.ones(len(cap.t_s), bool)
    keep[[20, 21, 50]] = False
    lossy = Capture(cap.frames[keep], cap.t_s[keep], cap.device)
    res = self_test(lossy)
    assert res.ok and res.numbers["lost_frames"] == 3 and abs(res.numbers["rate_hz"] - 14) < 0.5
    wrong = Capture(cap.frames[:, :, :90], cap.t_s, cap.device)
    assert not self_test(wrong).ok

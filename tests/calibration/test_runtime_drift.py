"""The drift monitor: each recalibration rule fires once, with a reason an installer can act
on, and re-arms only with hysteresis; on simulator output, temperature drift over a session
is compensated and a line that fails during the run is found and masked."""

from dataclasses import replace
from datetime import datetime, timedelta

import numpy as np
import pytest

from calibration import Applier
from calibration.drift import DriftConfig, DriftMonitor
from calibration.from_truth import calibration_from_truth
from calibration.runtime import CalibratedFrames
from sim.footsteps import FootstepCarpet
from sim.sensor import (
    CarpetSensor,
    CrosstalkConfig,
    DynamicsConfig,
    FrontEndConfig,
    GridConfig,
    SensorConfig,
    SessionConfig,
)


@pytest.fixture(scope="module")
def sensor_cal():
    s = CarpetSensor(replace(SensorConfig.for_grid(32), session=SessionConfig()), 1)
    return s, calibration_from_truth(s, 0.0)


def offsets(cal, global_sigmas, drifted_fraction=0.0, rng=np.random.default_rng(0)):
    sigma = float(np.median(cal.noise_counts))
    off = np.full(cal.shape, global_sigmas * sigma, np.float32) + rng.normal(0, 0.1 * sigma, cal.shape)
    n = int(drifted_fraction * off.size)
    off.ravel()[:n] += 6.0 * cal.noise_counts.ravel()[:n]
    return off


def run_offsets(mon, cal, t0, t1, level, dt=10.0, **kw):
    out = []
    t = t0
    while t < t1:
        out += mon.observe_offsets(t, offsets(cal, level, **kw))
        t += dt
    return out


def test_global_offset_rule_fires_after_10_minutes_once_and_rearms_with_hysteresis(sensor_cal):
    _, cal = sensor_cal
    mon = DriftMonitor(cal)
    assert run_offsets(mon, cal, 0, 590, 3.5) == []  # 3.5 σ, but not yet 10 min
    fired = run_offsets(mon, cal, 590, 3600, 3.5)
    assert [a.kind for a in fired] == ["offset_drift"]
    assert 600 <= fired[0].t_s <= 610 and "recalibrate" in fired[0].reason and "cavatar calibrate" in fired[0].reason
    # hovering between the clear (2 σ) and fire (3 σ) levels: nothing new
    assert run_offsets(mon, cal, 3600, 5400, 2.5) == [] and run_offsets(mon, cal, 5400, 6000, 3.2) == []
    assert run_offsets(mon, cal, 6000, 6100, 1.0) == []  # clears (silently) after a minute below 2 σ
    mon.refresh_active()
    assert ("offset_drift", "offset_drift") not in mon.active
    again = run_offsets(mon, cal, 6100, 7000, -4.0)  # drifts the other way: fires again after 10 min
    assert [a.kind for a in again] == ["offset_drift"] and "-" in again[0].reason


def test_a_short_excursion_does_not_advise(sensor_cal):
    _, cal = sensor_cal
    mon = DriftMonitor(cal)
    out = run_offsets(mon, cal, 0, 500, 5.0) + run_offsets(mon, cal, 500, 520, 0.0) + run_offsets(mon, cal, 520, 1000, 5.0)
    assert out == []  # neither run lasted 10 min


def test_five_percent_of_sensels_drifting_advises(sensor_cal):
    _, cal = sensor_cal
    mon = DriftMonitor(cal)
    assert run_offsets(mon, cal, 0, 600, 0.0, drifted_fraction=0.04) == []
    fired = run_offsets(mon, cal, 600, 2000, 0.0, drifted_fraction=0.08)
    assert [a.kind for a in fired] == ["sensel_drift"] and "8 %" in fired[0].reason


def test_known_users_weight_off_by_more_than_15_percent(sensor_cal):
    _, cal = sensor_cal
    mon = DriftMonitor(cal)
    assert mon.report_weight("Ana", 80.0, 70.0, 1.0) == []  # one report is not enough
    assert mon.report_weight("Ana", 71.0, 70.0, 2.0) == []
    assert mon.report_weight("Ana", 82.0, 70.0, 3.0) == []  # median of 3: +14 %
    fired = mon.report_weight("Ana", 83.0, 70.0, 4.0)  # median of the last 3: +17 %
    assert [a.kind for a in fired] == ["weight"] and "Ana" in fired[0].reason and "70 kg" in fired[0].reason
    assert all(mon.report_weight("Ana", 84.0, 70.0, 5.0 + i) == [] for i in range(10))  # said once
    # a saturated (censored) reading is a lower bound: reading low is no evidence
    assert all(mon.report_weight("Ben", 50.0, 80.0, 10.0 + i, censored=True) == [] for i in range(5))
    assert [a.key for a in mon.report_weight("Ben", 40.0, 80.0, 20.0) + mon.report_weight("Ben", 40.0, 80.0, 21.0)
            + mon.report_weight("Ben", 40.0, 80.0, 22.0)] == ["Ben"]


def test_an_old_calibration_is_reported_once(sensor_cal):
    _, cal = sensor_cal
    now = datetime.fromisoformat(cal.created) + timedelta(days=200)
    step = CalibratedFrames(cal, clock=lambda: now)
    rng = np.random.default_rng(0)
    base = np.rint(cal.baseline_counts).astype(np.uint16)
    advice = []
    for k in range(60):
        advice += step.process(base + rng.integers(0, 2, base.shape, dtype=np.uint16), float(k) * 5).advice
    assert [a.kind for a in advice] == ["age"] and "200 days" in advice[0].reason
    young = CalibratedFrames(cal, clock=lambda: datetime.fromisoformat(cal.created) + timedelta(days=3))
    assert young.process(base + 1, 1.0).advice == []


def test_drift_config_rejects_unknown_keys():
    with pytest.raises(ValueError, match="unknown drift option.*accepted"):
        DriftConfig.from_dict({"offset_sigma": 3})
    assert "offset_hold_s" in DriftConfig.describe()


def lying_person(shape, pitch_m, mass_kg=70.0):
    r, c = np.mgrid[0:shape[0], 0:shape[1]] * pitch_m
    inside = ((r - 0.9) / 0.55) ** 2 + ((c - 0.8) / 0.11) ** 2 <= 1.0
    p = inside.astype(float)
    return p * mass_kg * 9.81 / (p.sum() * pitch_m**2) / 1e3


def test_temperature_drift_over_a_session_is_compensated_and_advised_at_10_degrees():
    # +20 °C/h for 45 min (+15 °C), no creep/hysteresis so that temperature is the only effect
    cfg = replace(SensorConfig(grid=GridConfig(48, 48, pitch_mm=38.1)), session=SessionConfig(temperature_slope_c_per_h=20.0),
                  dynamics=DynamicsConfig(hysteresis=0.0, creep_per_decade=0.0),
                  crosstalk=CrosstalkConfig(line_resistance_ohm=0.0))
    s = CarpetSensor(cfg, 2)
    cal = calibration_from_truth(s, 0.0)
    with_t = CalibratedFrames(cal)
    without_t = CalibratedFrames(cal)
    pitch_m = cfg.grid.pitch_mm * 1e-3
    body = lying_person(s.shape, pitch_m)
    advice, t = [], 0.0
    for k in range(540):  # 45 min, a frame every 5 s; STATUS temperature with every frame
        t += 5.0
        c = s.counts(body, t)
        out = with_t.process(c, t, s.temperature_c(t))
        advice += out.advice
        plain = without_t.process(c, t).pressure_kpa
    force = lambda p: float(p.sum()) * pitch_m**2 * 1e3  # noqa: E731
    ref = force(Applier(calibration_from_truth(s, t)).apply(c, s.temperature_c(t)).pressure_kpa)  # truth at T_end
    assert s.temperature_c(t) - cal.temperature_c == pytest.approx(15.0)
    assert abs(force(out.pressure_kpa) / ref - 1) < 0.01
    assert force(plain) / ref - 1 > 0.03  # uncompensated: +0.25 %/°C × 15 °C
    temp = [a for a in advice if a.kind == "temperature"]
    assert len(temp) == 1 and "°C" in temp[0].reason
    assert s.temperature_c(temp[0].t_s) - cal.temperature_c >= 10.0
    assert s.temperature_c(temp[0].t_s) - cal.temperature_c < 11.0  # soon after crossing 10 °C (30 s hold)


@pytest.mark.parametrize("sign, bits", [(1, 10), (-1, 12)])
def test_a_column_stuck_during_the_run_is_advised_once_and_masked(sign, bits):
    s = CarpetSensor(replace(SensorConfig.for_grid(48), frontend=FrontEndConfig(adc_bits=bits, sign=sign)), 4)
    cal = calibration_from_truth(s, 0.0)
    step = CalibratedFrames(cal)
    empty = np.zeros(s.shape)
    rail = cal.full_scale if cal.device["sign"] > 0 else 0
    advice = []
    for k in range(1, 181):
        t = float(k)
        c = s.counts(empty, t)
        if t > 60:  # the column-17 input channel fails after a minute
            c[:, 17] = rail
        out = step.process(c, t)
        advice += out.advice
    assert [(a.kind, a.key) for a in advice] == [("line_failed", "col 17")]
    assert 90 <= advice[0].t_s <= 95 and "masked" in advice[0].reason
    assert out.masked[:, 17].all() and not out.masked[:, 16].any()
    assert (out.pressure_kpa[:, 17] == 0).all() and not out.saturated.any()


def test_a_row_broken_during_a_walk_is_found():
    s = CarpetSensor(SensorConfig(), 6)
    cal = calibration_from_truth(s, 0.0)
    step = CalibratedFrames(cal, drift=DriftConfig(activity_window_s=120.0))
    world = FootstepCarpet(96, 96, people=2, seed=3)
    advice = []
    for k in range(1, 301):  # 150 s of two people walking, a frame every 0.5 s
        idx = 7 * k
        world(idx)
        if k == 40:
            s.carpet.line_factor[50, :] = 0.0  # the row-50 thread breaks (no current from now on)
        out = step.process(s.counts(world.pressure_kpa(), idx / 14.0), idx / 14.0)
        advice += out.advice
    kinds = [(a.kind, a.key) for a in advice]
    assert ("line_failed", "row 50") in kinds
    assert all(kind != "line_failed" or key == "row 50" for kind, key in kinds)  # no other line blamed
    assert out.masked[50].all()


@pytest.mark.parametrize("seed", [3, 11])
def test_faults_known_at_calibration_are_not_reported_again(seed):
    # random 48×48 carpets with dead, stuck, noisy lines and a dead mux bank, all in the calibration
    s = CarpetSensor.random(seed, grid=48, fault_rates={"stuck": 0.5, "dead": 0.5, "mux_bank": 0.3, "noisy": 0.5})
    assert len(s.config.faults.lines) >= 2
    step = CalibratedFrames(calibration_from_truth(s, 0.0))
    world = FootstepCarpet(48, 48, people=1, seed=seed, pitch_mm=38.1)
    advice, t = [], 0.0
    for k in range(60):
        t += 2.0
        advice += step.process(s.counts(np.zeros(s.shape), t), t, s.temperature_c(t)).advice
    for k in range(1, 300):
        world(7 * k)
        tt = t + k / 2.0
        advice += step.process(s.counts(world.pressure_kpa(), tt), tt, s.temperature_c(tt)).advice
    assert advice == []

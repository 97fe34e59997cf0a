"""Runtime baseline tracking on simulator output: drift followed on an empty carpet, never
under people (walking or lying still for 30 min with creep). Accelerated time: one frame
every 0.5–5 s instead of 14 Hz."""

from dataclasses import replace

import numpy as np
from scipy import ndimage

from calibration import Applier
from calibration.from_truth import calibration_from_truth
from calibration.runtime import BaselineConfig, CalibratedFrames
from sim.footsteps import FootstepCarpet
from sim.sensor import CarpetSensor, CrosstalkConfig, FrontEndConfig, SensorConfig, SessionConfig

PITCH_M = 0.01905


def sensor_with(session: SessionConfig, seed: int = 3, **over) -> CarpetSensor:
    return CarpetSensor(replace(SensorConfig(), session=session, **over), seed)


def lying_person(shape=(96, 96), mass_kg=70.0, centre=(48, 40)) -> np.ndarray:
    """A person lying along the rows: a smooth 1.1 m × 0.22 m patch carrying their weight (≈ 3.5 kPa)."""
    r, c = np.mgrid[0:shape[0], 0:shape[1]] * PITCH_M
    inside = ((r - centre[0] * PITCH_M) / 0.55) ** 2 + ((c - centre[1] * PITCH_M) / 0.11) ** 2 <= 1.0
    p = ndimage.gaussian_filter(inside.astype(float), 1.0)
    return p * mass_kg * 9.81 / (p.sum() * PITCH_M**2) / 1e3


def force_n(p_kpa: np.ndarray) -> float:
    return float(p_kpa.sum(dtype=np.float64)) * PITCH_M**2 * 1e3


def test_baseline_drift_on_an_empty_carpet_is_tracked_to_a_count():
    # board drift 20 LSB/h with per-tile spread and 4 °C/h of offset tempco: ~10 counts in 30 min
    s = sensor_with(SessionConfig(drift_lsb10_per_h=-20.0, tile_drift_sigma_lsb10_per_h=3.0,
                                  temperature_slope_c_per_h=4.0), frontend=FrontEndConfig(sign=-1))
    cal = calibration_from_truth(s, 0.0)
    step = CalibratedFrames(cal)
    empty = np.zeros(s.shape)
    for k in range(1, 601):  # 30 min, a frame every 3 s
        t = 3.0 * k
        counts = s.counts(empty, t)
        out = step.process(counts, t, s.temperature_c(t))
        assert out.valid
    truth = s.expected_empty_counts(1800.0)
    err = np.abs(step.tracker.baseline_counts - truth)[cal.usable]
    static = np.abs(cal.baseline_counts - truth)[cal.usable]
    assert np.median(static) > 8.0  # the drift was real
    assert np.median(err) < 0.5 and np.percentile(err, 99) < 1.0
    p, _, _, _ = out
    assert force_n(p) < 5.0  # an empty carpet stays empty ...
    assert force_n(Applier(cal).apply(counts, s.temperature_c(t)).pressure_kpa) > 50.0  # ... the static baseline does not


def test_slow_baseline_is_not_updated_under_people_walking():
    s = sensor_with(SessionConfig(), seed=5)
    cal = calibration_from_truth(s, 0.0)
    step = CalibratedFrames(cal)
    naive = CalibratedFrames(cal, baseline=BaselineConfig(holdoff_s=0.0, neighbour_mm=0.0, contact_sigmas=1e6))
    world = FootstepCarpet(96, 96, people=2, seed=11)
    touched = np.zeros(s.shape, bool)
    for k in range(1, 241):  # 2 min of two people walking, a frame every 0.5 s
        idx = 7 * k
        world(idx)
        p = world.pressure_kpa()
        touched |= p > 0
        t = idx / 14.0
        counts = s.counts(p, t)
        step.process(counts, t)
        naive.process(counts.copy(), t)
    truth = s.expected_empty_counts(t)
    assert touched.mean() > 0.4  # they covered a good part of the carpet
    free_now = ~ndimage.binary_dilation(p > 0, iterations=4) & cal.usable
    err = np.abs(step.tracker.baseline_counts - truth)
    err_naive = np.abs(naive.tracker.baseline_counts - truth)
    # where people walked (and nobody stands now) the baseline is still the empty reading
    assert np.percentile(err[touched & free_now], 99) < 0.5 and err[touched & free_now].max() < 1.0
    assert np.percentile(err_naive[touched & free_now], 99) > 5.0  # ungated tracking is pulled up by footsteps
    assert step.tracker.counters["steps"] == 0


def test_a_person_lying_still_for_30_minutes_is_not_eaten_by_the_baseline():
    s = sensor_with(SessionConfig(drift_lsb10_per_h=4.0), seed=7,
                    crosstalk=CrosstalkConfig(line_resistance_ohm=0.0))
    assert s.config.dynamics.creep_per_decade > 0
    cal = calibration_from_truth(s, 0.0)
    step = CalibratedFrames(cal)
    naive = CalibratedFrames(cal, baseline=BaselineConfig(holdoff_s=0.0, neighbour_mm=0.0, contact_sigmas=1e6,
                                                          tau_s=300.0))
    body = lying_person()
    empty = np.zeros(s.shape)
    t = 0.0
    for k in range(60):  # a minute of empty carpet
        t += 1.0
        c = s.counts(empty, t)
        step.process(c, t)
        naive.process(c, t)
    first = None
    for k in range(360):  # 30 min lying still, a frame every 5 s
        t += 5.0
        c = s.counts(body, t)
        p = step.process(c, t).pressure_kpa
        pn = naive.process(c, t).pressure_kpa
        if first is None:
            first = force_n(p)
    # reference: the same frame through the true baseline of this moment (creep included)
    ref = Applier(calibration_from_truth(s, t)).apply(c).pressure_kpa
    assert abs(force_n(p) / force_n(ref) - 1.0) < 0.03
    assert force_n(p) >= 0.98 * first  # creep raises the reading; it is never tracked away
    assert force_n(pn) < 0.5 * force_n(ref)  # the test has teeth: ungated tracking eats the person


def test_an_offset_step_of_one_tile_is_followed_at_once_and_a_person_elsewhere_kept():
    s = sensor_with(SessionConfig(), seed=9, crosstalk=CrosstalkConfig(line_resistance_ohm=0.0))
    cal = calibration_from_truth(s, 0.0)
    step = CalibratedFrames(cal)
    body = lying_person(centre=(48, 80))  # in the right-hand tiles
    jump = 12  # counts, the middle-left tile (rows 32–63, cols 0–31), e.g. its front end re-biased
    t = 0.0
    for k in range(40):
        t += 1.0
        c = s.counts(body, t).astype(np.int32)
        if k >= 10:
            c[32:64, 0:32] += jump
        out = step.process(np.clip(c, 0, cal.full_scale).astype(np.uint16), t)
    assert step.tracker.counters["steps"] >= 1
    p = out.pressure_kpa
    assert force_n(p[32:64, 0:32]) < 2.0  # no phantom load where the tile jumped
    ref = Applier(calibration_from_truth(s, t)).apply(s.counts(body, t + 1.0)).pressure_kpa
    assert abs(force_n(p) / force_n(ref) - 1.0) < 0.03

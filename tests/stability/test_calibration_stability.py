"""Calibration on hard inputs: bad gains in the file, frames at the rail, constant frames, one live
sensel, codes beyond the ADC range. Whatever comes in, what goes out is finite and ≥ 0 kPa.

Documented behaviour (docs/stability.md): a gain ≤ 0 on a usable sensel, or NaN/∞ in any
per-sensel array, is refused when the Calibration is built or loaded (CalibrationError naming
how many); codes beyond the ADC range read as the rail they passed (Applier) or reject the
frame (CalibratedFrames); an all-rail second is never mistaken for an offset step.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from calibration import FAULT, Applier, Calibration, CalibrationError
from calibration.from_truth import calibration_from_truth
from calibration.runtime import CalibratedFrames
from sim.sensor import CarpetSensor, SensorConfig

RATE_HZ = 14.0


@pytest.fixture(autouse=True)
def numpy_warnings_are_errors():
    """An overflow or invalid-value warning is a NaN/∞ in the making: fail on it."""
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        yield


@pytest.fixture
def carpet():
    """A fresh simulated 32×32 carpet (its sensor keeps time: one per test) and its calibration."""
    sensor = CarpetSensor(SensorConfig.for_grid(32), 2)
    return sensor, calibration_from_truth(sensor, 0.0, device_id="carpet-s")


def with_arrays(cal: Calibration, **arrays) -> Calibration:
    """A copy of ``cal`` with some per-sensel arrays replaced (built through the constructor)."""
    fields = {k: v for k, v in cal.__dict__.items()}
    fields.update(arrays)
    return Calibration(**fields)


def rail_of(cal: Calibration) -> int:
    return 0 if cal.device["sign"] < 0 else cal.full_scale


def assert_sane(pressure_kpa: np.ndarray, cal: Calibration) -> None:
    assert pressure_kpa.dtype == np.float32
    assert np.isfinite(pressure_kpa).all()
    assert pressure_kpa.min() >= 0.0 and pressure_kpa.max() <= cal.curve.saturation_kpa


# ------------------------------------------------------------------ the file


@pytest.mark.parametrize("bad_gain", [0.0, -0.7])
def test_zero_or_negative_gain_on_usable_sensels_is_refused_naming_the_count(carpet, bad_gain):
    _, cal = carpet
    gain = cal.gain.copy()
    gain[3, 4] = gain[10, 11] = gain[20, 0] = bad_gain
    with pytest.raises(CalibrationError, match=r"gain is zero or negative at 3 usable sensel\(s\) \(first at row 3, col 4\)"):
        with_arrays(cal, gain=gain)


def test_a_saved_file_with_a_zero_gain_is_refused_at_load(carpet, tmp_path):
    _, cal = carpet
    broken = with_arrays(cal, gain=cal.gain.copy())
    broken.gain[5, 5] = 0.0  # edited after construction: save does not look, load must
    broken.save(tmp_path / "cal.npz")  # the hash is right: only the value is wrong
    with pytest.raises(CalibrationError, match=r"cal\.npz: calibration gain is zero or negative at 1 usable sensel"):
        Calibration.load(tmp_path / "cal.npz")


def test_zero_or_negative_gain_on_a_masked_sensel_is_accepted_and_reads_zero(carpet):
    sensor, cal = carpet
    gain, fault = cal.gain.copy(), cal.fault.copy()
    gain[3, 4], gain[3, 5] = 0.0, -2.0
    fault[3, 4] = fault[3, 5] = FAULT["dead"]
    ok = with_arrays(cal, gain=gain, fault=fault)
    press = np.zeros(sensor.shape)
    press[2:6, 2:8] = 8.0
    out = Applier(ok).apply(sensor.counts(press, 0.0))
    assert_sane(out.pressure_kpa, ok)
    assert out.masked[3, 4] and out.masked[3, 5] and (out.pressure_kpa[3, 4:6] == 0).all()
    assert out.pressure_kpa[2, 2] > 4.0  # its neighbours still read the load


@pytest.mark.parametrize("name", ["gain", "baseline_counts", "noise_counts"])
def test_nan_or_inf_in_any_per_sensel_array_is_refused(carpet, name):
    _, cal = carpet
    arr = getattr(cal, name).copy()
    arr[0, 1], arr[7, 7] = np.nan, np.inf
    with pytest.raises(CalibrationError, match=rf"calibration {name} has 2 NaN/∞ value\(s\) \(first at row 0, col 1\)"):
        with_arrays(cal, **{name: arr})


# ------------------------------------------------------------------ Applier on hard frames


@pytest.mark.parametrize("sign", [-1, 1])
def test_all_saturated_frame_reads_saturation_everywhere(carpet, sign):
    _, cal = carpet
    cal = with_arrays(cal, device={**cal.device, "sign": sign})
    out = Applier(cal).apply(np.full(cal.shape, rail_of(cal), np.uint16))
    assert_sane(out.pressure_kpa, cal)
    assert out.saturated[cal.usable].all()
    assert (out.pressure_kpa[cal.usable] == cal.curve.saturation_kpa).all()


@pytest.mark.parametrize("value", [-5000, 65535, 1e30, -1e30])
@pytest.mark.parametrize("sign", [-1, 1])
def test_codes_beyond_the_adc_range_read_as_the_rail_they_passed(carpet, sign, value):
    _, cal = carpet
    cal = with_arrays(cal, device={**cal.device, "sign": sign})
    out = Applier(cal).apply(np.full(cal.shape, value))
    assert_sane(out.pressure_kpa, cal)
    toward_pressure = (value > cal.full_scale) == (sign > 0)
    expected = cal.curve.saturation_kpa if toward_pressure else 0.0
    assert (out.pressure_kpa[cal.usable] == expected).all()


def test_constant_frame_reads_finite_and_non_negative(carpet):
    _, cal = carpet
    for value in (0, 1, cal.full_scale // 2, cal.full_scale):
        assert_sane(Applier(cal).apply(np.full(cal.shape, value, np.uint16)).pressure_kpa, cal)


def test_a_light_touch_on_lines_shared_with_a_railed_half_is_not_called_saturated():
    """The crosstalk inverse used to diverge on heavily loaded lines (1e8 after six iterations) and
    pushed every sensel on them to saturation; capped at r = 1 it stays a reading."""
    sensor = CarpetSensor(SensorConfig.for_grid(96), 2)
    cal = calibration_from_truth(sensor, 0.0, device_id="carpet-96")
    press = np.zeros(sensor.shape)
    press[64, 3] = 1.0
    counts = sensor.counts(press, 0.0).astype(np.float64)
    counts[:48] = rail_of(cal)  # the upper half at the rail: column 3 is loaded by 48 railed sensels
    out = Applier(cal).apply(counts)
    assert_sane(out.pressure_kpa, cal)
    assert not out.saturated[64, 3]
    assert 0.5 < out.pressure_kpa[64, 3] < 2.0


# ------------------------------------------------------------------ CalibratedFrames over time


def test_frames_exactly_at_the_rail_or_constant_are_rejected_and_counted(carpet):
    _, cal = carpet
    step = CalibratedFrames(cal)
    for i, value in enumerate((rail_of(cal), 0, cal.full_scale, 500)):
        out = step.process(np.full(cal.shape, value, np.uint16), (i + 1) / RATE_HZ)
        assert out.rejected == "constant" and out.pressure_kpa is None
    assert step.counters["rejected_constant"] == 4 and step.counters["valid"] == 0


def test_codes_beyond_the_adc_range_reject_the_frame_and_are_counted(carpet):
    sensor, cal = carpet
    step = CalibratedFrames(cal)
    good = sensor.counts(np.zeros(sensor.shape), 0.0)
    for i, value in enumerate((cal.full_scale + 1, 65535, -1)):
        frame = good.astype(np.int64)
        frame[4, 4] = value
        assert step.process(frame, (i + 1) / RATE_HZ).rejected == "out_of_range"
    assert step.counters["rejected_out_of_range"] == 3


def test_seconds_of_saturated_frames_do_not_become_the_baseline(carpet):
    """An all-rail second looked like an offset step (a whole tile 'in contact' by the same amount):
    the tracker moved the baseline to the rail and the carpet then read empty for many minutes."""
    sensor, cal = carpet
    step = CalibratedFrames(cal)
    rng = np.random.default_rng(1)
    rail, inward = rail_of(cal), -int(cal.device["sign"])
    t = 0.0
    for _ in range(int(5 * RATE_HZ)):  # five seconds at the rail, a count of noise (so not "constant")
        t += 1 / RATE_HZ
        out = step.process((rail + inward * rng.integers(0, 2, cal.shape)).astype(np.uint16), t)
        assert out.valid
        assert_sane(out.pressure_kpa, cal)
        assert out.saturated[cal.usable].mean() > 0.99
    assert step.counters["baseline_steps"] == 0
    press = np.zeros(sensor.shape)
    press[10:14, 10:14] = 8.0
    for _ in range(3):
        t += 1 / RATE_HZ
        out = step.process(sensor.counts(press, t), t)
    assert_sane(out.pressure_kpa, cal)
    assert abs(float(out.pressure_kpa[10:14, 10:14].mean()) - 8.0) < 1.5  # the load still reads


def test_a_single_live_sensel_reads_its_load_for_seconds(carpet):
    """One usable sensel cannot be 'constant' (every frame was rejected) nor an offset step."""
    sensor, cal = carpet
    fault = np.full(cal.shape, FAULT["dead"], np.uint8)
    fault[5, 7] = 0
    one = with_arrays(cal, fault=fault)
    step = CalibratedFrames(one)
    press = np.zeros(sensor.shape)
    press[4:7, 6:9] = 8.0
    t, readings = 0.0, []
    for _ in range(int(4 * RATE_HZ)):
        t += 1 / RATE_HZ
        out = step.process(sensor.counts(press, t), t)
        assert out.valid, out.rejected
        assert_sane(out.pressure_kpa, one)
        assert out.masked.sum() == out.masked.size - 1 and (out.pressure_kpa[out.masked] == 0).all()
        readings.append(float(out.pressure_kpa[5, 7]))
    assert step.counters["baseline_steps"] == 0
    assert abs(np.mean(readings[-14:]) - 8.0) < 1.5  # still the load after 4 s of baseline updates

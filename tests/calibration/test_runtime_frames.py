"""The runtime step's frame handling: garbage never crashes and is counted; a calibration from
another carpet is refused; the result unpacks as (pressure_kpa, saturated, masked, advice)."""

import numpy as np
import pytest

from calibration import CalibrationError
from calibration.from_truth import calibration_from_truth, device_info
from calibration.runtime import REJECT_REASONS, BaselineConfig, CalibratedFrames, status_temperature_c
from firmware_protocol import codec
from sim.sensor import CarpetSensor, FrameStream, SensorConfig, StreamConfig


@pytest.fixture
def carpet():
    s = CarpetSensor(SensorConfig.for_grid(32), 2)
    return s, calibration_from_truth(s, 0.0, device_id="carpet-07")


def test_nan_inf_out_of_range_constant_and_bad_time_frames_are_rejected_and_counted(carpet):
    s, cal = carpet
    step = CalibratedFrames(cal)
    good = s.counts(np.zeros(s.shape), 0.0)
    nan = good.astype(np.float64)
    nan[:10] = np.nan
    inf = good.astype(np.float32)
    inf[3, 4] = np.inf
    few_nan = good.astype(np.float64)
    few_nan[5, 5] = np.nan  # one sensel (< 1 %): masked for this frame, the frame is kept
    high = good.copy()
    high[0, 0] = cal.full_scale + 1
    negative = good.astype(np.int32)
    negative[1, 1] = -3
    frames = [(nan, "non_finite"), (inf, None), (few_nan, None), (high, "out_of_range"), (negative, "out_of_range"),
              (np.full(s.shape, 517, np.uint16), "constant"), (np.zeros(s.shape, np.uint16), "constant"),
              (np.zeros((31, 32), np.uint16), "shape_mismatch"), ("garbage", "not_an_array"),
              (np.zeros(s.shape, bool), "not_an_array")]
    t = 0.0
    for frame, reason in frames:
        t += 1.0
        out = step.process(frame, t)
        assert out.rejected == reason
        if reason is None:
            p, sat, masked, advice = out
            assert np.isfinite(p).all() and masked[~np.isfinite(frame)].all()
            assert (p[~np.isfinite(frame)] == 0).all()
        else:
            assert out.pressure_kpa is None and not out.valid
    assert step.process(good, 3.0).rejected == "time_not_increasing"  # the last valid frame was at 3 s
    assert step.process(good, float("nan")).rejected == "bad_time"
    assert step.process(good, None).rejected == "bad_time"
    c = step.counters
    assert c["frames"] == len(frames) + 3 and c["valid"] == 2
    assert {r: c[f"rejected_{r}"] for r in REJECT_REASONS} == {
        "not_an_array": 2, "shape_mismatch": 1, "bad_time": 2, "time_not_increasing": 1, "non_finite": 1,
        "out_of_range": 2, "constant": 2}
    # the baseline was not disturbed by any of it
    assert np.abs(step.tracker.baseline_counts - cal.baseline_counts).max() < 3 * cal.noise_counts.max()


def test_a_stream_with_garbage_torn_and_duplicated_frames_never_crashes(carpet):
    s, cal = carpet
    step = CalibratedFrames(cal, baseline=BaselineConfig(update_interval_s=0.5))
    stream = FrameStream(s, StreamConfig(drop_rate=0.05, duplicate_rate=0.05, tear_rate=0.05, corrupt_rate=0.1))
    rng = np.random.default_rng(0)
    pressure = []
    for k in range(300):
        p = np.zeros(s.shape)
        if k % 50 < 25:
            r, c = rng.integers(4, 28, 2)
            p[r - 3:r + 3, c - 2:c + 2] = 20.0
        pressure.append(p)
    n = 0
    for counts, t_s, flags in stream.frames(pressure):
        out = step.process(counts, t_s)
        n += 1
        assert out.valid or out.rejected in REJECT_REASONS
    assert step.counters["frames"] == n
    assert step.counters["rejected_constant"] + step.counters["rejected_out_of_range"] > 0
    assert step.counters["rejected_time_not_increasing"] > 0  # the duplicates


def test_bad_temperatures_are_ignored_and_counted(carpet):
    s, cal = carpet
    step = CalibratedFrames(cal)
    frame = s.counts(np.zeros(s.shape), 0.0)
    for t, temp in ((1.0, float("nan")), (2.0, 500.0), (3.0, "warm")):
        assert step.process(frame, t, temp).valid
    assert step.counters["bad_temperature"] == 3 and step.temperature_c is None
    step.process(frame, 4.0, 25.5)
    assert step.temperature_c == 25.5
    step.process(frame, 5.0)  # no new STATUS: the last temperature holds
    assert step.temperature_c == 25.5
    status = codec.PACKET_CLASSES["STATUS"](1, 0, 0, 0, 0, 0, 0, 0, 0, 2345, 0)
    assert status_temperature_c(status) == pytest.approx(23.45)
    assert status_temperature_c(status.__class__(1, 0, 0, 0, 0, 0, 0, 0, 0, -32768, 0)) is None


def test_a_calibration_from_another_carpet_is_refused(carpet):
    _, cal = carpet
    CalibratedFrames(cal, device_info(cal, fw_patch=9))  # the right carpet (a patch release) is accepted
    info = codec.Info(0, codec.PROTOCOL_VERSION, codec.DEFINITION_HASH, 1, 0, 0, "carpet-08", 32, 32, 1, 1,
                      cal.device["adc_bits"], 0, cal.device["sign"], 14000, 1)
    with pytest.raises(CalibrationError, match="device_id 'carpet-07' in the file, 'carpet-08' on the device"):
        CalibratedFrames(cal, info)
    with pytest.raises(CalibrationError, match="rows 32 in the file, 96 on the device.*cavatar calibrate"):
        CalibratedFrames(cal, device_info(cal, rows=96, cols=96))


def test_baseline_config_is_typed_and_rejects_unknown_keys():
    assert BaselineConfig.from_dict({"tau_s": 120, "blocks": [2, 2]}).blocks == (2, 2)
    with pytest.raises(ValueError, match="unknown baseline option.*accepted"):
        BaselineConfig.from_dict({"tau": 120})
    with pytest.raises(ValueError, match="tau_s must be > 0"):
        BaselineConfig(tau_s=0.0)
    assert "holdoff_s" in BaselineConfig.describe()

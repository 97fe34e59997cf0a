"""The calibration file (hash, device checks) and the runtime apply (counts → kPa)."""

from types import SimpleNamespace

import numpy as np
import pytest

from calibration import FAULT, Applier, Calibration, CalibrationError, Curve


def make_cal(rows=6, cols=5, sign=-1, bits=12, **kw):
    rng = np.random.default_rng(0)
    return Calibration(
        baseline_counts=2048 + rng.normal(0, 5, (rows, cols)), noise_counts=np.full((rows, cols), 1.5),
        gain=rng.uniform(0.8, 1.25, (rows, cols)), fault=np.zeros((rows, cols), np.uint8),
        device={"device_id": "carpet-01", "rows": rows, "cols": cols, "adc_bits": bits, "sign": sign,
                "firmware": [1, 0, 0], "protocol_version": 1},
        pitch_m=0.01905, curve=Curve(8.0, 1.2, 1800.0, 14.0), temperature_c=22.0, **kw)


def info(**over):
    base = dict(device_id="carpet-01", rows=6, cols=5, adc_bits=12, sign=-1, fw_major=1, fw_minor=0, fw_patch=3)
    return SimpleNamespace(**{**base, **over})


def forward(cal, p_kpa):
    """Counts a sensel following the calibration's own model would read (no noise)."""
    r = cal.curve.response(p_kpa)
    return cal.baseline_counts + cal.device["sign"] * cal.gain * cal.curve.span_counts * r


def test_save_load_round_trip_and_hash(tmp_path):
    cal = make_cal()
    digest = cal.save(tmp_path / "cal.npz")
    back = Calibration.load(tmp_path / "cal.npz")
    assert back.sha256 == digest and len(digest) == 64
    np.testing.assert_array_equal(back.gain, cal.gain.astype(np.float32))
    assert back.device == cal.device and back.curve == cal.curve
    assert not (tmp_path / "cal.npz.part").exists()


def test_a_damaged_file_is_refused(tmp_path):
    cal = make_cal()
    cal.save(tmp_path / "cal.npz")
    with np.load(tmp_path / "cal.npz") as z:
        arrays = {k: z[k] for k in z.files}
    arrays["gain"][0, 0] += 0.5
    np.savez_compressed(tmp_path / "cal.npz", **arrays)
    with pytest.raises(CalibrationError, match="damaged"):
        Calibration.load(tmp_path / "cal.npz")
    with pytest.raises(CalibrationError, match="cavatar calibrate"):
        Calibration.load(tmp_path / "missing.npz")


@pytest.mark.parametrize(
    "over, says",
    [({"device_id": "carpet-02"}, "device_id 'carpet-01' in the file, 'carpet-02' on the device"),
     ({"rows": 48, "cols": 48}, "rows 6 in the file, 48 on the device"),
     ({"adc_bits": 10}, "adc_bits 12 in the file, 10 on the device"),
     ({"fw_major": 2}, "firmware 1.0.0 in the file, 2.0.3 on the device")],
)
def test_another_carpet_resolution_or_firmware_is_refused_saying_what_differs(over, says):
    cal = make_cal()
    cal.check_device(info())  # the right one passes (a patch release is compatible)
    with pytest.raises(CalibrationError, match=says):
        cal.check_device(info(**over))


@pytest.mark.parametrize("sign", [-1, 1])
def test_apply_inverts_the_model_where_unsaturated_and_censors_above(sign):
    cal = make_cal(sign=sign)
    p = np.linspace(0, 20, 30).reshape(6, 5)
    counts = np.clip(np.rint(forward(cal, p)), 0, 4095).astype(np.uint16)
    out = Applier(cal).apply(counts)
    unsat = (p > 0.3) & (p < cal.curve.saturation_kpa * 0.95)
    rel = np.abs(out.pressure_kpa[unsat] - p[unsat]) / p[unsat]
    assert rel.max() < 0.02  # only rounding to whole counts remains
    assert out.saturated[p > cal.curve.saturation_kpa * 1.05].all()
    assert (out.pressure_kpa[out.saturated] == cal.curve.saturation_kpa).all()
    assert out.pressure_kpa[0, 0] == 0.0


def test_masked_sensels_are_zero_and_flagged():
    cal = make_cal()
    cal.fault[2, :] = FAULT["dead"]
    cal.fault[0, 0] = FAULT["weak"]  # weak is usable
    counts = np.clip(np.rint(forward(cal, np.full((6, 5), 5.0))), 0, 4095).astype(np.uint16)
    out = Applier(cal).apply(counts)
    assert out.masked[2].all() and (out.pressure_kpa[2] == 0).all()
    assert not out.masked[0, 0] and out.pressure_kpa[0, 0] > 0


def test_temperature_compensation_direction():
    cal = make_cal()
    counts = np.clip(np.rint(forward(cal, np.full((6, 5), 5.0))), 0, 4095).astype(np.uint16)
    a = Applier(cal)
    warm = a.apply(counts, temperature_c=32.0).pressure_kpa.mean()
    same = a.apply(counts, temperature_c=22.0).pressure_kpa.mean()
    assert warm < same  # a warmer sensor reads high, so the same counts mean less pressure


def test_crosstalk_inverse_recovers_line_loaded_readings():
    cal = make_cal(rows=16, cols=16, crosstalk_r_norm=0.05)
    cal.gain[:] = 1.0
    p = np.zeros((16, 16))
    p[3:6, 2:12] = 6.0  # a loaded band shares rows and columns
    r = cal.curve.response(p)
    r_app = r / ((1 + 0.05 * r.sum(axis=0, keepdims=True)) * (1 + 0.05 * r.sum(axis=1, keepdims=True)))
    counts = np.rint(cal.baseline_counts - cal.curve.span_counts * r_app).astype(np.uint16)
    plain = Applier(cal, crosstalk=False).apply(counts).pressure_kpa[p > 0]
    fixed = Applier(cal).apply(counts).pressure_kpa[p > 0]
    assert np.median(np.abs(plain - 6.0) / 6.0) > 0.10
    assert np.median(np.abs(fixed - 6.0) / 6.0) < 0.02


def test_wrong_frame_shape():
    with pytest.raises(ValueError, match=r"calibration is for \(6, 5\)"):
        Applier(make_cal()).apply(np.zeros((5, 6), np.uint16))

"""Test and simulation aid: a :class:`Calibration` made from a simulated sensor's TRUE parameters.

Not a calibration procedure (those live in the calibration steps and know nothing of
the truth). Tests of the runtime use it to start from the calibration a perfect
procedure would produce, so that whatever error remains is the runtime's own::

    sensor = CarpetSensor(SensorConfig(...), seed=3)          # sim.sensor
    cal = calibration_from_truth(sensor, t_s=0.0)             # baseline, noise, gain, curve, faults
    info = device_info(cal)                                   # an INFO-like record for check_device

Duck-typed on ``sim.sensor.CarpetSensor`` (``calibration`` may not import ``sim``).
The mapping, with the simulator's front end ``v = offset + sign·k·tile_gain·A`` and
``A = u(P)·film_gain·temp + leak``:

- baseline = the sensor's noise-free empty reading at ``t_s`` (offset, leakage, smear);
- gain·span = k·tile_gain·film_gain·line_factor·temp(T_cal); span is that product's
  median, gain the rest (median 1);
- curve = the true Hill curve, saturation at the true P_sat;
- noise = √(white² + row² + 1/12) (+ noisy-line extra), in counts at the ADC's bits;
- crosstalk_r_norm = R·g_full · median film gain (the runtime sums normalised r);
- temperature = the session's at ``t_s``; coefficient k_T / (1 + k_T·(T_cal − T_ref)),
  which makes the runtime's compensation exact for the simulator's linear law;
- faults from the true masks (dead and mux bank → dead, half-dead → weak, …).
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np

from calibration.file import FAULT, Calibration, Curve


def calibration_from_truth(sensor: Any, t_s: float = 0.0, device_id: str = "sim-carpet",
                           firmware: tuple[int, int, int] = (1, 0, 0)) -> Calibration:
    """The calibration a perfect procedure would save for ``sensor`` at time ``t_s``
    (not before the sensor's last frame: the simulator's time never goes back)."""
    cfg, carpet = sensor.config, sensor.carpet
    fe, rc, dyn, noise = cfg.frontend, cfg.response, cfg.dynamics, cfg.noise
    to_counts = 2.0 ** (fe.adc_bits - 10)
    temp_c = float(sensor.temperature_c(t_s))
    temp_factor = 1.0 + dyn.temp_gain_per_c * (temp_c - dyn.reference_temperature_c)

    baseline = sensor.expected_empty_counts(t_s)
    sens = carpet.k_counts * carpet.tile_gain * carpet.film_gain * carpet.line_factor * temp_factor
    live = sens > 0
    span = float(np.median(sens[live])) if live.any() else float(carpet.k_counts)
    gain = np.where(live, sens / span, 1.0)

    sigma = np.sqrt((noise.white_lsb10 * to_counts) ** 2 + (noise.row_lsb10 * to_counts) ** 2 + 1.0 / 12.0)
    noise_counts = np.maximum(np.hypot(sigma, carpet.extra_noise_counts), 0.5)

    m = carpet.masks
    fault = np.zeros(carpet.shape, np.uint8)
    fault[m["dead"] | m["mux_bank"]] |= FAULT["dead"]
    fault[m["half_dead"]] |= FAULT["weak"]
    fault[m["stuck"]] |= FAULT["stuck"]
    fault[m["noisy"]] |= FAULT["noisy"]
    fault[m["short"]] |= FAULT["short"]
    fault[m["outside"]] |= FAULT["outside"]

    rho = cfg.crosstalk.line_resistance_ohm * cfg.crosstalk.g_full_s
    film = carpet.film_gain[live] if live.any() else np.ones(1)
    return Calibration(
        baseline_counts=baseline.astype(np.float32), noise_counts=noise_counts.astype(np.float32),
        gain=gain.astype(np.float32), fault=fault,
        device={"device_id": device_id, "rows": carpet.shape[0], "cols": carpet.shape[1], "adc_bits": fe.adc_bits,
                "sign": fe.sign, "firmware": list(firmware), "protocol_version": 1},
        pitch_m=cfg.grid.pitch_mm * 1e-3,
        curve=Curve(half_scale_kpa=rc.half_scale_kpa, exponent=rc.exponent, span_counts=span,
                    saturation_kpa=rc.p_sat_kpa),
        crosstalk_r_norm=float(rho * np.median(film) * temp_factor),
        temperature_c=temp_c,
        temp_coeff_per_c=dyn.temp_gain_per_c / temp_factor,
        steps={"source": "calibration_from_truth (simulation aid)"},
    )


def device_info(cal: Calibration, **override: Any) -> SimpleNamespace:
    """An INFO-packet-like record matching ``cal`` (fields as ``firmware_protocol.codec.Info``)."""
    d = cal.device
    fw = list(d.get("firmware") or [1, 0, 0])
    fields = dict(device_id=d["device_id"], rows=d["rows"], cols=d["cols"], adc_bits=d["adc_bits"], sign=d["sign"],
                  fw_major=fw[0], fw_minor=fw[1], fw_patch=fw[2])
    fields.update(override)
    return SimpleNamespace(**fields)


__all__ = ["calibration_from_truth", "device_info"]

"""The distribution a random carpet is drawn from (``CarpetSensor.random``, ``params.random_config``):
the range of each ranged parameter of :mod:`sim.sensor.config` and the rate of each fault kind.
Sources and estimates as in :mod:`sim.sensor.config`.
"""

from __future__ import annotations

# Ranges the randomiser draws from: (low, mode, high); triangular around the default.
RANGES: dict[str, tuple[float, float, float]] = {
    "half_scale_kpa": (5.0, 8.0, 15.0),
    "exponent": (0.9, 1.2, 1.5),
    "p_sat_kpa": (10.0, 14.0, 20.0),
    "leakage_fraction": (0.0, 0.002, 0.005),
    "sensel_sigma": (0.05, 0.15, 0.30),
    "row_sigma": (0.0, 0.05, 0.10),
    "col_sigma": (0.0, 0.05, 0.10),
    "smooth_amplitude": (0.10, 0.15, 0.20),
    "smooth_length_mm": (200.0, 450.0, 800.0),
    "tile_sigma": (0.0, 0.05, 0.10),
    "global_offset_lsb10": (-12.0, 10.0, 48.0),
    "hysteresis": (0.0, 0.05, 0.10),
    "creep_per_decade": (0.0, 0.03, 0.05),
    "temp_gain_per_c": (0.0015, 0.0025, 0.0035),
    "line_resistance_ohm": (20.0, 100.0, 500.0),
    "white_lsb10": (1.0, 1.5, 2.5),
    "row_lsb10": (0.3, 0.7, 1.2),
    "smear_fraction": (0.0, 0.02, 0.04),
    "temperature_c": (15.0, 22.0, 30.0),
    "rug_sigma_mm": (0.0, 5.0, 15.0),
}

# Probability that a randomised carpet has at least one fault of each kind (est.).
FAULT_RATES: dict[str, float] = {
    "dead": 0.15,
    "half_dead": 0.10,
    "stuck": 0.05,
    "noisy": 0.10,
    "short": 0.05,
    "mux_bank": 0.03,
    "mask": 0.05,
}

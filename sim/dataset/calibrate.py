"""The calibration each simulated carpet of a dataset gets, so that training and evaluation
can read what a board reads: raw counts → ``calibration.apply`` → kPa.

    cal = carpet_calibration(carpet_seed, grid=96, adc_bits=12, pitch_mm=19.05, method="installer")

- ``installer``: the guided procedure of ``cavatar calibrate --sim`` acted out on the very
  carpet the dataset's sequences are rendered on (self-test, empty capture, coverage walk,
  board equilibration, known-weight stance of a 72 kg installer, held-out validation),
  with the CLI's default options (no crosstalk model): what a real installation would
  save, errors included (~12 s of CPU per carpet).
- ``truth``: the sensor's true parameters (``calibration.from_truth``): a perfect
  procedure, for telling the procedure's errors apart from the sensor's.

The file's creation time is fixed (``CREATED``) so that the same seed writes the same bytes.
"""

from __future__ import annotations

import tempfile
from pathlib import Path

METHODS = ("installer", "truth")
CREATED = "2026-01-01T00:00:00+00:00"
INSTALLER_MASS_KG = 72.0


def carpet_calibration(carpet_seed: int, *, grid: int, adc_bits: int, pitch_mm: float, method: str):
    """The calibration (calibration.file.Calibration) of the dataset carpet ``carpet_seed``."""
    from sim.sensor import CarpetSensor

    if method not in METHODS:
        raise ValueError(f"calibration must be one of {METHODS}, got {method!r}")
    sensor = CarpetSensor.random(carpet_seed, grid=grid, adc_bits=adc_bits, pitch_mm=pitch_mm)
    if method == "truth":
        from calibration.from_truth import calibration_from_truth

        cal = calibration_from_truth(sensor, device_id=f"sim-{carpet_seed}")
    else:
        from calibration.actor import Actor
        from calibration.providers import SimProvider
        from calibration.session import Options, Session

        with tempfile.TemporaryDirectory(prefix="cavatar-cal-") as work:
            session = Session(Path(work), Options(mass_kg=INSTALLER_MASS_KG))
            session.run(SimProvider(Actor(sensor, mass_kg=INSTALLER_MASS_KG, seed=carpet_seed), out=lambda _: None))
            cal, _ = session.finish()
    cal.created = CREATED
    return cal

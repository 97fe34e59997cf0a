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
The procedures are calibration's (``calibration.virtual.calibrate_virtual``); sim may not import
calibration (design.md), so it finds that function through its entry point
``cavatar.calibrations: virtual`` (setup.cfg).
"""

from __future__ import annotations

from importlib import metadata

METHODS = ("installer", "truth")
CREATED = "2026-01-01T00:00:00+00:00"
INSTALLER_MASS_KG = 72.0
ENTRY_POINT = ("cavatar.calibrations", "virtual")


def calibrator():
    """``calibrate_virtual(sensor, *, seed, method, mass_kg, device_id)`` of the installed calibration package."""
    group, name = ENTRY_POINT
    found = [ep for ep in metadata.entry_points(group=group) if ep.name == name]
    if not found:
        raise RuntimeError(f"writing a dataset's calibrations needs calibration's entry point {group}: {name}, which "
                           "is not installed; reinstall cavatar-edge (pip install -e .)")
    return found[0].load()


def carpet_calibration(carpet_seed: int, *, grid: int, adc_bits: int, pitch_mm: float, method: str):
    """The calibration (calibration.file.Calibration) of the dataset carpet ``carpet_seed``."""
    from sim.sensor import CarpetSensor

    if method not in METHODS:
        raise ValueError(f"calibration must be one of {METHODS}, got {method!r}")
    sensor = CarpetSensor.random(carpet_seed, grid=grid, adc_bits=adc_bits, pitch_mm=pitch_mm)
    cal, _ = calibrator()(sensor, seed=carpet_seed, method=method, mass_kg=INSTALLER_MASS_KG,
                          device_id=f"sim-{carpet_seed}")
    cal.created = CREATED
    return cal

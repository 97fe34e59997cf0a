"""The calibration of a virtual carpet: the installer's scripted session acted out on its sensor model,
or the sensor's true parameters.

    cal, validation = calibrate_virtual(sensor, seed=7)                   # what an installation would save
    cal, _ = calibrate_virtual(sensor, seed=7, method="truth", device_id="sim-7")   # a perfect procedure

Duck-typed on the sensor (``sim.sensor.CarpetSensor``; calibration may not import sim). The runtime
gets the sensor from the ``sim://`` source plug-in (edge.runtime.carpet_calibration); the dataset
generator of sim reaches this function through the entry point ``cavatar.calibrations: virtual``
(setup.cfg), so neither package imports the other.
"""

from __future__ import annotations

import tempfile
from pathlib import Path
from typing import Any

from calibration.file import Calibration
from calibration.result import StepResult

METHODS = ("installer", "truth")


def calibrate_virtual(sensor: Any, *, seed: int, method: str = "installer", mass_kg: float = 72.0,
                      device_id: str = "sim-carpet") -> tuple[Calibration, StepResult | None]:
    """``(calibration, validation)`` of ``sensor``; validation is None for ``truth``.

    ``installer``: the guided session of ``cavatar calibrate --sim`` (self-test, empty capture, coverage
    walk, board equilibration, known-weight stance of a ``mass_kg`` installer drawn from ``seed``,
    held-out validation) with the command's default options; errors included, as a real installation.
    ``truth``: ``calibration.from_truth`` (``device_id`` names the board). Raises what the session raises
    (SessionError, CalibrationError, ValueError)."""
    if method not in METHODS:
        raise ValueError(f"calibration method must be one of {METHODS}, got {method!r}")
    if method == "truth":
        from calibration.from_truth import calibration_from_truth

        return calibration_from_truth(sensor, device_id=device_id), None
    from calibration.actor import Actor
    from calibration.providers import SimProvider
    from calibration.session import Options, Session

    provider = SimProvider(Actor(sensor, mass_kg=mass_kg, seed=seed), None, out=lambda text: None, live_map=False)
    with tempfile.TemporaryDirectory(prefix="cavatar-simcal-") as work:
        session = Session(Path(work), Options(mass_kg=mass_kg))
        session.run(provider)
        return session.finish(None)


__all__ = ["METHODS", "calibrate_virtual"]

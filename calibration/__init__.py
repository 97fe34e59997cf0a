"""Calibration of the carpet's sensor grid: procedures, fault detection, file format, runtime apply."""

from calibration.apply import Applied, Applier
from calibration.file import FAULT, UNUSABLE, Calibration, CalibrationError, Curve
from calibration.runtime import CalibratedFrames

__all__ = ["Applied", "Applier", "CalibratedFrames", "Calibration", "CalibrationError", "Curve", "FAULT", "UNUSABLE"]

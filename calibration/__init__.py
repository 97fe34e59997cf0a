"""Calibration of the carpet's sensor grid: procedures, fault detection, file format, runtime apply."""

"""The synthetic carpet: motions, contact physics and the sensor model."""

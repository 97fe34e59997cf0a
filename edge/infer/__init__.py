"""On-board inference (numpy + onnxruntime, never torch): model bundles, input normalisation,
rotation conversions. The runtime (edge.scene → here → edge.body) builds on ModelBundle.
"""

from edge.infer.bundle import BundleError, ModelBundle, verify
from edge.infer.normalise import NORMALISATION, center_of_pressure_m, normalise_kpa
from edge.infer.rotations import rot6d_to_axis_angle
from edge.infer.window import FeatureWindow

__all__ = ["BundleError", "FeatureWindow", "ModelBundle", "NORMALISATION", "center_of_pressure_m", "normalise_kpa", "rot6d_to_axis_angle", "verify"]

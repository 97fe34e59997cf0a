"""On-board inference (numpy + onnxruntime, never torch): model bundles, input normalisation,
rotation conversions, and a person's inference (:class:`PeopleInference`: the scene's handover
in, one result per confirmed person out). The runtime (edge.scene → here → edge.record) builds on it.
"""

from edge.infer.bundle import BundleError, ModelBundle, verify
from edge.infer.normalise import NORMALISATION, center_of_pressure_m, normalise_kpa
from edge.infer.people import InferenceStep, PeopleInference
from edge.infer.rotations import rot6d_to_axis_angle
from edge.infer.window import FeatureWindow

__all__ = ["BundleError", "FeatureWindow", "InferenceStep", "ModelBundle", "NORMALISATION", "PeopleInference",
           "center_of_pressure_m", "normalise_kpa", "rot6d_to_axis_angle", "verify"]

"""The body model of the runtime: SMPL in numpy, and the free SMPL-layout files we ship.

``BodyModel.load(path).forward(pose_aa, betas, transl_m, vertices=False)``; see
``edge.body.model`` for the conventions and docs/body-model.md for the files.
No torch here: the differentiable twin lives in ``export.body``.
"""

from edge.body.files import BodyArrays, BodyModelFileError, read_body_file, write_body_npz
from edge.body.model import (
    SHIPPED_MODELS,
    SMPL_JOINT_NAMES,
    SMPL_PARENTS,
    BodyModel,
    BodyModelWarning,
    shipped_model_path,
)

__all__ = [
    "BodyArrays",
    "BodyModel",
    "BodyModelFileError",
    "BodyModelWarning",
    "SHIPPED_MODELS",
    "SMPL_JOINT_NAMES",
    "SMPL_PARENTS",
    "read_body_file",
    "shipped_model_path",
    "write_body_npz",
]

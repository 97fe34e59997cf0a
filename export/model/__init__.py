"""The CAvatar model (PyTorch): configuration, encoders, temporal heads, losses.

    from export.model import CAvatarNet, ModelConfig
    net = CAvatarNet(ModelConfig.preset("lean", grid=(96, 96)))
"""

from export.model.config import NUM_ACTIVITIES, NUM_BETAS, NUM_JOINTS, PRESETS, ModelConfig
from export.model.heads import OUTPUT_SIZES, OUTPUTS
from export.model.network import CAvatarNet, JointDiscriminator, matrix_to_rot6d, rot6d_to_matrix

__all__ = ["CAvatarNet", "JointDiscriminator", "ModelConfig", "PRESETS", "OUTPUTS", "OUTPUT_SIZES", "NUM_ACTIVITIES",
           "NUM_BETAS", "NUM_JOINTS", "matrix_to_rot6d", "rot6d_to_matrix"]

"""Training losses (the paper's): L1 on rotations, betas, translation, joints, vertices, the
activity cross-entropy, a confidence target, and the adversarial joint-position term.

Joints and vertices come from the torch body twin evaluated on the predicted rotation
matrices; training uses the `lite` mesh (1,229 vertices) for the vertex loss: 8× cheaper than
`full`, the same skeleton (the dataset's joints are the lite model's).
"""

from __future__ import annotations

import torch
from torch.nn import functional as F

from export.body.torch_body import TorchBodyModel, axis_angle_to_matrix
from export.model.config import ModelConfig
from export.model.network import JointDiscriminator, rot6d_to_matrix

CONFIDENCE_SCALE_M = 0.10  # confidence target: exp(-pelvis-aligned MPJPE / 10 cm)


def body_from_matrices(body: TorchBodyModel, rot: torch.Tensor, betas: torch.Tensor, transl_m: torch.Tensor,
                       vertices: bool = False) -> dict[str, torch.Tensor]:
    """The twin's forward with rotation matrices (B,J,3,3) instead of axis-angle."""
    dtype = body.v_template.dtype
    return body.forward_matrices(rot.to(dtype), betas.to(dtype), transl_m.to(dtype), vertices)


def generator_losses(out: dict[str, torch.Tensor], target: dict[str, torch.Tensor], body: TorchBodyModel,
                     cfg: ModelConfig, disc: JointDiscriminator | None) -> tuple[torch.Tensor, dict[str, float], torch.Tensor]:
    """out: the net's outputs (B,…); target: pose_aa (B,72), betas, transl_rel_m (B,3), activity (B,).

    Returns (total, parts as floats, predicted joints (B,24,3) for the discriminator step).
    """
    b = out["rot6d"].shape[0]
    rot = rot6d_to_matrix(out["rot6d"].reshape(b, -1, 6))
    rot_gt = axis_angle_to_matrix(target["pose_aa"].reshape(b, -1, 3))
    parts = {
        "pose": F.l1_loss(rot, rot_gt),
        "betas": F.l1_loss(out["betas"], target["betas"]),
        "transl": F.l1_loss(out["transl_rel_m"], target["transl_rel_m"]),
        "activity": F.cross_entropy(out["activity_logits"], target["activity"]),
    }
    pred = body_from_matrices(body, rot, out["betas"], out["transl_rel_m"], vertices=cfg.body_losses)
    with torch.no_grad():
        gt = body_from_matrices(body, rot_gt, target["betas"], target["transl_rel_m"], vertices=cfg.body_losses)
        aligned = (pred["joints"] - pred["joints"][:, :1]) - (gt["joints"] - gt["joints"][:, :1])
        mpjpe = aligned.norm(dim=-1).mean(-1)
    parts["confidence"] = F.binary_cross_entropy(out["confidence"].clamp(1e-6, 1 - 1e-6), torch.exp(-mpjpe / CONFIDENCE_SCALE_M))
    if cfg.body_losses:
        parts["joints"] = F.l1_loss(pred["joints"], gt["joints"])
        parts["vertices"] = F.l1_loss(pred["vertices"], gt["vertices"])
    if disc is not None and cfg.discriminator:
        logits = disc(pred["joints"])
        parts["adversarial"] = F.binary_cross_entropy_with_logits(logits, torch.ones_like(logits))
    weights = {"pose": cfg.w_pose, "betas": cfg.w_betas, "transl": cfg.w_transl, "activity": cfg.w_activity,
               "confidence": cfg.w_confidence, "joints": cfg.w_joints, "vertices": cfg.w_vertices,
               "adversarial": cfg.w_adversarial}
    total = sum(weights[k] * v for k, v in parts.items())
    floats = {k: float(v.detach()) for k, v in parts.items()}
    floats["mpjpe_train_cm"] = float(mpjpe.mean()) * 100
    return total, floats, pred["joints"].detach()


def discriminator_loss(disc: JointDiscriminator, real_joints: torch.Tensor, fake_joints: torch.Tensor) -> torch.Tensor:
    """BCE: ground-truth joints → 1, predicted joints → 0."""
    real, fake = disc(real_joints), disc(fake_joints)
    return (F.binary_cross_entropy_with_logits(real, torch.ones_like(real))
            + F.binary_cross_entropy_with_logits(fake, torch.zeros_like(fake)))

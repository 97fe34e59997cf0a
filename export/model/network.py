"""The CAvatar network: a per-frame encoder, a temporal head, and the joint discriminator.

Training shares frames between overlapping windows: a chunk of B+T-1 consecutive frames
of one person is encoded once and unfolded into B windows of T (:meth:`CAvatarNet.forward_chunk`).
"""

from __future__ import annotations

import torch
from torch import nn

from export.model.config import NUM_JOINTS, ModelConfig
from export.model.encoders import build_encoder
from export.model.heads import OUTPUTS, build_head


def rot6d_to_matrix(x: torch.Tensor) -> torch.Tensor:
    """(..., 6) = first column then second column → (..., 3, 3) by Gram–Schmidt."""
    a1, a2 = x[..., 0:3], x[..., 3:6]
    b1 = nn.functional.normalize(a1, dim=-1, eps=1e-6)
    b2 = nn.functional.normalize(a2 - (b1 * a2).sum(-1, keepdim=True) * b1, dim=-1, eps=1e-6)
    b3 = torch.cross(b1, b2, dim=-1)
    return torch.stack([b1, b2, b3], -1)


def matrix_to_rot6d(r: torch.Tensor) -> torch.Tensor:
    """(..., 3, 3) → (..., 6): the first two columns."""
    return torch.cat([r[..., :, 0], r[..., :, 1]], -1)


class CAvatarNet(nn.Module):
    def __init__(self, cfg: ModelConfig):
        super().__init__()
        self.cfg = cfg
        self.encoder = build_encoder(cfg)
        self.head = build_head(cfg)

    def forward_chunk(self, frames: torch.Tensor) -> dict[str, torch.Tensor]:
        """frames (N,1,H,W), N ≥ T → outputs for the N-T+1 windows ending at frames T-1 … N-1."""
        t = self.cfg.window
        feats = self.encoder(frames)                           # (N,F): each frame encoded once
        windows = feats.unfold(0, t, 1).transpose(1, 2)        # (N-T+1, T, F)
        return dict(zip(OUTPUTS, self.head(windows)))

    def forward(self, windows: torch.Tensor) -> dict[str, torch.Tensor]:
        """windows (B,T,1,H,W) → outputs (the simple, unshared path; for tests and evaluation)."""
        b, t = windows.shape[:2]
        feats = self.encoder(windows.flatten(0, 1)).reshape(b, t, -1)
        return dict(zip(OUTPUTS, self.head(feats)))


class JointDiscriminator(nn.Module):
    """Real vs predicted pelvis-centred joint positions: 72 → 256 (tanh) → 1 (sigmoid)."""

    def __init__(self, hidden: int = 256):
        super().__init__()
        self.net = nn.Sequential(nn.Linear(3 * NUM_JOINTS, hidden), nn.Tanh(), nn.Linear(hidden, 1))

    def forward(self, joints_m: torch.Tensor) -> torch.Tensor:
        """joints (B,24,3) → logits (B,); the sigmoid lives in the BCE-with-logits loss."""
        centred = joints_m - joints_m[:, :1]
        return self.net(centred.flatten(1))[:, 0]

"""Temporal heads: features of a causal window (B,T,F) → parameters of the window's last frame.

Outputs (a tuple, in OUTPUTS order, so the ONNX graph has named outputs):

    rot6d           (B, 144)  24 joints × 6D rotation (the first two columns of R, Zhou et al.)
    betas           (B, 10)
    transl_rel_m    (B, 3)    pelvis minus (CoP_x, CoP_y, 0) of the target frame, carpet frame, metres
    activity_logits (B, 12)   sim.motion.ACTIVITIES order
    confidence      (B,)      in (0, 1): trained to predict exp(-MPJPE / 10 cm) of this output

`transformer`: linear F→d (then a LayerNorm when `feature_norm`, so the features are not
swamped by the positional encoding), sine/cosine positional encoding, nn.TransformerEncoder (post-norm,
ReLU, batch_first, enable_nested_tensor=False), the last token → linear. `gru` and `mean` are
the no-attention ablations (a one-layer GRU; a temporal mean then an MLP).
"""

from __future__ import annotations

import math

import torch
from torch import nn

from export.model.config import NUM_ACTIVITIES, NUM_BETAS, NUM_JOINTS, ModelConfig

OUTPUTS = ("rot6d", "betas", "transl_rel_m", "activity_logits", "confidence")
OUTPUT_SIZES = {"rot6d": 6 * NUM_JOINTS, "betas": NUM_BETAS, "transl_rel_m": 3, "activity_logits": NUM_ACTIVITIES, "confidence": 1}
# Zero output = a person standing upright (global orientation +90° about x: columns (1,0,0), (0,0,1)),
# every other joint at rest, the pelvis 0.9 m up over the centre of pressure.
_IDENTITY_6D = torch.tensor([1.0, 0.0, 0.0, 1.0, 0.0, 0.0])
_UPRIGHT_6D = torch.tensor([1.0, 0.0, 0.0, 0.0, 0.0, 1.0])


def sinusoidal_encoding(length: int, d: int) -> torch.Tensor:
    """(length, d) sine/cosine positional encoding (Vaswani et al.)."""
    pos = torch.arange(length, dtype=torch.float32)[:, None]
    div = torch.exp(torch.arange(0, d, 2, dtype=torch.float32) * (-math.log(10000.0) / d))
    pe = torch.zeros(length, d)
    pe[:, 0::2] = torch.sin(pos * div)
    pe[:, 1::2] = torch.cos(pos * div[: d // 2])
    return pe


class ParamHead(nn.Module):
    """Linear d → all outputs; rotations predicted as offsets from identity, pelvis from standing."""

    def __init__(self, d: int):
        super().__init__()
        self.out = nn.Linear(d, sum(OUTPUT_SIZES.values()))
        nn.init.normal_(self.out.weight, std=1e-2)
        nn.init.zeros_(self.out.bias)
        self.register_buffer("rot_bias", torch.cat([_UPRIGHT_6D, _IDENTITY_6D.repeat(NUM_JOINTS - 1)]), persistent=False)
        self.register_buffer("transl_bias", torch.tensor([0.0, 0.0, 0.9]), persistent=False)

    def forward(self, h: torch.Tensor) -> tuple[torch.Tensor, ...]:
        y = self.out(h)
        rot6d, betas, transl, logits, conf = torch.split(y, list(OUTPUT_SIZES.values()), dim=-1)
        return rot6d + self.rot_bias, betas, transl + self.transl_bias, logits, torch.sigmoid(conf[..., 0])


class TransformerHead(nn.Module):
    def __init__(self, cfg: ModelConfig):
        super().__init__()
        self.proj = nn.Linear(cfg.features, cfg.d_model)
        self.norm = nn.LayerNorm(cfg.d_model, eps=cfg.layer_norm_eps) if cfg.feature_norm else nn.Identity()
        self.register_buffer("pe", sinusoidal_encoding(cfg.window, cfg.d_model), persistent=False)
        layer = nn.TransformerEncoderLayer(cfg.d_model, cfg.heads, cfg.ff, cfg.dropout, batch_first=True,
                                           layer_norm_eps=cfg.layer_norm_eps)
        self.encoder = nn.TransformerEncoder(layer, cfg.layers, enable_nested_tensor=False)
        self.params = ParamHead(cfg.d_model)

    def forward(self, feats: torch.Tensor) -> tuple[torch.Tensor, ...]:
        h = self.encoder(self.norm(self.proj(feats)) + self.pe)
        return self.params(h[:, -1])


class GRUHead(nn.Module):
    def __init__(self, cfg: ModelConfig):
        super().__init__()
        self.gru = nn.GRU(cfg.features, cfg.d_model, batch_first=True)
        self.params = ParamHead(cfg.d_model)

    def forward(self, feats: torch.Tensor) -> tuple[torch.Tensor, ...]:
        h, _ = self.gru(feats)
        return self.params(h[:, -1])


class MeanHead(nn.Module):
    def __init__(self, cfg: ModelConfig):
        super().__init__()
        self.mlp = nn.Sequential(nn.Linear(2 * cfg.features, cfg.d_model), nn.ReLU())
        self.params = ParamHead(cfg.d_model)

    def forward(self, feats: torch.Tensor) -> tuple[torch.Tensor, ...]:
        return self.params(self.mlp(torch.cat([feats.mean(1), feats[:, -1]], -1)))


class FrameHead(nn.Module):
    """One frame's features (B,F) → parameters: the auxiliary head of the `frames` training stage
    (an MLP, discarded after it; the encoder it trained is kept)."""

    def __init__(self, cfg: ModelConfig):
        super().__init__()
        self.mlp = nn.Sequential(nn.Linear(cfg.features, cfg.d_model), nn.LayerNorm(cfg.d_model), nn.ReLU(),
                                 nn.Linear(cfg.d_model, cfg.d_model), nn.ReLU())
        self.params = ParamHead(cfg.d_model)

    def forward(self, feats: torch.Tensor) -> tuple[torch.Tensor, ...]:
        return self.params(self.mlp(feats))


def build_head(cfg: ModelConfig) -> nn.Module:
    return {"transformer": TransformerHead, "gru": GRUHead, "mean": MeanHead}[cfg.head](cfg)

"""The model configuration: one typed dataclass, two presets (`paper`, `lean`) and ablation switches.

    cfg = ModelConfig.preset("lean", grid=(96, 96))
    cfg = ModelConfig.preset("paper", head="gru", discriminator=False)   # an ablation

Unknown keys are an error (:meth:`ModelConfig.from_dict`), so a checkpoint or manifest
written by a newer version fails loudly instead of building a different network.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, replace
from typing import Any

from cavatar_common.config import strict_from_dict
from sim.motion import ACTIVITIES

NUM_JOINTS = 24
NUM_BETAS = 10
NUM_ACTIVITIES = len(ACTIVITIES)  # 12: the simulator's activity classes, in ACTIVITIES order

ENCODERS = ("resnet18", "strided")
HEADS = ("transformer", "gru", "mean")  # "gru"/"mean" are the no-attention ablations


@dataclass(frozen=True)
class ModelConfig:
    """Architecture and loss weights. Lengths in frames, grid in sensels."""

    name: str = "lean"
    grid: tuple[int, int] = (96, 96)           # (H, W) of the carpet; the encoder graph is built for it
    window: int = 40                           # causal window: the target frame and the 39 before it
    encoder: str = "strided"                   # "resnet18" (paper) or "strided" (lean)
    encoder_widths: tuple[int, ...] = (16, 32, 64, 128)  # strided encoder: channels per stride-2 stage
    coord_channels: bool = True                # add two constant x/y channels inside the encoder (position cue)
    norm: str = "none"                         # encoder normalisation: "batch" (paper), "group" or "none" (conv bias)
    pool: str = "meanmax"                      # "mean" (paper) or "meanmax": global mean ‖ global max (sparse footprints)
    feature_norm: bool = True                  # LayerNorm on the projected features before the positional encoding
    features: int = 128                        # F, per-frame feature size
    head: str = "transformer"                  # "transformer", "gru" (no attention), "mean" (temporal mean)
    d_model: int = 128
    layers: int = 2
    heads: int = 4
    ff: int = 256
    dropout: float = 0.1
    layer_norm_eps: float = 1e-5
    # losses (weights; positions are in metres, rotations as matrix entries)
    w_pose: float = 1.0
    w_betas: float = 0.1
    w_transl: float = 5.0
    w_joints: float = 5.0
    w_vertices: float = 5.0
    w_activity: float = 0.1
    w_confidence: float = 0.1
    w_adversarial: float = 0.01
    discriminator: bool = True                 # ablation: False drops the adversarial term
    body_losses: bool = True                   # ablation: False drops the joint and vertex losses
    body_model: str = "lite"                   # body model of the training losses (lite mesh: 1,229 vertices)

    def __post_init__(self) -> None:
        if self.encoder not in ENCODERS:
            raise ValueError(f"encoder must be one of {ENCODERS}, got {self.encoder!r}")
        if self.head not in HEADS:
            raise ValueError(f"head must be one of {HEADS}, got {self.head!r}")
        if self.head == "transformer" and self.d_model % self.heads:
            raise ValueError(f"d_model {self.d_model} must be a multiple of heads {self.heads}")
        if self.norm not in ("batch", "group", "none"):
            raise ValueError(f"norm must be 'batch', 'group' or 'none', got {self.norm!r}")
        if self.pool not in ("mean", "meanmax"):
            raise ValueError(f"pool must be 'mean' or 'meanmax', got {self.pool!r}")
        if self.window < 1:
            raise ValueError("window must be at least 1 frame")
        object.__setattr__(self, "grid", tuple(int(g) for g in self.grid))
        object.__setattr__(self, "encoder_widths", tuple(int(c) for c in self.encoder_widths))

    @classmethod
    def preset(cls, name: str, **overrides: Any) -> "ModelConfig":
        """`paper` (ResNet18 → 256, 6×4-head transformer, d 256, ff 2048) or `lean` (small board)."""
        if name not in PRESETS:
            raise ValueError(f"unknown model preset {name!r}; expected one of {sorted(PRESETS)}")
        return replace(PRESETS[name], **overrides)

    def to_dict(self) -> dict[str, Any]:
        d = asdict(self)
        d["grid"], d["encoder_widths"] = list(self.grid), list(self.encoder_widths)
        return d

    @classmethod
    def from_dict(cls, d: dict[str, Any]) -> "ModelConfig":
        return strict_from_dict(cls, d, "model config")


PRESETS: dict[str, ModelConfig] = {
    "lean": ModelConfig(),
    "paper": ModelConfig(name="paper", encoder="resnet18", coord_channels=False, norm="batch", pool="mean", feature_norm=False,
                         features=256, head="transformer", d_model=256, layers=6, heads=4, ff=2048, dropout=0.1),
    # for tests and smoke runs: the lean layout, a few thousand parameters
    "tiny": ModelConfig(name="tiny", encoder_widths=(8, 16), features=16, d_model=16, heads=2, ff=32, layers=1),
}

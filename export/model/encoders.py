"""Per-frame encoders: one person's normalised pressure (B,1,H,W) → features (B,F).

`resnet18` is the paper's: torchvision's ResNet18 layout written out here (no torchvision
on our machines), first convolution for one channel, the last pooling/linear replaced by
global average pooling and a linear layer to F. `strided` is the lean board encoder: four
stride-2 stages of (3×3 conv, ReLU) + a residual 3×3 conv (no normalisation by default), then pooling and a linear.
Pooling is the global mean (paper) or mean ‖ max (`pool="meanmax"`, lean). Both optionally
append two coordinate channels (the input times x and y ramps in [-1, 1]) inside the graph so the
pooled features keep where on the carpet the pressure is (`coord_channels`).
"""

from __future__ import annotations

import torch
from torch import nn

from export.model.config import ModelConfig


def norm2d(c: int, kind: str) -> nn.Module:
    """BatchNorm (paper), GroupNorm (8 groups) or nothing. With "batch", a training batch that is one
    person's consecutive frames has batch statistics that subtract the pose the frames share."""
    if kind == "batch":
        return nn.BatchNorm2d(c)
    return nn.GroupNorm(min(8, c), c) if kind == "group" else nn.Identity()


class CoordChannels(nn.Module):
    """(B,1,H,W) → (B,3,H,W): the input, and the input times x and y ramps in [-1, 1] (position
    where there is pressure; constant ramps alone would drown a footprint covering 1 % of the carpet)."""

    def __init__(self, grid: tuple[int, int]):
        super().__init__()
        h, w = grid
        ys = torch.linspace(-1.0, 1.0, h)[:, None].expand(h, w)
        xs = torch.linspace(-1.0, 1.0, w)[None, :].expand(h, w)
        self.register_buffer("coords", torch.stack([xs, ys])[None].contiguous(), persistent=False)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return torch.cat([x, x * self.coords], 1)


class BasicBlock(nn.Module):
    """ResNet basic block: two 3×3 convs with BN, identity or 1×1-strided shortcut."""

    def __init__(self, cin: int, cout: int, stride: int = 1, norm: str = "batch"):
        super().__init__()
        bias = norm == "none"
        self.conv1 = nn.Conv2d(cin, cout, 3, stride, 1, bias=bias)
        self.bn1 = norm2d(cout, norm)
        self.conv2 = nn.Conv2d(cout, cout, 3, 1, 1, bias=bias)
        self.bn2 = norm2d(cout, norm)
        self.down = None
        if stride != 1 or cin != cout:
            self.down = nn.Sequential(nn.Conv2d(cin, cout, 1, stride, bias=bias), norm2d(cout, norm))

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        y = torch.relu(self.bn1(self.conv1(x)))
        y = self.bn2(self.conv2(y))
        return torch.relu(y + (x if self.down is None else self.down(x)))


class ResNet18Encoder(nn.Module):
    """ResNet18 (2-2-2-2 basic blocks, 64-128-256-512) for one channel, pooled, linear → F."""

    def __init__(self, cfg: ModelConfig):
        super().__init__()
        cin = 3 if cfg.coord_channels else 1
        self.coords = CoordChannels(cfg.grid) if cfg.coord_channels else None
        self.stem = nn.Sequential(nn.Conv2d(cin, 64, 7, 2, 3, bias=cfg.norm == "none"), norm2d(64, cfg.norm), nn.ReLU(),
                                  nn.MaxPool2d(3, 2, 1))
        blocks, c = [], 64
        for width, stride in ((64, 1), (128, 2), (256, 2), (512, 2)):
            blocks += [BasicBlock(c, width, stride, cfg.norm), BasicBlock(width, width, norm=cfg.norm)]
            c = width
        self.blocks = nn.Sequential(*blocks)
        self.pool = cfg.pool
        self.fc = nn.Linear(512 * (2 if cfg.pool == "meanmax" else 1), cfg.features)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if self.coords is not None:
            x = self.coords(x)
        y = self.blocks(self.stem(x))
        return self.fc(global_pool(y, self.pool))


class StridedEncoder(nn.Module):
    """Lean encoder: per stage a stride-2 conv then a residual 3×3 conv (BN folds at export)."""

    def __init__(self, cfg: ModelConfig):
        super().__init__()
        self.coords = CoordChannels(cfg.grid) if cfg.coord_channels else None
        c = 3 if cfg.coord_channels else 1
        stages = []
        for width in cfg.encoder_widths:
            stages.append(nn.Sequential(nn.Conv2d(c, width, 3, 2, 1, bias=cfg.norm == "none"), norm2d(width, cfg.norm), nn.ReLU()))
            stages.append(_Residual(width, cfg.norm))
            c = width
        self.stages = nn.Sequential(*stages)
        self.pool = cfg.pool
        self.fc = nn.Linear(c * (2 if cfg.pool == "meanmax" else 1), cfg.features)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        if self.coords is not None:
            x = self.coords(x)
        return self.fc(global_pool(self.stages(x), self.pool))


class _Residual(nn.Module):
    def __init__(self, c: int, norm: str):
        super().__init__()
        self.conv = nn.Conv2d(c, c, 3, 1, 1, bias=norm == "none")
        self.bn = norm2d(c, norm)

    def forward(self, x: torch.Tensor) -> torch.Tensor:
        return torch.relu(x + self.bn(self.conv(x)))


def global_pool(x: torch.Tensor, kind: str) -> torch.Tensor:
    """(B,C,h,w) → (B,C) mean, or (B,2C) mean ‖ max: a footprint covers ~1 % of the carpet, and a
    mean alone dilutes it into the empty background."""
    mean = x.mean((2, 3))
    return mean if kind == "mean" else torch.cat([mean, x.amax((2, 3))], 1)


def build_encoder(cfg: ModelConfig) -> nn.Module:
    enc = ResNet18Encoder(cfg) if cfg.encoder == "resnet18" else StridedEncoder(cfg)
    for m in enc.modules():  # He init (torchvision's ResNet does the same): keeps the sparse signal's scale
        if isinstance(m, nn.Conv2d):
            nn.init.kaiming_normal_(m.weight, mode="fan_out", nonlinearity="relu")
            if m.bias is not None:
                nn.init.zeros_(m.bias)
    for m in enc.modules():
        if isinstance(m, _Residual) and cfg.norm == "none":
            m.conv.weight.data.mul_(0.5)  # residual branches start small: x + ½·conv(x)
    return enc

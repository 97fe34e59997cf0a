"""Draw the sensor model's documentation figures: ``python -m sim.sensor.figures OUT_DIR``.

Needs matplotlib (the ``viz`` extra); the model itself does not.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from .config import FrontEndConfig, SensorConfig
from .fault_config import FaultConfig, LineFault, MuxBankFault, ShortFault
from .model import CarpetSensor


def two_feet(shape: tuple[int, int], pitch_mm: float, kpa: float = 30.0) -> np.ndarray:
    """Two foot-shaped ellipses (25 × 9 cm) at ``kpa``, 20 cm apart, mid-carpet."""
    rows, cols = shape
    y, x = (np.mgrid[0:rows, 0:cols] + 0.5) * pitch_mm
    cy, cx = rows * pitch_mm / 2, cols * pitch_mm / 2
    p = np.zeros(shape)
    for dx in (-100.0, 100.0):
        p[((y - cy) / 125.0) ** 2 + ((x - cx - dx) / 45.0) ** 2 <= 1] = kpa
    return p


def demo_faults(shape: tuple[int, int]) -> FaultConfig:
    rows, cols = shape
    mask = np.ones(shape, bool)
    mask[: rows // 6, : cols // 6] = False
    return FaultConfig(
        lines=(LineFault("dead", "row", rows // 2 + 3), LineFault("half_dead", "col", cols // 3),
               LineFault("stuck", "col", cols - 10), LineFault("noisy", "row", rows - 12),
               LineFault("dead", "col", cols // 2 + 9, start=rows // 2)),
        shorts=(ShortFault(rows // 4, cols // 2),), mux_banks=(MuxBankFault("col", 64 if cols >= 96 else 0, 16),),
        mask=mask,
    )


def main(out_dir: str = "docs/sim/sensor") -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    cfg = SensorConfig(frontend=FrontEndConfig(adc_bits=10, sign=1))
    p = _empty_and_loaded(plt, out, cfg)
    _faults(plt, out, cfg, p)
    _crosstalk(plt, out, cfg)
    print(f"wrote {sorted(x.name for x in out.glob('*.png'))} to {out}")


def _empty_and_loaded(plt, out: Path, cfg: SensorConfig) -> np.ndarray:
    """empty.png (an empty frame, its temporal noise, its histogram) and loaded.png (two feet); → their pressure."""
    sensor = CarpetSensor(cfg, seed=7)
    pitch = cfg.grid.pitch_mm
    empty = sensor.counts(np.zeros(sensor.shape), 0.0)
    frames = np.stack([sensor.counts(np.zeros(sensor.shape), (k + 1) / 14) for k in range(100)]).astype(float)
    p = two_feet(sensor.shape, pitch)
    loaded = sensor.counts(p, 8.0)
    sat = sensor.last.saturated

    fig, ax = plt.subplots(1, 3, figsize=(15, 4.6))
    im = ax[0].imshow(empty, cmap="viridis")
    ax[0].set_title(f"empty frame, 10 bit (median {np.median(empty):.0f})")
    fig.colorbar(im, ax=ax[0], label="counts")
    im = ax[1].imshow(frames.std(axis=0), cmap="magma", vmin=0, vmax=3)
    ax[1].set_title(f"temporal σ over 100 frames (median {np.median(frames.std(axis=0)):.2f})")
    fig.colorbar(im, ax=ax[1], label="counts")
    ax[2].hist(empty.ravel(), bins=60, color="C0")
    ax[2].set_title("empty frame histogram (3×3 tile offsets)")
    ax[2].set_xlabel("counts")
    fig.tight_layout()
    fig.savefig(out / "empty.png", dpi=80)
    plt.close(fig)

    fig, ax = plt.subplots(1, 3, figsize=(15, 4.6))
    im = ax[0].imshow(p, cmap="inferno")
    ax[0].set_title("true pressure: two feet at 30 kPa")
    fig.colorbar(im, ax=ax[0], label="kPa")
    im = ax[1].imshow(loaded, cmap="viridis", vmin=0, vmax=1023)
    ax[1].set_title("raw counts (sign +1, 10 bit)")
    fig.colorbar(im, ax=ax[1], label="counts")
    ax[2].imshow(sat, cmap="gray_r")
    ax[2].set_title(f"saturated (at the rail): {sat.sum()} of {(p > 0).sum()} loaded sensels")
    fig.tight_layout()
    fig.savefig(out / "loaded.png", dpi=80)
    plt.close(fig)
    return p


def _faults(plt, out: Path, cfg: SensorConfig, p: np.ndarray) -> None:
    """faults.png: every fault mask of a demo carpet, and its counts under the feet and two strips."""
    faulty = CarpetSensor(SensorConfig(faults=demo_faults(cfg.grid.shape)), seed=7)
    masks = faulty.fault_masks
    walk = p.copy()
    walk[10:80, 20:28] = 6.0  # strips of load, to show the line faults
    walk[62:70, 3:95] = 6.0
    faulty.counts(np.zeros(faulty.shape), 0.0)
    fc = faulty.counts(walk, 1.0)
    kinds = ["dead", "half_dead", "stuck", "noisy", "short", "short_lines", "mux_bank", "outside"]
    fig, ax = plt.subplots(2, 5, figsize=(19, 8))
    for a_, k in zip(ax.ravel(), kinds):
        a_.imshow(masks[k], cmap="gray_r", vmin=0, vmax=1)
        a_.set_title(f"mask: {k} ({masks[k].sum()})")
    ax[1, 3].imshow(walk, cmap="inferno")
    ax[1, 3].set_title("pressure (feet + two strips, 6 kPa)")
    ax[1, 4].imshow(fc, cmap="viridis", vmin=0, vmax=1023)
    ax[1, 4].set_title("counts of the faulty carpet")
    fig.tight_layout()
    fig.savefig(out / "faults.png", dpi=70)
    plt.close(fig)


def _crosstalk(plt, out: Path, cfg: SensorConfig) -> None:
    """crosstalk.png: a floating readout's ghost, and line resistance reading shared rows low."""
    ghost_cfg = SensorConfig(frontend=FrontEndConfig(adc_bits=10), crosstalk=cfg.crosstalk.__class__(readout="floating"))
    gs = CarpetSensor(ghost_cfg.ideal(), seed=7)
    q = np.zeros(gs.shape)
    for r, c in ((20, 20), (20, 60), (60, 20)):
        q[r : r + 8, c : c + 5] = 12.0
    e0 = gs.counts(np.zeros(gs.shape), 0.0).astype(float)
    g1 = gs.counts(q, 1.0).astype(float) - e0
    zs = CarpetSensor(SensorConfig(frontend=FrontEndConfig(adc_bits=10), crosstalk=cfg.crosstalk.__class__(
        line_resistance_ohm=500.0)).ideal(), seed=7)
    z0 = zs.counts(np.zeros(zs.shape), 0.0).astype(float)
    two = np.zeros(zs.shape)
    two[40:52, 10:40] = 8.0
    two[40:52, 55:85] = 8.0
    z1 = zs.counts(two, 1.0).astype(float) - z0
    fig, ax = plt.subplots(1, 2, figsize=(11, 4.6))
    im = ax[0].imshow(g1, cmap="viridis")
    ax[0].set_title("floating lines: ghost at the fourth corner")
    fig.colorbar(im, ax=ax[0], label="Δcounts")
    im = ax[1].imshow(z1, cmap="viridis")
    ax[1].set_title("R = 500 Ω: two loads on the same rows read low")
    fig.colorbar(im, ax=ax[1], label="Δcounts")
    fig.tight_layout()
    fig.savefig(out / "crosstalk.png", dpi=80)
    plt.close(fig)


if __name__ == "__main__":
    main(*sys.argv[1:])

"""Model input preparation shared by training and the board (numpy only).

The model sees ONE person's calibrated pressure (the other people's sensels zeroed),
normalised as ``x = log1p(p / 1 kPa)`` (NORMALISATION, recorded in every bundle manifest):
0 kPa → 0, the ~14 kPa saturation of the sensor → 2.7, so no sensel dominates.

The pelvis translation is predicted relative to the person's centre of pressure (CoP) in
the target frame: ``transl_m = transl_rel_m + (CoP_x, CoP_y, 0)``, CoP in carpet metres
(origin at the outer corner of sensel (0, 0), x along columns, y along rows).
"""

from __future__ import annotations

import numpy as np

NORMALISATION = {"kind": "log1p", "scale_kpa": 1.0, "formula": "x = log1p(pressure_kpa / scale_kpa), negatives clipped to 0"}


def check_finite(pressure_kpa: np.ndarray, what: str = "pressure_kpa") -> np.ndarray:
    """Return ``pressure_kpa`` as an array, or raise ValueError if any value is NaN or ±∞.

    NaN and ∞ are rejected upstream, never normalised: ``normalise_kpa`` would pass them
    through (log1p(NaN) = NaN, log1p(∞) = ∞) into the encoder, and the centre of pressure of
    a frame holding one ∞ is NaN. The scene's frame check masks or rejects such sensels first;
    this is the last gate before the model.
    """
    p = np.asarray(pressure_kpa)
    bad = ~np.isfinite(p)
    if bad.any():
        nan = int(np.isnan(p).sum())
        raise ValueError(f"{what} holds {nan} NaN and {int(bad.sum()) - nan} infinite value(s) of {p.size} "
                         f"(first at index {tuple(int(i) for i in np.argwhere(bad)[0])}); reject the frame before "
                         "inference (edge.scene.check_frame masks or rejects NaN/∞ sensels)")
    return p


def normalise_kpa(pressure_kpa: np.ndarray, scale_kpa: float = 1.0) -> np.ndarray:
    """(…,H,W) kPa → model input (same shape) float32.

    Negatives read as 0. NaN and +∞ pass through unchanged: check them with :func:`check_finite`
    first (``ModelBundle.normalise`` and ``ModelBundle.encode`` refuse them).
    """
    return np.log1p(np.maximum(np.asarray(pressure_kpa, np.float32), 0.0) / np.float32(scale_kpa)).astype(np.float32)


def center_of_pressure_m(pressure_kpa: np.ndarray, pitch_m: float) -> np.ndarray:
    """(…,H,W) → (…,2) pressure-weighted sensel centre (x, y) in carpet metres; the carpet centre if empty.

    Negatives read as 0, so a frame of zeros or negatives is empty. The result is always inside
    [pitch/2, (W − ½)·pitch] × [pitch/2, (H − ½)·pitch] for finite input (NaN/∞: see check_finite).
    """
    p = np.maximum(np.asarray(pressure_kpa, np.float64), 0.0)
    h, w = p.shape[-2:]
    total = p.sum((-2, -1))
    xs = (np.arange(w) + 0.5) * pitch_m
    ys = (np.arange(h) + 0.5) * pitch_m
    safe = np.where(total > 0, total, 1.0)
    x = (p.sum(-2) * xs).sum(-1) / safe
    y = (p.sum(-1) * ys).sum(-1) / safe
    x = np.where(total > 0, x, w * pitch_m / 2)
    y = np.where(total > 0, y, h * pitch_m / 2)
    return np.stack([x, y], -1)

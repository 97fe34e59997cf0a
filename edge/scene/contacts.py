"""Contact detection: two thresholds with hysteresis, 8-connected labels, blob features.

A contact is an 8-connected component of ``pressure > grow_kpa`` that contains at least
one sensel ``> start_kpa`` (a seed): one ``ndimage.label`` of the low mask, then keep
the components that a seed falls in. Features come from ``np.bincount`` over the
labels, so the cost does not grow with the number of blobs.

Coordinates follow the carpet frame: sensel (r, c) centre = ((c + 0.5)·pitch, (r + 0.5)·pitch).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

EIGHT = np.ones((3, 3), dtype=bool)


@dataclass(frozen=True, slots=True)
class Blob:
    """One contact. ``label`` is its value in the label image (1-based)."""

    label: int
    area_m2: float
    force_n: float
    cop_m: np.ndarray  # (2,) x, y: force-weighted centre in the carpet frame
    bbox: tuple[slice, slice]  # rows, cols of the label image


def sensel_centres_m(rows: int, cols: int, pitch_m: float) -> tuple[np.ndarray, np.ndarray]:
    """x (H, W) and y (H, W) float32 of sensel centres in metres."""
    ys, xs = np.mgrid[0:rows, 0:cols].astype(np.float32)
    return (xs + 0.5) * np.float32(pitch_m), (ys + 0.5) * np.float32(pitch_m)


def detect_contacts(
    pressure_kpa: np.ndarray,
    start_kpa: float | np.ndarray,
    grow_kpa: float | np.ndarray,
    pitch_m: float,
    min_area_sensels: int,
    x_m: np.ndarray,
    y_m: np.ndarray,
    loaded: np.ndarray | None = None,
) -> tuple[np.ndarray, list[Blob]]:
    """Filtered pressure (H, W) → (labels (H, W) int32 with 0 = no contact, blobs in label order).

    start_kpa, grow_kpa: scalars or (H, W) per-sensel thresholds. x_m, y_m: sensel centres.
    loaded: (H, W) bool of sensels that count towards a blob's area (default: all of the blob).
    Smoothing widens a contact, so the pipeline passes "unsmoothed pressure > start" here.
    """
    low = pressure_kpa > grow_kpa
    lab, n = ndimage.label(low, structure=EIGHT)
    if n == 0:
        return lab, []
    seeded = np.zeros(n + 1, dtype=bool)
    seeded[lab[pressure_kpa > start_kpa]] = True
    seeded[0] = False
    flat = lab.reshape(-1)
    count = np.bincount(flat, minlength=n + 1)
    keep = seeded & (count >= min_area_sensels)
    k = int(keep.sum())
    if k == 0:
        return np.zeros_like(lab), []
    if k < n:
        lut = np.zeros(n + 1, dtype=lab.dtype)
        lut[keep] = np.arange(1, k + 1, dtype=lab.dtype)
        lab = lut[lab]
        flat = lab.reshape(-1)
        count = count[keep]
    else:
        count = count[1:]
    if loaded is not None:
        count = np.bincount(flat, weights=loaded.reshape(-1), minlength=k + 1)[1:]
    p = pressure_kpa.reshape(-1)
    w = np.bincount(flat, weights=p, minlength=k + 1)[1:]
    wx = np.bincount(flat, weights=p * x_m.reshape(-1), minlength=k + 1)[1:]
    wy = np.bincount(flat, weights=p * y_m.reshape(-1), minlength=k + 1)[1:]
    sensel_m2 = pitch_m * pitch_m
    boxes = ndimage.find_objects(lab)
    blobs = []
    for i in range(k):
        wi = max(w[i], 1e-12)
        blobs.append(Blob(label=i + 1, area_m2=float(count[i] * sensel_m2), force_n=float(w[i] * sensel_m2 * 1e3),
                          cop_m=np.array([wx[i] / wi, wy[i] / wi]), bbox=boxes[i]))
    return lab, blobs

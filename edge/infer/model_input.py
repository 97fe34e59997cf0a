"""One person's model input, prepared exactly as the training inputs were (export/README.md, "Decisions").

Training fed the encoder the simulator's true pressure through ``export.data.corrupt``:
gain and noise on the person's loaded sensels, readings below 0.2 kPa set to 0, clipped at
14 kPa, other people's sensels zeroed, then ``log1p(p / 1 kPa)``. On the board the gain and
noise are the real sensor's, so what remains to reproduce is::

    p = calibrated kPa, masked sensels filled           (the scene's own fill, no spatial filter)
    p = p · person.mask                                 (other people's sensels → 0)
    p = 0 where p < 0.2 kPa                             (the training floor; negatives too)
    p = min(p, 14 kPa)                                  (the training saturation)
    x = bundle.normalise(p)                             (log1p(p / 1 kPa), from the manifest)
    origin = bundle.origin_m(p)                         (CoP of the same p, z = 0)

The pressure is taken BEFORE the scene's 3×3 median, Gaussian and EMA: training never saw
them (they widen and soften contacts: the 3×3 median alone removes ~4 % of a foot's force at
19 mm pitch), and the encoder learned from unfiltered sensels. The scene's filtered frame is
used only to find people and their masks; salt noise outside a person's mask never reaches
the model, and inside it the floor removes the common small spikes.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from edge.infer.bundle import ModelBundle

FLOOR_KPA = 0.2  # export.data.corrupt: readings below this are 0 (what a calibrated board reads)
SATURATION_KPA = 14.0  # export.data.SATURATION_KPA


def input_limits(manifest: dict[str, Any]) -> tuple[float, float]:
    """(floor_kpa, saturation_kpa): the manifest's ``input`` values when it records them, else training's."""
    inp = manifest.get("input", {}) if isinstance(manifest, dict) else {}
    return float(inp.get("floor_kpa", FLOOR_KPA)), float(inp.get("saturation_kpa", SATURATION_KPA))


def person_pressure_kpa(pressure_kpa: np.ndarray, mask: np.ndarray, floor_kpa: float = FLOOR_KPA,
                        saturation_kpa: float = SATURATION_KPA) -> np.ndarray:
    """(H, W) frame kPa, (H, W) bool person mask → (H, W) float32: that person's pressure, as in training."""
    p = np.where(mask, pressure_kpa, np.float32(0.0)).astype(np.float32, copy=False)
    p[p < floor_kpa] = 0.0
    np.minimum(p, np.float32(saturation_kpa), out=p)
    return p


def batch_inputs(bundle: ModelBundle, pressure_kpa: np.ndarray, masks: list[np.ndarray]) -> tuple[np.ndarray, np.ndarray]:
    """N people → encoder input (N, 1, H, W) float32 and translation origins (N, 3) (CoP of the same input)."""
    floor, sat = input_limits(bundle.manifest)
    people = np.stack([person_pressure_kpa(pressure_kpa, m, floor, sat) for m in masks])
    return bundle.normalise(people)[:, None], bundle.origin_m(people).astype(np.float32)


__all__ = ["FLOOR_KPA", "SATURATION_KPA", "batch_inputs", "input_limits", "person_pressure_kpa"]

"""What the scene hands to inference for one valid frame (edge.infer.PeopleInference.step).

    frame = tracker.update(pressure_kpa, t_s, masks=unusable)
    if frame.valid:
        step = people_inference.step(frame.handover)

Inference needs three things and reads nothing else of the scene:

- ``filled_kpa``: the calibrated frame with masked (and tolerated non-finite) sensels filled
  the scene's way, BEFORE its temporal and spatial filters: the model was trained on
  unfiltered sensels (edge/infer/model_input.py);
- ``people``: the confirmed people of this frame, each with its track id, its (H, W) mask
  and whether its pressure is still;
- ``held_track_ids``: every track the scene still holds, coasting ones included, so a
  feature window lives exactly as long as its track.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True, slots=True)
class PersonObservation:
    """One confirmed person in one frame.

    cop_m, force_n: one-euro filtered centre of pressure (x, y in the carpet frame) and total force;
    cop_raw_m, force_raw_n: this frame's measurement, integrated over ``mask`` on the pressure before
    the spatial filters (the 3×3 median erodes thin contacts); area_m2: contact area;
    mask: (H, W) bool, the person's contacts grown by mask_margin_mm; bbox: (rows, cols) slices of the mask;
    still: pressure under the person unchanged within noise since their last non-still frame.
    """

    track_id: int
    cop_m: np.ndarray
    force_n: float
    cop_raw_m: np.ndarray
    force_raw_n: float
    area_m2: float
    velocity_m_s: np.ndarray
    mask: np.ndarray
    bbox: tuple[slice, slice]
    contacts: int
    still: bool
    age_s: float


@dataclass(frozen=True, slots=True)
class PeopleHandover:
    """filled_kpa: (H, W) float32 kPa; people: confirmed people in scene order; held_track_ids: live tracks."""

    filled_kpa: np.ndarray
    people: tuple[PersonObservation, ...]
    held_track_ids: frozenset[int]


__all__ = ["PeopleHandover", "PersonObservation"]

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
from typing import TYPE_CHECKING

import numpy as np

if TYPE_CHECKING:
    from edge.scene.pipeline import PersonObservation


@dataclass(frozen=True, slots=True)
class PeopleHandover:
    """filled_kpa: (H, W) float32 kPa; people: confirmed people in scene order; held_track_ids: live tracks."""

    filled_kpa: np.ndarray
    people: tuple[PersonObservation, ...]
    held_track_ids: frozenset[int]


__all__ = ["PeopleHandover"]

"""What the contact model returns: one person's contact (``ContactResult``) and a scene's sum."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np


@dataclass
class ContactResult:
    """One person's contact with the carpet (one frame)."""

    pressure_kpa: np.ndarray  # (H, W) float32: true pressure sampled at the sensels
    contact_mask: np.ndarray  # (H, W) bool: pressure_kpa > the model's contact threshold
    force_n: float  # vertical force landing on the carpet (fine grid)
    force_total_n: float  # vertical force the body exerts in all (on + off the carpet)
    target_force_n: float  # m·(g + a_z), what force_total_n was solved to
    force_off_carpet_n: float  # lost beyond the carpet's edges
    cop_m: np.ndarray  # (2,) centre of pressure of the on-carpet force (NaN if none)
    cop_total_m: np.ndarray  # (2,) centre of pressure of the whole force (NaN if none)
    target_cop_m: np.ndarray | None  # (2,) where the COP was made to be (None: free)
    com_m: np.ndarray  # (3,) centre of mass used
    mass_kg: float
    balanced: bool  # COP reached the target (or no target asked); False: see cop_error_m
    cop_error_m: float  # |cop_total − target_cop| (0 when no target)
    airborne: bool  # lowest point above the floor by more than max_gap, or target ≤ 0
    indentation_mm: float  # deepest penetration into the compliant layer
    slope: np.ndarray  # (2,) tilt of the indentation plane (dz/dx, dz/dy)
    contact_area_m2: float  # fine-grid contact area (whole body, also off the carpet)
    sensel_force_n: float  # Σ pressure_kpa·pitch²: what perfect sensels would sum to
    iterations: int
    fine_pressure_kpa: np.ndarray | None = None  # (ny, nx) with keep_fine=True
    fine_origin: tuple[int, int] | None = None  # lattice index (j0, i0) of fine[0, 0]
    fine_cell_m: float | None = None
    info: dict = field(default_factory=dict)

    @property
    def off_carpet_fraction(self) -> float:
        return self.force_off_carpet_n / self.force_total_n if self.force_total_n > 0 else 0.0


@dataclass
class SceneResult:
    pressure_kpa: np.ndarray  # (H, W) float32, the sum of everyone's field
    person_index: np.ndarray  # (H, W) int8: whose pressure dominates a contact sensel, −1 none
    people: list  # the ContactResult of each person

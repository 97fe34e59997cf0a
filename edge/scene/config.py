"""Scene configuration: one typed dataclass, every field in physical units.

Everything physical is given in mm, m, cm², kPa, N, s or Hz and converted with the
carpet's pitch when a ``SceneTracker`` is built, so the same configuration serves a
96×96, 48×48 or 32×32 carpet. ``SceneConfig.from_dict`` rejects unknown keys and
wrong types with a message that lists what is accepted; ``SceneConfig.describe()``
returns the documentation of every field.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any


def _f(default: Any, doc: str) -> Any:
    return field(default=default, metadata={"doc": doc})


@dataclass(frozen=True)
class SceneConfig:
    """Filtering, contact detection, grouping and tracking settings (see ``describe()``)."""

    # --- frame validation -----------------------------------------------------------
    min_pressure_kpa: float = _f(-20.0, "a sensel below this (after calibration) rejects the frame as out_of_range")
    max_pressure_kpa: float = _f(2000.0, "a sensel above this rejects the frame as out_of_range (feet peak at ~800 kPa)")
    max_total_force_n: float = _f(8000.0, "total force above this rejects the frame as implausible_force (~8 adults)")
    min_total_force_n: float = _f(-500.0, "total force below this rejects the frame as implausible_force")
    max_nonfinite_fraction: float = _f(
        0.01, "NaN/Inf sensels up to this fraction of the carpet are filled like masked ones; more rejects as non_finite")
    # --- filters (each can be switched off) -------------------------------------------
    temporal_median: bool = _f(False, "median of the last 3 frames per sensel (kills one-frame glitches, adds 1 frame of lag to steps)")
    fill_masked: bool = _f(True, "replace masked (unusable) sensels by the mean of their usable 8-neighbours")
    fill_max_distance_mm: float = _f(
        40.0, "masked sensels farther than this from a usable one take its nearest value only up to here; beyond, 0")
    median_3x3: bool = _f(True, "3×3 spatial median against salt noise")
    median_max_pitch_mm: float = _f(
        25.0, "run the 3×3 median only at pitches up to this: at a coarser pitch 3 sensels are wider than a foot "
              "(~9 cm) and it would erase it")
    gaussian_sigma_mm: float = _f(13.3, "Gaussian smoothing σ (0.7 sensel at 19.05 mm); 0 switches it off; skipped below 0.3 sensel")
    ema_tau_s: float = _f(0.05, "time constant of the per-sensel exponential moving average; 0 switches it off")
    # --- contact detection -----------------------------------------------------------
    noise_kpa: float | None = _f(
        None, "σ of the sensel noise in kPa; None estimates it online (1.4826·MAD of contact-free sensels, refreshed each noise_update_s)")
    noise_update_s: float = _f(1.0, "how often the online noise estimate is refreshed")
    start_sigmas: float = _f(5.0, "a contact starts where filtered pressure exceeds start_sigmas·noise ...")
    start_min_kpa: float = _f(0.3, "... or this, whichever is larger")
    grow_fraction: float = _f(0.5, "a contact grows (8-connected) over sensels above this fraction of the start threshold")
    min_blob_area_cm2: float = _f(6.0, "contacts smaller than this are ignored")
    # --- grouping blobs into people -----------------------------------------------------
    group_radius_m: float = _f(0.6, "contacts no track reaches belong to one new person when all lie within this of each "
                                    "other (centre to centre)")
    reach_m: float = _f(0.6, "a new contact joins a body within this beyond the body's extent (its farthest contact from "
                             "its centre): a stride, a hand put down")
    extent_memory_s: float = _f(2.0, "a body's extent is forgotten with this time constant (someone who lay down and stood up)")
    split_distance_m: float = _f(1.5, "one track's contacts in parts farther apart than this (centre to centre) for "
                                      "split_s become two tracks; a push-up spans 1.3 m")
    split_s: float = _f(0.5, "how long a split must be seen (parts too far apart, or a part carrying more than the "
                             "body's weight) before it is made")
    newcomer_s: float = _f(0.5, "contacts that joined a body at most this long before it began to carry more than its "
                                "weight can be split off as someone who stepped in beside it")
    weight_tau_s: float = _f(3.0, "time constant of a body's weight estimate (the force of its contacts)")
    min_person_force_n: float = _f(80.0, "a new person needs at least this total force (a child of 8 kg) to start a track; "
                                         "a track carrying this much more than its weight has someone beside it")
    mask_margin_mm: float = _f(40.0, "each person's mask is their contacts grown by this margin (never onto another person's contacts)")
    # --- tracking -----------------------------------------------------------------------
    track_gate_m: float = _f(0.5, "an unassigned person matches a track (Hungarian, on distance) only within this of its prediction")
    max_speed_m_s: float = _f(2.5, "the gate of a coasting track grows at this speed; velocities are clipped to it")
    birth_frames: int = _f(3, "a track is reported after this many consecutive observations")
    coast_s: float = _f(0.6, "a confirmed track survives this long unobserved before it is lost")
    reid_s: float = _f(5.0, "a new track within reid_radius_m of where a track was lost less than this ago takes its id; 0 = off")
    reid_radius_m: float = _f(0.6, "see reid_s")
    # --- one-euro filter on each person's centre of pressure and force ------------------
    cop_min_cutoff_hz: float = _f(1.0, "one-euro minimum cutoff for the centre of pressure")
    cop_beta_hz_per_m_s: float = _f(2.0, "one-euro speed coefficient for the centre of pressure (cutoff grows by this per m/s)")
    force_min_cutoff_hz: float = _f(1.0, "one-euro minimum cutoff for the force")
    force_beta_hz_per_n_s: float = _f(0.002, "one-euro speed coefficient for the force (cutoff grows by this per N/s)")
    derivative_cutoff_hz: float = _f(1.0, "one-euro cutoff of the derivative estimate")
    # --- stillness ---------------------------------------------------------------------
    still_rms_kpa: float | None = _f(
        None, "a person is still when the RMS change of their pressure since the last non-still frame is below this; "
              "None = max(3·noise, 0.05 kPa)")

    def __post_init__(self) -> None:
        for f in dataclasses.fields(self):
            v = getattr(self, f.name)
            if f.type == "bool":
                if not isinstance(v, bool):
                    raise ValueError(f"{f.name} must be true or false, got {v!r}")
            elif f.type == "int":
                if isinstance(v, bool) or not isinstance(v, int) or v < 1:
                    raise ValueError(f"{f.name} must be a positive integer, got {v!r}")
            elif v is None and "None" in f.type:
                continue
            elif isinstance(v, bool) or not isinstance(v, (int, float)) or not math.isfinite(v):
                raise ValueError(f"{f.name} must be a finite number, got {v!r}")
        nonneg = ("fill_max_distance_mm", "median_max_pitch_mm", "gaussian_sigma_mm", "ema_tau_s", "reid_s", "mask_margin_mm",
                  "min_blob_area_cm2", "min_person_force_n", "start_min_kpa", "max_nonfinite_fraction")
        for name in nonneg:
            if getattr(self, name) < 0:
                raise ValueError(f"{name} must be ≥ 0, got {getattr(self, name)}")
        positive = ("noise_update_s", "start_sigmas", "group_radius_m", "reach_m", "extent_memory_s",
                    "split_distance_m", "split_s", "newcomer_s", "weight_tau_s", "track_gate_m",
                    "max_speed_m_s", "coast_s", "reid_radius_m", "cop_min_cutoff_hz", "force_min_cutoff_hz", "derivative_cutoff_hz")
        for name in positive:
            if getattr(self, name) <= 0:
                raise ValueError(f"{name} must be > 0, got {getattr(self, name)}")
        if not 0 < self.grow_fraction <= 1:
            raise ValueError(f"grow_fraction must be in (0, 1], got {self.grow_fraction}")
        if self.noise_kpa is not None and self.noise_kpa <= 0:
            raise ValueError(f"noise_kpa must be > 0 or None, got {self.noise_kpa}")
        if self.min_pressure_kpa >= self.max_pressure_kpa or self.min_total_force_n >= self.max_total_force_n:
            raise ValueError("min_pressure_kpa/min_total_force_n must be below their max_ counterparts")

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> SceneConfig:
        """Build from a plain mapping (parsed YAML/JSON); unknown keys are a ValueError naming the accepted ones."""
        known = {f.name for f in dataclasses.fields(cls)}
        unknown = sorted(set(values) - known)
        if unknown:
            raise ValueError(f"unknown scene option(s) {', '.join(unknown)}; accepted: {', '.join(sorted(known))}")
        kwargs = {}
        for f in dataclasses.fields(cls):
            if f.name in values:
                v = values[f.name]
                if f.type == "float" and isinstance(v, int) and not isinstance(v, bool):
                    v = float(v)
                kwargs[f.name] = v
        return cls(**kwargs)

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

    @classmethod
    def describe(cls) -> dict[str, str]:
        """Field name → one-line documentation (with its default)."""
        return {f.name: f"{f.metadata['doc']} (default {f.default!r})" for f in dataclasses.fields(cls)}

"""Scene configuration: one typed dataclass, every field in physical units.

Everything physical is given in mm, m, cm², kPa, N, s or Hz and converted with the
carpet's pitch when a ``SceneTracker`` is built, so the same configuration serves a
96×96, 48×48 or 32×32 carpet. Built on :class:`cavatar_common.config.StrictConfig`, as the
runtime's own configuration is: ``SceneConfig.from_dict`` rejects unknown keys and wrong
types with a message that lists what is accepted; ``SceneConfig.describe()`` returns the
documentation of every field; each field carries its own check.
"""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass
from typing import Any, ClassVar

from cavatar_common.config import StrictConfig, at_least_one, at_least_zero, described, positive


def _fraction(v: Any) -> str | None:
    return None if 0 < v <= 1 else "must be in (0, 1]"


@dataclass(frozen=True)
class SceneConfig(StrictConfig):
    """Filtering, contact detection, grouping and tracking settings (see ``describe()``)."""

    WHAT: ClassVar[str] = "scene"

    # --- frame validation -----------------------------------------------------------
    min_pressure_kpa: float = described(-20.0, "a sensel below this (after calibration) rejects the frame as out_of_range")
    max_pressure_kpa: float = described(2000.0, "a sensel above this rejects the frame as out_of_range (feet peak at ~800 kPa)")
    max_total_force_n: float = described(8000.0, "total force above this rejects the frame as implausible_force (~8 adults)")
    min_total_force_n: float = described(-500.0, "total force below this rejects the frame as implausible_force")
    max_nonfinite_fraction: float = described(
        0.01, "NaN/Inf sensels up to this fraction of the carpet are filled like masked ones; more rejects as non_finite", at_least_zero)
    # --- filters (each can be switched off) -------------------------------------------
    temporal_median: bool = described(
        False, "median of the last 3 frames per sensel (kills one-frame glitches, adds 1 frame of lag to steps)")
    fill_masked: bool = described(True, "replace masked (unusable) sensels by the mean of their usable 8-neighbours")
    fill_max_distance_mm: float = described(
        40.0, "masked sensels farther than this from a usable one take its nearest "
              "value only up to here; beyond, 0", at_least_zero)
    median_3x3: bool = described(True, "3×3 spatial median against salt noise")
    median_max_pitch_mm: float = described(
        25.0, "run the 3×3 median only at pitches up to this: at a coarser pitch 3 sensels are wider than a foot "
              "(~9 cm) and it would erase it", at_least_zero)
    gaussian_sigma_mm: float = described(
        13.3, "Gaussian smoothing σ (0.7 sensel at 19.05 mm); 0 switches it off; "
              "skipped below 0.3 sensel", at_least_zero)
    ema_tau_s: float = described(0.05, "time constant of the per-sensel exponential moving average; 0 switches it off", at_least_zero)
    # --- contact detection -----------------------------------------------------------
    noise_kpa: float | None = described(
        None, "σ of the sensel noise in kPa; None estimates it online (1.4826·MAD of contact-free sensels, "
              "refreshed each noise_update_s)", positive)
    noise_update_s: float = described(1.0, "how often the online noise estimate is refreshed", positive)
    start_sigmas: float = described(5.0, "a contact starts where filtered pressure exceeds start_sigmas·noise ...", positive)
    start_min_kpa: float = described(0.3, "... or this, whichever is larger", at_least_zero)
    grow_fraction: float = described(
        0.5, "a contact grows (8-connected) over sensels above this fraction of the start threshold", _fraction)
    min_blob_area_cm2: float = described(6.0, "contacts smaller than this are ignored", at_least_zero)
    # --- grouping blobs into people -----------------------------------------------------
    group_radius_m: float = described(
        0.6, "contacts no track reaches belong to one new person when all lie within this "
             "of each other (centre to centre)", positive)
    reach_m: float = described(
        0.6, "a new contact joins a body within this beyond the body's extent (its farthest "
             "contact from its centre): a stride, a hand put down", positive)
    extent_memory_s: float = described(
        2.0, "a body's extent is forgotten with this time constant (someone who lay down and stood up)", positive)
    split_distance_m: float = described(
        1.5, "one track's contacts in parts farther apart than this (centre to centre) "
             "for split_s become two tracks; a push-up spans 1.3 m", positive)
    split_s: float = described(
        0.5, "how long a split must be seen (parts too far apart, or a part carrying more than "
             "the body's weight) before it is made", positive)
    newcomer_s: float = described(
        0.5, "contacts that joined a body at most this long before it began to carry more than "
             "its weight can be split off as someone who stepped in beside it", positive)
    weight_tau_s: float = described(3.0, "time constant of a body's weight estimate (the force of its contacts)", positive)
    min_person_force_n: float = described(
        80.0, "a new person needs at least this total force (a child of 8 kg) to start "
              "a track; a track carrying this much more than its weight has someone beside it", at_least_zero)
    mask_margin_mm: float = described(
        40.0, "each person's mask is their contacts grown by this margin (never onto "
              "another person's contacts)", at_least_zero)
    # --- tracking -----------------------------------------------------------------------
    track_gate_m: float = described(
        0.5, "an unassigned person matches a track (Hungarian, on distance) only within this "
             "of its prediction", positive)
    max_speed_m_s: float = described(2.5, "the gate of a coasting track grows at this speed; velocities are clipped to it", positive)
    birth_frames: int = described(3, "a track is reported after this many consecutive observations", at_least_one)
    coast_s: float = described(0.6, "a confirmed track survives this long unobserved before it is lost", positive)
    reid_s: float = described(
        5.0, "a new track within reid_radius_m of where a track was lost less than this ago takes "
             "its id; 0 = off", at_least_zero)
    reid_radius_m: float = described(0.6, "see reid_s", positive)
    # --- one-euro filter on each person's centre of pressure and force ------------------
    cop_min_cutoff_hz: float = described(1.0, "one-euro minimum cutoff for the centre of pressure", positive)
    cop_beta_hz_per_m_s: float = described(2.0, "one-euro speed coefficient for the centre of pressure (cutoff grows by this per m/s)")
    force_min_cutoff_hz: float = described(1.0, "one-euro minimum cutoff for the force", positive)
    force_beta_hz_per_n_s: float = described(0.002, "one-euro speed coefficient for the force (cutoff grows by this per N/s)")
    derivative_cutoff_hz: float = described(1.0, "one-euro cutoff of the derivative estimate", positive)
    # --- stillness ---------------------------------------------------------------------
    still_rms_kpa: float | None = described(
        None, "a person is still when the RMS change of their pressure since the last non-still frame is below "
              "this; None = max(3·noise, 0.05 kPa)")

    def __post_init__(self) -> None:
        self.check_fields()
        if self.min_pressure_kpa >= self.max_pressure_kpa or self.min_total_force_n >= self.max_total_force_n:
            raise ValueError("min_pressure_kpa/min_total_force_n must be below their max_ counterparts")

    def to_dict(self) -> dict[str, Any]:
        return dataclasses.asdict(self)

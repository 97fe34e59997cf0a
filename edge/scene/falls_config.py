"""The fall detector's configuration: thresholds in physical units (``[events]`` in the TOML; docs/falls.md)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

from cavatar_common.config import StrictConfig, at_least_zero, described


def _f(default, doc: str):
    """A field of FallConfig: every number is a finite value ≥ 0."""
    return described(default, doc, at_least_zero if isinstance(default, float) else None)


@dataclass(frozen=True)
class FallConfig(StrictConfig):
    """Fall and person-down events: thresholds in physical units (docs/falls.md)."""

    WHAT: ClassVar[str] = "events"

    enabled: bool = _f(True, "detect falls and people down and publish them as events")
    person_down_s: float = _f(30.0, "person_down is raised after someone who arrived on the floor like a fall has "
                                    "been there this long")
    confirm_s: float = _f(0.8, "fall is raised once the body has stayed on the floor this long (fewer false alarms, "
                               "later alerts)")
    fall_window_s: float = _f(2.5, "a fall: from on the feet to on the floor within this (a slow collapse takes up "
                                   "to ~2.5 s; lying down on purpose takes longer)")
    down_window_s: float = _f(6.0, "person_down also for arrivals up to this slow (a slower, controlled lie-down "
                                   "never raises it)")
    release_s: float = _f(2.0, "events clear when nobody has been on the floor there for this long")
    person_min_force_n: float = _f(150.0, "a body on the floor carries at least this load to count as a person (the "
                                          "calibrated load of a standing adult reads ≈ 250–700 N)")
    merge_radius_m: float = _f(1.5, "tracks whose centres of pressure are closer than this form one body (a fallen "
                                    "person's feet and trunk often land as two tracks); two people on their feet "
                                    "never merge")
    feet_min_force_n: float = _f(60.0, "on the feet: at least this load (a person seated on a chair beside the "
                                       "carpet has only their feet on it)")
    feet_max_area_m2: float = _f(0.06, "on the feet: contact area at most this (two feet ≈ 0.02–0.045 m², a heavy "
                                       "person's up to ≈ 0.055)")
    feet_max_length_m: float = _f(0.9, "on the feet: pressure length (4 standard deviations, major axis) at most this")
    floor_min_area_m2: float = _f(0.05, "on the floor (lying): contact area at least this (lying ≈ 0.05–0.11 m²)")
    floor_min_length_m: float = _f(0.0, "on the floor (lying): pressure length at least this")
    floor_long_m: float = _f(1.6, "... or a body this long (feet to shoulders on the floor) ...")
    floor_long_min_area_m2: float = _f(0.025, "... with at least this contact area ...")
    floor_long_max_kpa: float = _f(10.0, "... pressed at most this on average (a lying body spreads its weight; the "
                                         "feet of a deep lunge or a plank's hands and feet carry it on small prints)")
    floor_max_kpa: float = _f(14.0, "a large print pressed harder than this on average is feet, not a body lying (a "
                                    "heavy person's feet can cover 0.052 m² at 17.5 kPa; lying reads ≈ 4–9 kPa, "
                                    "sitting ≈ 11)")
    floor_stay_min_area_m2: float = _f(0.04, "still on the floor (once there): contact area at least this")
    floor_min_kpa: float = _f(3.5, "on the floor: the load over the contact area at least this (an adult lying "
                                   "presses ≈ 4–9 kPa on average; a pet of ≤ 30 kg lying spreads ≈ 2 kPa, a bag less)")
    fall_radius_m: float = _f(1.6, "the body on its feet must have stood within this of where the load now lies")
    min_shift_m: float = _f(0.45, "... and at least this far from it: the load moved by about a body's height "
                                  "(sitting down or a bag dropped beside someone moves it less)")
    collapse_window_s: float = _f(1.0, "... or, nearer than min_shift_m, a collapse where they stood: the body landed within "
                                       "this of the stance ending ...")
    collapse_s: float = _f(4.0, "... having carried a standing load at most this before landing (a deliberate "
                                "lie-down stays low, kneeling or sitting, for longer) ...")
    collapse_min_length_m: float = _f(1.2, "... and landed at full length, pressure length at least this from landing "
                                            "on (sitting, kneeling, getting down for a push-up, or a bag or a pet beside "
                                            "someone's feet, is shorter)")
    collapse_min_area_m2: float = _f(0.10, "... or landed this large (a body crumpled on its side: trunk, hips and "
                                          "legs down together)")
    max_load_ratio: float = _f(2.5, "... and carried at least the lying load divided by this (lighter: the body was "
                                    "in the air)")
    seated_s: float = _f(1.5, "a still, light footprint held this long is someone seated on a chair beside the carpet "
                              "(only their feet on it) ...")
    seated_load_ratio: float = _f(3.5, "... when the body that lands carries at least this times its load (seated, "
                                       "the feet carry ≈ 15–30 % of the weight): a fall wherever it lands")
    exercise_activities: list[str] = _f(["push_up", "sit_up"], "the model's activities that mark a floor exercise: "
                                                                "no person_down once seen while the body moves ...")
    exercise_s: float = _f(1.5, "... for this long in all (someone lying still is not exercising, whatever the "
                                "model calls the pose)")

    def __post_init__(self) -> None:
        self.check_fields()  # types, and every number finite and ≥ 0
        if self.fall_window_s > self.down_window_s:
            raise ValueError("fall_window_s must not exceed down_window_s")
        if self.person_down_s < self.confirm_s:
            raise ValueError("person_down_s must be at least confirm_s")


__all__ = ["FallConfig"]

"""Procedural human motion for the synthetic carpet (SMPL parameters in the carpet frame).

    from sim.motion import Subject, person_track, scene, ACTIVITIES
    s = Subject.random(3)                                  # betas N(0,1) clipped ±3, style from the seed
    tr = person_track(s, ["squat", "walking"], 10.0, 14.0, rng=1)   # Track
    tr.pose_aa (T,72), tr.transl_m (T,3) (pelvis), tr.betas (10,), tr.activity (T,) index
    into ACTIVITIES, tr.contact (T,6) bool over CONTACT_PARTS (weight-bearing, locked parts)
    sc = scene([Subject.random(i) for i in range(2)], ["squat", "stepping"], 10.0, 14.0,
               carpet_size_m=(1.83, 1.83), rng=7)           # Scene(tracks, rate_hz, carpet_size_m)
    # people ≥ min_gap_m (0.15) apart (any two vertices, top-down, every frame) and on the
    # carpet; ValueError when no arrangement is found (catch it and try other activities).

Upright = +90° about x in pose_aa[0:3], facing −y at heading 0. Known gaps: docs/sim-motion.md.
"""

from sim.motion.activities import ACTIVITIES
from sim.motion.generate import DEFAULT_RATE_HZ, Scene, Style, Subject, Track, person_track
from sim.motion.placement import box_gaps, scene
from sim.motion.rig import CONTACT_PARTS

__all__ = ["ACTIVITIES", "CONTACT_PARTS", "DEFAULT_RATE_HZ", "Scene", "Style", "Subject", "Track", "box_gaps", "person_track", "scene"]

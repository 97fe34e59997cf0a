"""The activities: their names, pacing limits and what every builder shares.

The builders themselves, one keyframe timeline per activity (one segment each, standing →
activity → standing), are in ``sim.motion.upright_activities`` (on the feet) and
``sim.motion.floor_activities`` (down to the floor and back up); walking, which also needs
the body's step length, is ``sim.motion.walking``.

Every builder has the signature ``build(style, rng, seconds, label, pace=None) -> Timeline``: the
timeline starts from and returns to ``keys.BASE`` with both feet down, fills exactly
``seconds`` and labels its frames (``label`` for the activity, "standing" for the lead-in
and lead-out; ``standing_frame`` does this). ``style`` is the subject's ``Style`` (tempo,
amplitude, asymmetry, lead side); ``rng`` draws the per-repetition variety; ``pace`` (a
``sim.motion.pace.Pacer``) lengthens keys that would move the centre of mass up or down
faster than ``VERTICAL_ACC_LIMIT_M_S2`` allows for the activity.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sim.motion.keys import BASE, Timeline, both_feet
from sim.motion.rig import LF, J

ACTIVITIES = (
    "stepping", "bending", "turning", "squat", "twisting", "raising_arms", "lunge",
    "sitting", "push_up", "sit_up", "walking", "standing",
)
STANDING = ACTIVITIES.index("standing")
# Largest vertical COM acceleration a key may ask for (m/s²). Controlled exercises keep the
# floor force within ~0.9–1.1 × body weight (issue 13): under 0.1 g. The limit keeps a margin
# for the template poses' height change running up to ~10 % short of the grounded body's
# (feet flattened and locked by IK) and for repetitions squeezed by up to ~10 % to fill the
# sequence (acceleration ∝ 1/T²). Stepping and lunging move the body more briskly
# (~0.8–1.2 × mg). Sitting, the push-up and the sit-up are paced too and budget their
# repetitions after the paced getting down and up (``lasts_s``): getting down, one repetition
# and getting up take ~9–11 s (sitting) and ~17–19 s (push-up, sit-up), which a sequence gives
# them (``sim.motion.generate.share_time``; datasets extend a sequence that cannot). Sitting was
# left unpaced while the scene split a slow sit-down into two tracks on the board's path; it no
# longer does (tests/edge/scene/test_scene_activities_alone.py).
VERTICAL_ACC_LIMIT_M_S2 = {a: 0.62 for a in ("bending", "squat", "twisting", "raising_arms", "standing", "push_up",
                                              "sitting", "sit_up")} | {"stepping": 1.6, "turning": 1.6, "lunge": 1.6}
FEET = both_feet()

_LR = [(J[n], J[n.replace("left_", "right_")]) for n in (
    "left_hip", "left_knee", "left_ankle", "left_foot", "left_collar", "left_shoulder",
    "left_elbow", "left_wrist", "left_hand",
)]


def mirror(p: np.ndarray) -> np.ndarray:
    """Left ↔ right: swap the limbs and negate the y and z angles everywhere."""
    q = p.copy()
    for a, b in _LR:
        q[a], q[b] = p[b].copy(), p[a].copy()
    q[:, 1:] *= -1
    return q


def styled(p: np.ndarray, style, amp: float = 1.0, ref: np.ndarray = BASE) -> np.ndarray:
    """Scale a pose's difference from ``ref`` by amp·amplitude and the left/right asymmetry."""
    d = (p - ref) * (amp * style.amplitude)
    for a, b in _LR:
        d[a] *= 1.0 + style.asymmetry
        d[b] *= 1.0 - style.asymmetry
    return ref + d


def uniform(rng, lo, hi) -> float:
    """One draw from U(lo, hi) as a float."""
    return float(rng.uniform(lo, hi))


def repeat(tl: Timeline, rep, seconds_left: float, rng, min_reps=1):
    """Append repetitions (rep(tl) appends one) until their duration fills seconds_left."""
    n0 = len(tl.keys)
    d0 = tl.duration_s
    rep(tl)
    per = tl.duration_s - d0
    n = max(min_reps, int(seconds_left / max(per, 1e-3) + 0.1))  # whole repetitions at the subject's own tempo
    for _ in range(n - 1):
        rep(tl)
    return n0


MAX_STRETCH = 1.12  # an activity's keys last at most this much longer than the subject's tempo makes them


def lasts_s(tl: Timeline, add) -> float:
    """How long the keys that ``add(timeline)`` appends would last after tl's last key (on tl's pacer)."""
    scratch = Timeline(pace=tl.pace)
    if tl.keys:
        scratch.keys.append(replace(tl.keys[-1], dur_s=0.0))
    add(scratch)
    return scratch.duration_s


def standing_frame(style, rng, seconds, label, body, lead_in=(0.4, 0.9), lead_out=(0.4, 0.9), pace=None, pace_if_it_fits=False):
    """Standing lead-in, the body of the activity stretched to fit, standing lead-out (pace:
    an optional ``sim.motion.pace.Pacer`` that sets the keys' shortest durations;
    pace_if_it_fits: drop the pacing where the paced body does not fit the sequence, which
    would squeeze it all, and build it again from the same random draws at its own tempo)."""
    tl = Timeline(pace=pace)
    a0, b0 = uniform(rng, *lead_in), uniform(rng, *lead_out)
    a, b = min(a0, 0.15 * seconds), min(b0, 0.15 * seconds)
    tl.add(a, BASE, FEET, LF, label=STANDING)
    first = len(tl.keys)
    slot = seconds - a - b
    state = rng.bit_generator.state
    body(tl, slot)
    own_s = a0 + b0 + tl.duration_s - a  # what the activity needs (as paced), before any squeezing
    if pace_if_it_fits and pace is not None and tl.duration_s - a > slot:
        rng.bit_generator.state = state
        del tl.keys[first:]
        tl.pace = None
        body(tl, slot)
    # Keep the activity's own tempo: stretch by at most MAX_STRETCH and stand for the rest
    # (squeezing is unavoidable when even one repetition does not fit).
    took = tl.duration_s - a
    stretch = min(slot / max(took, 1e-9), MAX_STRETCH)
    tl.scale_to(a + took * stretch, fixed=first)
    tl.tempo_factor, tl.own_s = stretch, own_s
    rest = slot - took * stretch
    if rest > 1e-6:  # a pause before the next activity, still part of this one (repetitions end in pauses too)
        tl.add(rest, BASE, FEET, LF, label=label)
    tl.add(b, BASE, FEET, LF, label=STANDING)
    return tl


HEEL_OFF_DEG = (25.0, 40.0)  # heel raise before a foot leaves the floor (toe-off)

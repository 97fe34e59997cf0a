"""The activities down on the floor and back up as keyframe timelines: sitting, sit_up,
push_up (builders as ``sim.motion.activities`` describes), and the floor postures they and
``sim.motion.falls`` share."""

from __future__ import annotations

import numpy as np

from sim.motion.activities import FEET, lasts_s, repeat, standing_frame, styled, uniform
from sim.motion.keys import BASE, contacts, pose
from sim.motion.rig import BACK, BUTT, LF, LH, RF, RH, SETTLE

SQUAT_LOW = pose(root=(25, 0, 0), left_hip=(-120, 0, 12), right_hip=(-120, 0, -12),
                 left_knee=(145, 0, 0), right_knee=(145, 0, 0), spine1=(10, 0, 0), spine2=(5, 0, 0),
                 left_shoulder=(0, -60, -25), right_shoulder=(0, 60, 25), neck=(-10, 0, 0))
SIT_BENT = pose(root=(-18, 0, 0), left_hip=(-105, 0, 10), right_hip=(-105, 0, -10),
                left_knee=(115, 0, 0), right_knee=(115, 0, 0), spine1=(14, 0, 0), spine2=(8, 0, 0), spine3=(5, 0, 0),
                left_shoulder=(-55, 0, -65), right_shoulder=(-55, 0, 65), left_elbow=(0, -35, 0), right_elbow=(0, 35, 0))
SIT_LONG = pose(root=(-8, 0, 0), left_hip=(-88, 0, 6), right_hip=(-88, 0, -6),
                left_knee=(6, 0, 0), right_knee=(6, 0, 0), spine1=(6, 0, 0), spine2=(4, 0, 0),
                left_shoulder=(-30, 0, -70), right_shoulder=(-30, 0, 70), left_elbow=(0, -30, 0), right_elbow=(0, 30, 0))


def crouch(p: np.ndarray, style) -> np.ndarray:
    """A deep template (crouch, squat to the floor) as deep as this person goes: shallower for a
    small range of motion, never deeper than the template (knees would pass 150°)."""
    return styled(p, style, min(1.0, 1.0 / style.amplitude) if style.amplitude > 1.0 else 1.0)


def _get_down(tl, style, label, end_pose, end_contact, end_anchor):
    tm = style.tempo
    tl.add(1.6 * tm, crouch(SQUAT_LOW, style), FEET, LF, label=label)
    tl.add(1.3 * tm, end_pose, FEET, SETTLE, label=label)  # the buttocks come down onto the floor
    tl.add(0.2 * tm, end_pose, end_contact, end_anchor, label=label)


def _get_up(tl, style, label, from_pose, from_contact, from_anchor):
    tm = style.tempo
    tl.add(0.2 * tm, from_pose, from_contact, from_anchor, label=label)
    tl.add(1.3 * tm, crouch(SQUAT_LOW, style), FEET, SETTLE, label=label)  # weight back onto the feet
    tl.add(1.6 * tm, BASE, FEET, LF, label=label)


def sitting(style, rng, seconds, label, pace=None):
    sit_bent = styled(SIT_BENT, style)  # how deep this person folds: hips, knees, lean
    sit = contacts(BUTT, LF, RF)

    def body(tl, left):
        d0 = tl.duration_s
        _get_down(tl, style, label, sit_bent, sit, BUTT)

        def rep(t):
            kind = rng.integers(0, 3)
            if kind == 0:  # lean forward, hug the knees
                p = pose(sit_bent, spine1=(24, 0, 0), spine2=(14, 0, 0), left_shoulder=(-70, -10, -60),
                         right_shoulder=(-70, 10, 60), left_elbow=(0, -60, 0), right_elbow=(0, 60, 0))
            elif kind == 1:  # look around, turn the trunk
                s = 1 if rng.random() < 0.5 else -1
                p = pose(sit_bent, spine2=(8, s * 15, 0), spine3=(5, s * 12, 0), neck=(0, s * 25, 0))
            else:  # lean back a little, arms relaxed
                p = pose(sit_bent, spine1=(4, 0, 0), spine2=(2, 0, 0), left_shoulder=(-20, 0, -70), right_shoulder=(-20, 0, 70))
            d = 1.6 * style.tempo * uniform(rng, 0.8, 1.2)
            t.add(0.5 * d, styled(p, style, 1.0, sit_bent), sit, BUTT, label=label)
            t.add(uniform(rng, 0.3, 1.0), styled(p, style, 1.0, sit_bent), sit, BUTT, label=label)
            t.add(0.5 * d, sit_bent, sit, BUTT, label=label)
        repeat(tl, rep, left - (tl.duration_s - d0) - lasts_s(tl, lambda t: _get_up(t, style, label, sit_bent, sit, BUTT)), rng)
        _get_up(tl, style, label, sit_bent, sit, BUTT)
    return standing_frame(style, rng, seconds, label, body, pace=pace)


LIE_BENT = pose(root=(-88, 0, 0), left_hip=(-50, 0, 8), right_hip=(-50, 0, -8),
                left_knee=(95, 0, 0), right_knee=(95, 0, 0),
                left_shoulder=(-10, -70, -40), right_shoulder=(-10, 70, 40), left_elbow=(0, -110, 0), right_elbow=(0, 110, 0),
                neck=(15, 0, 0))
CURL_UP = pose(root=(-30, 0, 0), left_hip=(-100, 0, 8), right_hip=(-100, 0, -8),
               left_knee=(100, 0, 0), right_knee=(100, 0, 0), spine1=(15, 0, 0), spine2=(15, 0, 0), spine3=(10, 0, 0),
               left_shoulder=(-10, -70, -40), right_shoulder=(-10, 70, 40), left_elbow=(0, -110, 0), right_elbow=(0, 110, 0),
               neck=(20, 0, 0))


def sit_up(style, rng, seconds, label, pace=None):
    sit_bent, lie_bent = styled(SIT_BENT, style), styled(LIE_BENT, style)
    curl = styled(CURL_UP, style, 1.0, LIE_BENT)  # how far this person curls up
    sit = contacts(BUTT, LF, RF)
    lie = contacts(BUTT, BACK, LF, RF)

    def lie_down(tl):
        _get_down(tl, style, label, sit_bent, sit, BUTT)
        tl.add(1.6 * style.tempo, lie_bent, sit, BUTT, label=label)
        tl.add(0.4, lie_bent, lie, BUTT, label=label)  # the back settles on the floor before the first curl

    def get_up(tl):
        tl.add(1.6 * style.tempo, sit_bent, sit, BUTT, label=label)
        _get_up(tl, style, label, sit_bent, sit, BUTT)

    def body(tl, left):
        d0 = tl.duration_s
        lie_down(tl)

        def rep(t):
            a = uniform(rng, 0.75, 1.05)
            up = styled(curl, style, a, lie_bent)
            d = 3.0 * style.tempo * uniform(rng, 0.85, 1.15)
            t.add(0.5 * d, up, sit, BUTT, label=label)
            t.add(uniform(rng, 0.05, 0.3), up, sit, BUTT, label=label)
            t.add(0.5 * d, lie_bent, sit, BUTT, label=label)
            t.add(uniform(rng, 0.1, 0.5), lie_bent, lie, BUTT, label=label)
        repeat(tl, rep, left - (tl.duration_s - d0) - lasts_s(tl, get_up), rng)
        get_up(tl)
    return standing_frame(style, rng, seconds, label, body, pace=pace, pace_if_it_fits=True)


# Push-up: hands flat under the shoulders, body straight on the toes.
CROUCH_HANDS = pose(root=(70, 0, 0), left_hip=(-95, 0, 12), right_hip=(-95, 0, -12),
                    left_knee=(140, 0, 0), right_knee=(140, 0, 0), spine1=(10, 0, 0), spine2=(5, 0, 0),
                    left_shoulder=(-10, -85, -10), right_shoulder=(-10, 85, 10), neck=(-25, 0, 0))
# The plank's arms (shoulders 32°, was 20°) bring the feet nearer the hands: the hands carry 68 % of the
# weight in the audit (was 63.6; published 64–75 %, 69 % in the up position: Suprak 2011, Ebben 2011).
PLANK = pose(root=(70, 0, 0), left_hip=(0, 3, 0), right_hip=(0, -3, 0), left_knee=(10, 0, 0), right_knee=(10, 0, 0),
             left_shoulder=(32, -88, 0), right_shoulder=(32, 88, 0), left_elbow=(0, 0, 0), right_elbow=(0, 0, 0),
             neck=(-25, 0, 0))
PLANK_DOWN = pose(PLANK, root=(84, 0, 0), left_shoulder=(45, -80, 0), right_shoulder=(-45, 80, 0), neck=(-30, 0, 0))
HOP = pose(CROUCH_HANDS, left_hip=(-45, 0, 8), right_hip=(-45, 0, -8), left_knee=(60, 0, 0), right_knee=(60, 0, 0),
           left_shoulder=(5, -87, -5), right_shoulder=(-5, 87, 5))  # legs on their way back, in the air
_TOES = 72.0


def push_up(style, rng, seconds, label, pace=None):
    """Down to a crouch with the hands on the floor, hop both feet back into a plank (hands
    carry the body meanwhile), push-ups, hop the feet forward again, stand up."""
    squat_low, crouch_hands = crouch(SQUAT_LOW, style), crouch(CROUCH_HANDS, style)
    four = contacts(LF, RF, LH, RH)
    hands = contacts(LH, RH)
    toes = (_TOES, _TOES)

    def plank_down(tl):
        tm = style.tempo
        tl.add(1.6 * tm, squat_low, FEET, LF, label=label)
        tl.add(1.0 * tm, crouch_hands, FEET, LF, label=label)
        tl.add(0.2 * tm, crouch_hands, four, LH, label=label)
        tl.add(0.35 * tm, HOP, hands, LH, heel=(30, 30), label=label)
        tl.add(0.35 * tm, PLANK, hands, LH, heel=toes, label=label)
        tl.add(0.3 * tm, PLANK, four, LF, heel=toes, label=label)  # the toes carry the body now

    def get_up(tl):
        tm = style.tempo
        tl.add(0.2 * tm, PLANK, four, LF, heel=toes, label=label)
        tl.add(0.35 * tm, HOP, hands, LH, heel=(30, 30), label=label)
        tl.add(0.35 * tm, crouch_hands, hands, LH, label=label)
        tl.add(0.3 * tm, crouch_hands, four, LH, label=label)
        tl.add(0.2 * tm, crouch_hands, FEET, LF, label=label)
        tl.add(1.0 * tm, squat_low, FEET, LF, label=label)
        tl.add(1.6 * tm, BASE, FEET, LF, label=label)

    def body(tl, left):
        tm = style.tempo
        d0 = tl.duration_s
        plank_down(tl)

        def rep(t):
            a = uniform(rng, 0.7, 1.0)
            down = PLANK + (PLANK_DOWN - PLANK) * a * min(style.amplitude, 1.0)
            d = 2.6 * tm * uniform(rng, 0.85, 1.15)
            t.add(0.5 * d, down, four, LF, heel=toes, label=label)
            t.add(uniform(rng, 0.05, 0.3), down, four, LF, heel=toes, label=label)
            t.add(0.5 * d, PLANK, four, LF, heel=toes, label=label)
            t.add(uniform(rng, 0.1, 0.5), PLANK, four, LF, heel=toes, label=label)
        repeat(tl, rep, left - (tl.duration_s - d0) - lasts_s(tl, get_up), rng)
        get_up(tl)
    return standing_frame(style, rng, seconds, label, body, pace=pace, pace_if_it_fits=True)


BUILDERS = {"sitting": sitting, "push_up": push_up, "sit_up": sit_up}

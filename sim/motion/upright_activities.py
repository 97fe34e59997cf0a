"""The activities on the feet as keyframe timelines: stepping, turning, bending, squat,
twisting, raising_arms, lunge, standing (builders as ``sim.motion.activities`` describes)."""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from sim.motion.activities import FEET, HEEL_OFF_DEG, mirror, repeat, standing_frame, styled, uniform
from sim.motion.keys import BASE, contacts, pose
from sim.motion.rig import LF, RF, J

MAX_SQUAT_SCALE = 1.05  # of the squat template (knees 140°)
MAX_BEND_SCALE = 1.1  # of the bending template (trunk 72° forward)


def _step(tl, style, rng, side, label, lift=(35, 50), turn=0.0, dur=0.8):
    """One step in place with foot `side` (LF/RF): heel off, lift, put down, brief double support."""
    hip, knee = uniform(rng, *lift), uniform(rng, 55, 80)
    swing = pose(left_hip=(-hip, 4, 0), left_knee=(knee, 0, 0), left_ankle=(-10, 0, 0),
                 right_shoulder=(-18, 0, 72), left_shoulder=(12, 0, -72), root=(0, 0, 3))
    if side == RF:
        swing = mirror(swing)
    stance = RF if side == LF else LF
    dur = dur * style.tempo * uniform(rng, 0.9, 1.1)
    c = contacts(stance)
    heel_off = [0.0, 0.0]
    heel_off[side] = uniform(rng, *HEEL_OFF_DEG)  # the weight goes onto the stance foot, the swing heel rises first
    tl.add(0.15 * dur, BASE, FEET, stance, heel=heel_off, label=label)
    tl.add(0.40 * dur, styled(swing, style), c, stance, turn_rad=0.6 * turn, label=label)
    tl.add(0.35 * dur, BASE, c, stance, turn_rad=0.4 * turn, label=label)
    tl.add(0.10 * dur, BASE, FEET, stance, label=label)


def stepping(style, rng, seconds, label, pace=None):
    def body(tl, left):
        side = [LF if style.lead == 0 else RF]

        def rep(t):
            _step(t, style, rng, side[0], label)
            side[0] = RF if side[0] == LF else LF
        repeat(tl, rep, left, rng, min_reps=2)
    return standing_frame(style, rng, seconds, label, body, pace=pace)


def turning(style, rng, seconds, label, pace=None):
    def body(tl, left):
        side = [LF]

        def rep(t):
            n = int(rng.integers(4, 7))
            total = np.radians(uniform(rng, 120, 210) * style.amplitude) * (1 if rng.random() < 0.5 else -1)
            # Turning left (positive yaw) leads with the left foot.
            side[0] = LF if total > 0 else RF
            for _ in range(n):
                _step(t, style, rng, side[0], label, lift=(20 * style.amplitude, 35 * style.amplitude), turn=total / n, dur=0.75)
                side[0] = RF if side[0] == LF else LF
            t.add(uniform(rng, 0.2, 0.6), BASE, FEET, LF if side[0] == RF else RF, label=label)
        repeat(tl, rep, left, rng)
    return standing_frame(style, rng, seconds, label, body, pace=pace)


def bending(style, rng, seconds, label, pace=None):
    def body(tl, left):
        def rep(t):
            a = uniform(rng, 0.6, 1.05)
            down = pose(root=(72, 0, 0), left_hip=(-80, 2, -3), right_hip=(-80, -2, 3),
                        left_knee=(10, 0, 0), right_knee=(10, 0, 0),
                        spine1=(10, 0, 0), spine2=(10, 0, 0), spine3=(8, 0, 0), neck=(-12, 0, 0),
                        left_shoulder=(-95, 0, -80), right_shoulder=(-95, 0, 80))
            side = uniform(rng, -6, 6)
            down[J["spine2"], 1] = side  # a little twist to one side
            d = 3.0 * style.tempo * uniform(rng, 0.85, 1.15)
            a = min(a, MAX_BEND_SCALE / style.amplitude)  # the trunk stops a little below horizontal
            t.add(0.45 * d, styled(down, style, a), FEET, LF, label=label)
            t.add(uniform(rng, 0.1, 0.6), styled(down, style, a * 1.03), FEET, LF, label=label)
            t.add(0.45 * d, BASE, FEET, LF, label=label)
        repeat(tl, rep, left, rng)
    return standing_frame(style, rng, seconds, label, body, pace=pace)


def squat(style, rng, seconds, label, pace=None):
    def body(tl, left):
        def rep(t):
            a = uniform(rng, 0.7, 1.0)
            arms_fwd = rng.random() < 0.6
            down = pose(root=(20, 0, 0), left_hip=(-115, 0, 10), right_hip=(-115, 0, -10),
                        left_knee=(140, 0, 0), right_knee=(140, 0, 0),
                        spine1=(12, 0, 0), spine2=(6, 0, 0), neck=(-15, 0, 0))
            if arms_fwd:
                down = pose(down, left_shoulder=(0, -75, 0), right_shoulder=(0, 75, 0), left_elbow=(0, -5, 0), right_elbow=(0, 5, 0))
            else:  # hands together in front of the chest
                down = pose(down, left_shoulder=(0, -45, -55), right_shoulder=(0, 45, 55), left_elbow=(0, -100, 0), right_elbow=(0, 100, 0))
            d = 3.6 * style.tempo * uniform(rng, 0.85, 1.15)
            a = min(a, MAX_SQUAT_SCALE / style.amplitude)  # knees stop near 147°, however flexible the person
            t.add(0.45 * d, styled(down, style, a), FEET, LF, label=label)
            t.add(uniform(rng, 0.1, 0.5), styled(down, style, a), FEET, LF, label=label)
            t.add(0.45 * d, BASE, FEET, LF, label=label)
        repeat(tl, rep, left, rng)
    return standing_frame(style, rng, seconds, label, body, pace=pace)


TWIST_ARMS = (  # how people hold their arms while they twist
    pose(left_shoulder=(-20, 0, -55), right_shoulder=(-20, 0, 55), left_elbow=(0, -95, 0), right_elbow=(0, 95, 0)),  # elbows bent
    pose(left_shoulder=(0, 0, -50), right_shoulder=(0, 0, 50), left_elbow=(0, -100, 0), right_elbow=(0, 100, 0)),  # hands on the hips
    pose(left_shoulder=(-10, -80, 0), right_shoulder=(-10, 80, 0), left_elbow=(0, 0, 0), right_elbow=(0, 0, 0)),  # arms out in front
)


def twisting(style, rng, seconds, label, pace=None):
    arms = TWIST_ARMS[int(rng.integers(len(TWIST_ARMS)))]

    def body(tl, left):
        tl.add(0.5 * style.tempo, arms, FEET, LF, label=label)

        def rep(t):
            for sgn in (1, -1):
                a = uniform(rng, 0.7, 1.1) * style.amplitude
                tw = pose(arms, root=(0, sgn * 10 * a, 0), spine1=(0, sgn * 13 * a, 0), spine2=(0, sgn * 13 * a, 0),
                          spine3=(0, sgn * 12 * a, 0), neck=(0, sgn * 8 * a, 0))
                t.add(0.75 * style.tempo * uniform(rng, 0.85, 1.15), tw, FEET, LF, label=label)
            t.add(0.15, arms, FEET, LF, label=label)
        repeat(tl, rep, left - 1.0, rng)
        tl.add(0.5 * style.tempo, BASE, FEET, LF, label=label)
    return standing_frame(style, rng, seconds, label, body, pace=pace)


def raising_arms(style, rng, seconds, label, pace=None):
    def body(tl, left):
        def rep(t):
            a = uniform(rng, 0.8, 1.05)
            kind = rng.integers(0, 3)
            if kind == 0:  # sideways, overhead
                up = pose(left_collar=(0, 0, 15), right_collar=(0, 0, -15), left_shoulder=(0, 0, 70), right_shoulder=(0, 0, -70),
                          left_elbow=(0, 0, 0), right_elbow=(0, 0, 0))
            elif kind == 1:  # forward, overhead
                up = pose(left_collar=(0, 0, 10), right_collar=(0, 0, -10), left_shoulder=(-165, 0, -72), right_shoulder=(-165, 0, 72),
                          left_elbow=(0, 0, 0), right_elbow=(0, 0, 0), spine3=(-5, 0, 0))
            else:  # sideways to shoulder height
                up = pose(left_shoulder=(0, 0, 0), right_shoulder=(0, 0, 0), left_elbow=(0, 0, 0), right_elbow=(0, 0, 0))
            d = 1.2 * style.tempo * uniform(rng, 0.85, 1.15)
            t.add(0.45 * d, styled(up, style, a), FEET, LF, label=label)
            t.add(uniform(rng, 0.2, 0.8), styled(up, style, a), FEET, LF, label=label)
            t.add(0.45 * d, BASE, FEET, LF, label=label)
        repeat(tl, rep, left, rng)
    return standing_frame(style, rng, seconds, label, body, pace=pace)


def lunge(style, rng, seconds, label, pace=None):
    depth_amp = style.amplitude  # how deep this person lunges: their own range of motion
    style = replace(style, amplitude=float(np.clip(style.amplitude, 0.85, 1.1)))  # a lunge needs a long split stance
    def body(tl, left):
        side = [style.lead]

        def rep(t):
            front = LF if side[0] == 0 else RF
            back = RF if front == LF else LF
            lift = pose(left_hip=(-55, 4, 0), left_knee=(60, 0, 0), root=(0, 0, 2))
            split = pose(left_hip=(-38, 4, 0), left_knee=(8, 0, 0), right_hip=(12, -4, 0), right_knee=(4, 0, 0))
            a = float(np.clip(uniform(rng, 0.75, 1.0) * depth_amp, 0.5, 1.1))
            deep = pose(root=(6 * a, 0, 0), left_hip=(-38 - 40 * a, 4, 0), left_knee=(8 + 70 * a, 0, 0),
                        right_hip=(12 - 6 * a, -4, 0), right_knee=(4 + 66 * a, 0, 0), spine1=(-4, 0, 0))
            if front == RF:
                lift, split, deep = mirror(lift), mirror(split), mirror(deep)
            heel_split = [0.0, 0.0]
            heel_deep = [0.0, 0.0]
            heel_split[back] = 25.0
            heel_deep[back] = 25.0 + 45.0 * a
            tm = style.tempo * uniform(rng, 0.85, 1.15)
            t.add(0.45 * tm, styled(lift, style), contacts(back), back, label=label)
            t.add(0.40 * tm, styled(split, style), contacts(back), back, heel=heel_split, label=label)
            t.add(0.10 * tm, styled(split, style), FEET, back, heel=heel_split, label=label)
            for _ in range(int(rng.integers(1, 3))):
                t.add(1.3 * tm, deep, FEET, back, heel=heel_deep, label=label)
                t.add(uniform(rng, 0.1, 0.4), deep, FEET, back, heel=heel_deep, label=label)
                t.add(1.3 * tm, styled(split, style), FEET, back, heel=heel_split, label=label)
            t.add(0.45 * tm, styled(lift, style), contacts(back), back, label=label)
            t.add(0.40 * tm, BASE, contacts(back), back, label=label)
            t.add(0.3 * tm, BASE, FEET, back, label=label)
            side[0] = 1 - side[0]
        repeat(tl, rep, left, rng)
    return standing_frame(style, rng, seconds, label, body, pace=pace)




def standing(style, rng, seconds, label, pace=None):
    def body(tl, left):
        n = max(1, int(left // 2.0))
        for _ in range(n):
            p = pose(spine2=(uniform(rng, -3, 3), uniform(rng, -8, 8), 0), neck=(uniform(rng, -10, 10), uniform(rng, -25, 25), 0))
            tl.add(left / n * 0.5, p, FEET, LF, label=label)
            tl.add(left / n * 0.5, BASE, FEET, LF, label=label)
    return standing_frame(style, rng, seconds, label, body, pace=pace)


BUILDERS = {
    "stepping": stepping, "bending": bending, "turning": turning, "squat": squat, "twisting": twisting,
    "raising_arms": raising_arms, "lunge": lunge, "standing": standing,
}

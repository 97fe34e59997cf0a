"""Walking as a keyframe timeline: steps between random spots near the start, turning toward
each (a builder as ``sim.motion.activities`` describes, which also takes the body's rig for
its step length, where to walk and the heading it starts at).

The planner steers by where the pelvis really goes: it places each landing foot as the
ground solve will (the posed body's double support, from the stance foot's ball), so a
walk stays near its spots instead of drifting by the gap between a nominal step and the
posed one (up to 0.85 m in 20 s before)."""

from __future__ import annotations

import numpy as np

from edge.body.rotations import euler_xyz_deg_to_matrix
from sim.motion.activities import FEET, HEEL_OFF_DEG, STANDING, mirror, styled, uniform
from sim.motion.keys import BASE, Timeline, contacts, pose
from sim.motion.rig import LF, LOCK_JOINT, RF, UPRIGHT, J, Rig, rot_z


def walking(style, rng, seconds, label, rig: Rig, home_radius_m: float, heading0: float, line: bool = False) -> Timeline:
    """Walk between random spots within home_radius_m of the start, turning toward each
    (line: back and forth between spots on one line through the start, along heading0 + 90°)."""
    ds = pose(left_hip=(-22, 4, 0), left_knee=(6, 0, 0), right_hip=(14, -4, 0), right_knee=(10, 0, 0),
              left_shoulder=(14, 0, -74), right_shoulder=(-16, 0, 74))
    mid = pose(left_hip=(-2, 4, 0), left_knee=(6, 0, 0), right_hip=(-26, -4, 0), right_knee=(55, 0, 0), right_ankle=(-8, 0, 0),
               root=(0, 0, -2))
    a = style.amplitude
    arm_swing = uniform(rng, *ARM_SWING)  # people swing their arms anywhere from barely to briskly
    for shoulder in ("left_shoulder", "right_shoulder"):
        ds[J[shoulder], 0] *= arm_swing
    ds, mid = styled(ds, style, a), styled(mid, style, a)
    balls = _balls_xy(rig, ds)
    step = abs(balls[LF, 1] - balls[RF, 1])  # this body's full step: the balls' spread in double support
    tl = Timeline()
    lead = min(uniform(rng, 0.3, 0.7), 0.15 * seconds)
    tl.add(lead, BASE, FEET, LF, label=STANDING)
    pos, head = np.zeros(2), heading0
    # Where the feet are (world xy of each ball), as ``sim.motion.locks`` will put them: the
    # stance foot stays; at each double support the pelvis is where the posed body puts it over
    # the stance ball, and the landing ball where the posed body puts it from there.
    ball_w = _turned(_balls_xy(rig, BASE), heading0)
    target = None
    stance = RF  # the first step is taken with the left foot
    t_left = seconds - lead - 1.0 * style.tempo
    step_dur = 0.55 * style.tempo
    front = None  # which foot is in front now (None: feet together)
    while t_left > 2 * step_dur:
        if target is None or np.linalg.norm(target - pos) < ARRIVE_M:
            if target is not None and rng.random() < 0.5:  # pause at the spot
                pause = min(uniform(rng, 0.3, 1.0), t_left - 2 * step_dur)
                if front is not None:  # bring the feet together first
                    t_left -= _close_feet(tl, front, mid, step_dur, label)
                    pos, ball_w = _land(rig, BASE, ball_w, front, 1 - front, head)
                    front, stance = None, front
                tl.add(pause, BASE, FEET, stance, label=STANDING)
                t_left -= pause
            target = _next_spot(rng, pos, home_radius_m, heading0, line)
        d = target - pos
        want = np.arctan2(d[0], -d[1])
        err = (want - head + np.pi) % (2 * np.pi) - np.pi
        turn = float(np.clip(err, -MAX_TURN_RAD, MAX_TURN_RAD))
        # Short steps while turning toward a spot off to the side, and when close to it.
        short = float(np.clip(np.cos(err - turn) * min(1.0, np.linalg.norm(d) / step), MIN_SHORT, 1.0))
        swing = LF if stance == RF else RF
        if front is None:  # from the feet together: the weight goes onto the stance foot as the swing heel rises
            heel_start = [0.0, 0.0]
            heel_start[swing] = START_HEEL_OFF_DEG * a
            tl.add(START_DS_S * style.tempo, BASE, FEET, stance, heel=heel_start, label=label)
            t_left -= START_DS_S * style.tempo
        # Swing through the mid pose into double support with the swing foot in front.
        ds_k = BASE + (ds - BASE) * short
        end = mirror(ds_k) if swing == RF else ds_k
        m = mirror(mid) if swing == LF else mid
        heel_mid, heel_off = [0.0, 0.0], [0.0, 0.0]
        heel_mid[stance] = 12.0  # late stance: the stance heel rises (heel off) …
        heel_off[stance] = uniform(rng, *HEEL_OFF_DEG)  # … and the foot leaves from its toes (toe off)
        heel_mid[swing] = heel_off[swing] = -HEEL_STRIKE_DEG * max(short, 0.7)  # the swing foot lands on its heel, toes up
        tl.add(0.5 * step_dur, m, contacts(stance), stance, turn_rad=0.5 * turn, label=label)
        tl.add(0.5 * step_dur, end, contacts(stance), stance, turn_rad=0.5 * turn, heel=heel_mid, label=label)
        # Double support: the body passes onto the landing foot (it carries the pelvis from here), the
        # trailing knee flexes as its heel rises (pre-swing), so the pelvis stays low between the feet.
        push = end.copy()
        push[J["left_knee" if stance == LF else "right_knee"], 0] = PRE_SWING_KNEE_DEG * a
        tl.add(0.12 * style.tempo, push, FEET, swing, heel=heel_off, label=label)
        head += turn
        pos, ball_w = _land(rig, end, ball_w, stance, swing, head)
        t_left -= step_dur + 0.12 * style.tempo
        front, stance = swing, swing
    if front is not None:  # close the feet
        _close_feet(tl, front, mid, step_dur, label)
        stance = front
    tl.add(0.1, BASE, FEET, stance, label=STANDING)
    tl.scale_to(seconds - 0.2)
    tl.add(0.2, BASE, FEET, LF, label=STANDING)
    return tl


ARRIVE_M = 0.2  # at a spot when the pelvis is this close to it
MAX_TURN_RAD = np.radians(60.0)  # the most a step turns (a spin turn; 90° takes two steps)
MIN_SHORT = 0.15  # the shortest step, as a fraction of the full one (turning on the spot)
ARM_SWING = (0.4, 1.8)  # per walk: the shoulders' swing against the template's ±15° (gait studies: ~5–35°)
HEEL_STRIKE_DEG = 15.0  # toes up at heel strike (the foot is flat by mid-stance)
CLOSE_STRIKE_DEG = 8.0  # a short closing step lands on its heel too, toes a little up
PRE_SWING_KNEE_DEG = 35.0  # the trailing knee at toe-off (gait studies: ~35–40°)
START_HEEL_OFF_DEG = 20.0  # the first step from standing: the swing heel rises while the weight shifts
START_DS_S = 0.25


def _balls_xy(rig: Rig, p: np.ndarray) -> np.ndarray:
    """(2,2) xy of the left and right ball (the feet's lock points) in pose p, pelvis at the
    origin, facing −y."""
    local = euler_xyz_deg_to_matrix(p[None])
    local[:, 0] = UPRIGHT @ local[:, 0]
    g = rig.fk(local)[1][0]
    return g[[LOCK_JOINT[LF], LOCK_JOINT[RF]], :2]


def _turned(xy: np.ndarray, heading: float) -> np.ndarray:
    """Points (…,2) of a body facing −y, turned to ``heading`` (rad, about +z)."""
    return xy @ rot_z(heading)[:2, :2].T


def _land(rig: Rig, p: np.ndarray, ball_w: np.ndarray, stance: int, swing: int, heading: float):
    """Double support in pose p at ``heading``, the stance ball staying where it is: the
    pelvis (2,) and the balls' world xy (2,2) with the swing ball where p puts it."""
    posed = _turned(_balls_xy(rig, p), heading)
    pelvis = ball_w[stance] - posed[stance]
    out = ball_w.copy()
    out[swing] = pelvis + posed[swing]
    return pelvis, out


def _next_spot(rng, pos: np.ndarray, home_radius_m: float, heading0: float, line: bool) -> np.ndarray:
    """A spot (2,) within home_radius_m of the start and over 0.5 m from pos (the last of 20
    draws when none is); line: on the line through the start along heading0 + 90°."""
    for _ in range(20):
        cand = rng.uniform(-home_radius_m, home_radius_m, 2)
        if line:
            cand = np.sign(cand[0]) * max(abs(cand[0]), 0.6 * home_radius_m) * np.array([np.cos(heading0), np.sin(heading0)])
        if np.linalg.norm(cand) <= home_radius_m and np.linalg.norm(cand - pos) > 0.5:
            break
    return cand


def _close_feet(tl, front, mid, step_dur, label) -> float:
    """The back foot steps up beside the front one (``front`` stays on the floor): it swings
    through the mid pose and lands on its heel, then both feet roll flat. Returns the seconds."""
    swing = LF if front == RF else RF
    heel_land = [0.0, 0.0]
    heel_land[swing] = -CLOSE_STRIKE_DEG
    tl.add(0.5 * step_dur, mid if swing == RF else mirror(mid), contacts(front), front, label=label)
    tl.add(0.5 * step_dur, BASE, contacts(front), front, heel=heel_land, label=label)
    tl.add(0.2, BASE, FEET, front, label=label)
    return step_dur + 0.2

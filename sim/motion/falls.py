"""Falls and their look-alikes, with exact truth: one person, one scenario.

    from sim.motion.falls import SCENARIOS, fall_track
    ft = fall_track(Subject.random(3), "fall_forward", rng=1)      # FallTrack
    ft.track                  # a sim.motion Track (pose_aa, transl_m, betas, activity, contact, rate_hz)
    ft.truth                  # {"scenario", "fall": bool, "start_s", "impact_s", "floor_s": [a, b] | None, "gets_up"}
    ft.load_fraction          # (T,) share of the body weight on the carpet (a chair carries the rest)

A scenario is a keyframe timeline (sim.motion.keys) of whole-body poses. Unlike the activities
(sim.motion.activities, placed by sim.motion.ground with locked contacts), the body is placed here by a
simple rule that also holds while it topples: every frame the lowest vertex touches the floor,
and one anchor (the feet's midpoint while on the feet, the pelvis while on the floor, the knees
while kneeling) keeps its place on the floor across the frame. Falls pivot about the feet and land
where the body's length puts them. Fall start is the first frame of the toppling key, impact the
end of it (the trunk on the floor); floor_s is the interval with the trunk on the floor.

Falls (``fall`` true): fall_forward, fall_backward, fall_sideways (from standing), walk_fall_forward,
walk_fall_sideways (a few steps first), chair_slump (seated on a chair off the carpet: slumps and
slides onto the floor), chair_slide (slides off the chair's edge onto the buttocks, then over),
slow_collapse (knees give way, then over to the side). Each lies still for ``lie_s`` and then gets
up (``get_up``) or stays down until the end.

Hard negatives (``fall`` false): kneel, lie_down (deliberately, on the back, via kneeling and
sitting), lie_down_hand_first (slowly onto the side, a hand on the floor first), pick_up; the
existing activities push_up, sit_up, sitting (on the floor), bending come from sim.motion.activities;
a dropped bag and a small pet are objects (sim/objects.py), not bodies.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from edge.body.rotations import euler_xyz_deg_to_matrix, matrix_to_axis_angle
from sim.motion.activities import ACTIVITIES, mirror
from sim.motion.floor_activities import SIT_BENT, SIT_LONG
from sim.motion.generate import DEFAULT_RATE_HZ, Subject, Track, body_model, person_track
from sim.motion.keys import BASE, Timeline, pose
from sim.motion.rest import settle
from sim.motion.rig import UPRIGHT, J, rot_z

FALLS = ("fall_forward", "fall_backward", "fall_sideways", "walk_fall_forward", "walk_fall_sideways",
         "chair_slump", "chair_slide", "slow_collapse")
LOOKALIKES = ("kneel", "lie_down", "lie_down_hand_first", "pick_up")
SCENARIOS = FALLS + LOOKALIKES

FEET, PELVIS, KNEES = 0, 1, 2  # anchors
_ANCHOR_JOINTS = {FEET: (J["left_ankle"], J["right_ankle"]), PELVIS: (J["pelvis"],), KNEES: (J["left_knee"], J["right_knee"])}
_STANDING = ACTIVITIES.index("standing")
_SITTING = ACTIVITIES.index("sitting")
_SIT_UP = ACTIVITIES.index("sit_up")

# ----------------------------------------------------------------------------- poses (degrees, SMPL canonical axes)

PRONE = pose(root=(88, 0, 0), left_shoulder=(0, 0, -80), right_shoulder=(0, 0, 80),
             left_elbow=(0, -10, 0), right_elbow=(0, 10, 0), left_hip=(5, 4, 0), right_hip=(5, -4, 0),
             left_knee=(15, 0, 0), right_knee=(10, 0, 0), neck=(-20, 0, 0))
BRACE = pose(root=(40, 0, 0), left_shoulder=(-80, 0, -30), right_shoulder=(-80, 0, 30), left_hip=(-20, 4, 0),
             right_hip=(10, -4, 0), left_knee=(25, 0, 0), right_knee=(10, 0, 0), spine2=(10, 0, 0))
SUPINE = pose(root=(-88, 0, 0), left_shoulder=(0, 0, -45), right_shoulder=(0, 0, 45), left_hip=(-15, 4, -5),
              right_hip=(-10, -4, 5), left_knee=(30, 0, 0), right_knee=(20, 0, 0), neck=(15, 0, 0))
TIP_BACK = pose(root=(-35, 0, 0), left_shoulder=(-60, 0, -40), right_shoulder=(-60, 0, 40), left_hip=(-45, 4, 0),
                right_hip=(-40, -4, 0), left_knee=(50, 0, 0), right_knee=(45, 0, 0), spine1=(10, 0, 0))
SIDE = pose(root=(0, 0, 86), left_shoulder=(0, 0, -78), right_shoulder=(-80, 0, 70), right_elbow=(0, 20, 0), left_hip=(-30, 4, 0),
            right_hip=(-20, -4, 0), left_knee=(40, 0, 0), right_knee=(30, 0, 0), neck=(0, 0, -15))
TIP_SIDE = pose(root=(0, 0, 35), right_shoulder=(0, 0, 20), left_shoulder=(0, 0, -40), left_hip=(-10, 4, 0),
                right_knee=(15, 0, 0), spine2=(0, 0, -10))
CHAIR = pose(left_hip=(-90, 4, 0), right_hip=(-90, -4, 0), left_knee=(90, 0, 0), right_knee=(90, 0, 0),
             left_shoulder=(-20, 0, -70), right_shoulder=(-20, 0, 70), left_elbow=(0, -40, 0), right_elbow=(0, 40, 0))
CHAIR_SLUMP = pose(CHAIR, root=(15, 0, 12), spine1=(15, 0, 8), spine2=(15, 0, 8), neck=(20, 0, 0),
                   left_shoulder=(0, 0, -85), right_shoulder=(0, 0, 85))
SIT_FLOOR = SIT_LONG
KNEEL_UP = pose(left_hip=(0, 4, 0), right_hip=(0, -4, 0), left_knee=(90, 0, 0), right_knee=(90, 0, 0),
                left_ankle=(30, 0, 0), right_ankle=(30, 0, 0))
KNEEL_SIT = pose(KNEEL_UP, root=(25, 0, 0), left_hip=(-100, 4, 0), right_hip=(-100, -4, 0), left_knee=(150, 0, 0),
                 right_knee=(150, 0, 0), spine1=(-10, 0, 0))
BUCKLE = pose(root=(20, 0, 0), left_hip=(-60, 4, 0), right_hip=(-55, -4, 0), left_knee=(90, 0, 0), right_knee=(85, 0, 0),
              spine1=(15, 0, 0), spine2=(10, 0, 0), neck=(20, 0, 0), left_shoulder=(0, 0, -85), right_shoulder=(0, 0, 85))
SQUAT = pose(root=(25, 0, 0), left_hip=(-120, 0, 12), right_hip=(-120, 0, -12), left_knee=(145, 0, 0),
             right_knee=(145, 0, 0), spine1=(10, 0, 0), spine2=(5, 0, 0), neck=(-10, 0, 0))
HAND_DOWN = pose(SQUAT, root=(30, 0, 25), left_shoulder=(-10, 0, 10), spine2=(5, 0, 15))
SIDE_PROP = pose(SIDE, root=(0, 0, 72), neck=(0, 0, -25))
PICK = pose(root=(70, 0, 0), left_hip=(-80, 2, -3), right_hip=(-80, -2, 3), left_knee=(15, 0, 0), right_knee=(15, 0, 0),
            spine1=(10, 0, 0), spine2=(10, 0, 0), left_shoulder=(-95, 0, -80), right_shoulder=(-95, 0, 80))


@dataclass
class FallTrack:
    """One scenario: its Track, the truth and the share of the weight on the carpet per frame."""

    track: Track
    truth: dict
    load_fraction: np.ndarray
    anchor: np.ndarray  # (T,) FEET / PELVIS / KNEES: what rests on the floor (for the record)


class _Script:
    """A timeline plus the per-key anchor and weight share, and named instants; ``rest(p)`` settles a
    pose on the floor for this subject (``settle``)."""

    def __init__(self, rest) -> None:
        self.rest = rest
        self.tl = Timeline()
        self.anchor: list[int] = []
        self.load: list[float] = []
        self.marks: dict[str, float] = {}

    def add(self, dur_s, p, anchor=FEET, label=_STANDING, load=1.0):
        self.tl.add(dur_s, p, np.zeros(6, bool), 0, label=label)
        self.anchor.append(anchor)
        self.load.append(load)
        return self

    def mark(self, name: str) -> None:
        self.marks[name] = self.tl.duration_s


def _u(rng, lo, hi) -> float:
    return float(rng.uniform(lo, hi))


def _lie_still(s: _Script, p, rng, lie_s: float, label=_STANDING) -> None:
    """Lying in pose p for lie_s seconds with small shifts (breathing, a hand moving)."""
    n = max(1, int(lie_s // 4.0))
    for _ in range(n):
        q = pose(p, neck=p[J["neck"]] + (_u(rng, -8, 8), _u(rng, -10, 10), 0))
        q[J["left_elbow"], 1] += _u(rng, -10, 10)
        s.add(lie_s / n, q, PELVIS, label)


def _get_up(s: _Script, rng, tempo: float, prone: bool = False) -> None:
    """From lying: to sitting (from the front: onto hands and knees), to kneeling, to standing (about 5 s)."""
    if not prone:
        s.add(1.6 * tempo, s.rest(SIT_FLOOR), PELVIS, _SITTING)
    s.add(1.4 * tempo, KNEEL_SIT, KNEES, _SITTING)
    s.add(1.2 * tempo, KNEEL_UP, KNEES, _SITTING)
    s.add(1.4 * tempo, BASE, FEET, _STANDING)


def _falling(s: _Script, rng, tempo, via, end, fall_s) -> None:
    """Loss of balance (via, on the feet) and the drop (to end, the trunk on the floor)."""
    s.mark("start_s")
    s.add(fall_s * 0.45, via, FEET)
    s.add(fall_s * 0.55, s.rest(end), PELVIS)
    s.mark("impact_s")


def _script(name: str, rng, tempo: float, lie_s: float, get_up: bool, side: int, rest) -> _Script:
    s = _Script(rest)
    s.add(_u(rng, 1.0, 2.5), BASE)
    flip = (lambda p: mirror(p)) if side else (lambda p: p)
    fall_s = _u(rng, 0.7, 1.1)
    if name in ("fall_forward", "walk_fall_forward"):
        _falling(s, rng, tempo, BRACE, flip(PRONE), fall_s)
    elif name == "fall_backward":
        _falling(s, rng, tempo, TIP_BACK, flip(SUPINE), fall_s)
    elif name in ("fall_sideways", "walk_fall_sideways"):
        _falling(s, rng, tempo, flip(TIP_SIDE), flip(SIDE), fall_s)
    elif name == "chair_slump":  # seated on a chair beside the carpet: only the feet are on it
        s.add(1.5 * tempo, CHAIR, FEET, _SITTING, load=0.25)
        s.add(_u(rng, 4, 8), CHAIR, FEET, _SITTING, load=0.25)
        s.mark("start_s")
        s.add(_u(rng, 1.0, 2.0), flip(CHAIR_SLUMP), FEET, _SITTING, load=0.3)
        s.add(_u(rng, 0.5, 0.8), s.rest(flip(SIDE)), PELVIS, _STANDING)
        s.mark("impact_s")
    elif name == "chair_slide":
        s.add(1.5 * tempo, CHAIR, FEET, _SITTING, load=0.25)
        s.add(_u(rng, 4, 8), CHAIR, FEET, _SITTING, load=0.25)
        s.mark("start_s")
        s.add(_u(rng, 0.4, 0.7), s.rest(SIT_FLOOR), PELVIS, _SITTING)
        s.add(_u(rng, 0.5, 0.9), s.rest(flip(SUPINE) if rng.random() < 0.5 else flip(SIDE)), PELVIS, _STANDING)
        s.mark("impact_s")
    elif name == "slow_collapse":
        s.mark("start_s")
        s.add(_u(rng, 1.0, 2.0), BUCKLE, FEET)
        s.add(_u(rng, 0.6, 1.0), KNEEL_SIT, KNEES)
        s.add(_u(rng, 0.6, 0.9), s.rest(flip(SIDE)), PELVIS)
        s.mark("impact_s")
    elif name == "kneel":
        s.add(_u(rng, 1.5, 2.5) * tempo, KNEEL_UP, KNEES, _SITTING)
        s.add(_u(rng, 3.0, 12.0), KNEEL_SIT if rng.random() < 0.5 else KNEEL_UP, KNEES, _SITTING)
        s.add(_u(rng, 1.5, 2.5) * tempo, BASE, FEET)
        return s
    elif name == "lie_down":  # onto an exercise mat: kneel, sit, lie back
        s.add(_u(rng, 1.5, 2.5) * tempo, KNEEL_UP, KNEES, _SITTING)
        s.add(_u(rng, 1.2, 2.0) * tempo, KNEEL_SIT, KNEES, _SITTING)
        s.add(_u(rng, 1.5, 2.5) * tempo, s.rest(SIT_BENT), PELVIS, _SITTING)  # onto the buttocks, knees up
        s.add(_u(rng, 2.0, 3.0) * tempo, s.rest(SUPINE), PELVIS, _SIT_UP)
        _lie_still(s, s.rest(SUPINE), rng, lie_s, _SIT_UP)
        _get_up(s, rng, tempo)
        return s
    elif name == "lie_down_hand_first":  # slowly onto the side, a hand on the floor first
        s.add(_u(rng, 1.5, 2.2) * tempo, SQUAT, FEET)
        s.add(_u(rng, 1.2, 2.0) * tempo, flip(HAND_DOWN), FEET)
        s.add(_u(rng, 1.5, 2.5) * tempo, flip(s.rest(SIT_BENT)), PELVIS, _SITTING)  # onto the hip, sitting
        s.add(_u(rng, 1.5, 2.5) * tempo, s.rest(flip(SIDE)), PELVIS, _SIT_UP)
        _lie_still(s, s.rest(flip(SIDE)), rng, lie_s, _SIT_UP)
        _get_up(s, rng, tempo)
        return s
    elif name == "pick_up":
        for _ in range(int(rng.integers(1, 4))):
            s.add(_u(rng, 0.8, 1.4) * tempo, PICK if rng.random() < 0.5 else SQUAT, FEET)
            s.add(_u(rng, 0.3, 1.0), PICK, FEET)
            s.add(_u(rng, 0.8, 1.4) * tempo, BASE, FEET)
        return s
    else:
        raise ValueError(f"unknown fall scenario {name!r}; expected one of {SCENARIOS}")
    end = s.tl.keys[-1].pose
    _lie_still(s, end, rng, lie_s)
    s.mark("floor_end_s")
    if get_up:
        _get_up(s, rng, tempo, prone=end[0, 0] > 45)
    return s


def _heading_of(pose_aa_root: np.ndarray) -> float:
    from scipy.spatial.transform import Rotation

    f = Rotation.from_rotvec(pose_aa_root).as_matrix() @ np.array([0.0, 0.0, 1.0])  # the body's front
    return float(np.arctan2(f[0], -f[1]))


def _place(model, betas, pose_aa: np.ndarray, anchor: np.ndarray, start_xy) -> np.ndarray:
    """transl (T,3): lowest vertex on the floor, the anchor joints' midpoint fixed while the anchor holds."""
    out = model.forward(pose_aa, betas, None, vertices=True)
    v, jt = out["vertices"], out["joints"]
    z = -v[:, :, 2].min(axis=1)
    transl = np.zeros((len(pose_aa), 3))
    transl[:, 2] = z
    pin = None
    for t in range(len(pose_aa)):
        here = jt[t, list(_ANCHOR_JOINTS[int(anchor[t])]), :2].mean(axis=0)  # relative to the pelvis at 0
        if t == 0:
            pin = np.asarray(start_xy, float) + here
        elif anchor[t] != anchor[t - 1]:  # the new anchor stays where the body puts it now
            pin = transl[t - 1, :2] + here
        transl[t, :2] = pin - here
    return transl


def fall_track(subject: Subject, scenario: str, rate_hz: float = DEFAULT_RATE_HZ, rng=None, model=None,
               lie_s: float | None = None, get_up: bool | None = None, walk_s: float = 3.0,
               heading_rad: float = 0.0, start_xy=(0.0, 0.0)) -> FallTrack:
    """One scenario (a name from SCENARIOS) for ``subject`` at rate_hz, truth included.

    lie_s: time lying still after a fall (default 35–50 s, so that a person-down alert is due);
    get_up: whether they get up afterwards (default: half of them). Falls from walking are
    preceded by walk_s seconds of walking (sim.motion's walking).
    """
    if scenario not in SCENARIOS:
        raise ValueError(f"unknown fall scenario {scenario!r}; expected one of {SCENARIOS}")
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    body = body_model(model)
    lie_s = _u(rng, 35.0, 50.0) if lie_s is None else float(lie_s)
    get_up = bool(rng.random() < 0.5) if get_up is None else bool(get_up)
    lead = None
    head, xy = float(heading_rad), np.asarray(start_xy, float)
    if scenario.startswith("walk_"):
        lead = person_track(subject, ["walking"], walk_s, rate_hz, rng, body, heading_rad=head, start_xy=xy,
                            walk_radius_m=0.3, walk_line=True)
        head = _heading_of(lead.pose_aa[-1, :3])
        xy = lead.transl_m[-1, :2]
    s = _script(scenario, rng, subject.style.tempo, lie_s, get_up, int(rng.integers(0, 2)),
                lambda p: settle(p, body, subject.betas))
    n = int(round(s.tl.duration_s * rate_hz)) + 1
    euler, heading, _, _, _, label = s.tl.sample(n, rate_hz, BASE, head)
    local = euler_xyz_deg_to_matrix(euler)
    local[:, 0] = rot_z(heading) @ UPRIGHT @ local[:, 0]
    pose_aa = matrix_to_axis_angle(local).reshape(n, 72)
    ends = np.cumsum([k.dur_s for k in s.tl.keys])
    key = np.minimum(np.searchsorted(ends, np.arange(n) / rate_hz, side="right"), len(ends) - 1)
    anchor = np.array(s.anchor)[key]
    load = np.array(s.load)[key]
    transl = _place(body, subject.betas, pose_aa, anchor, xy)
    contact = np.zeros((n, 6), bool)
    label = label.astype(np.int8)
    t0 = 0.0
    if lead is not None:  # walking first
        t0 = len(lead) / rate_hz
        pose_aa = np.concatenate([lead.pose_aa, pose_aa])
        transl = np.concatenate([lead.transl_m, transl])
        label = np.concatenate([lead.activity, label])
        contact = np.concatenate([lead.contact, contact])
        anchor = np.concatenate([np.full(len(lead), FEET), anchor])
        load = np.concatenate([np.ones(len(lead)), load])
    track = Track(subject.subject_id, subject.betas.copy(), pose_aa, transl, label, contact, float(rate_hz))
    is_fall = scenario in FALLS
    truth = {"scenario": scenario, "fall": is_fall, "gets_up": get_up if is_fall else None,
             "start_s": round(t0 + s.marks["start_s"], 3) if is_fall else None,
             "impact_s": round(t0 + s.marks["impact_s"], 3) if is_fall else None,
             "floor_s": [round(t0 + s.marks["impact_s"], 3), round(t0 + s.marks["floor_end_s"], 3)] if is_fall else None,
             "seconds": round(len(transl) / rate_hz, 3)}
    return FallTrack(track, truth, load, anchor)


def on_carpet(ft: FallTrack, carpet_size_m=(1.83, 1.83), rng=None, model=None, margin_m: float = 0.01) -> FallTrack:
    """The scenario turned and shifted so every vertex stays margin_m inside the carpet in every frame
    (turns tried in random order, the shift drawn among those that fit); ValueError when none fits."""
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    body = body_model(model)
    tr = ft.track
    from scipy.spatial import ConvexHull

    pts = body.forward(tr.pose_aa, tr.betas, tr.transl_m, vertices=True)["vertices"][..., :2].reshape(-1, 2)
    pts = pts[ConvexHull(pts).vertices]  # every vertex of every frame: a turned extent is reached on the hull
    size = np.asarray(carpet_size_m, float)
    for yaw in rng.uniform(0, 2 * np.pi) + np.arange(24)[rng.permutation(24)] * (np.pi / 12):
        c, s = np.cos(yaw), np.sin(yaw)
        p = pts @ np.array([[c, s], [-s, c]])
        lo, hi = p.min(axis=0), p.max(axis=0)
        room = size - 2 * margin_m - (hi - lo)
        if np.all(room >= 0):
            offset = margin_m - lo + rng.uniform(0, 1, 2) * room
            return FallTrack(tr.rotated(float(yaw), offset), ft.truth, ft.load_fraction, ft.anchor)
    raise ValueError(f"{ft.truth['scenario']} does not fit on a {size[0]:.2f}×{size[1]:.2f} m carpet")


def scenario_scene(subject: Subject, scenario: str, seconds: float, rate_hz: float, size_m: float, seed, model=None):
    """A one-person Scene of ``scenario`` exactly round(seconds·rate_hz) frames long (the last frame held
    when the scenario is shorter), placed on a size_m carpet: what sim://?activities=… streams. The
    truth of the fall is ``fall_track``'s; on the live carpet a chair carries nothing (load on the feet)."""
    from sim.motion.generate import Scene

    rng = np.random.default_rng(seed)
    ft = on_carpet(fall_track(subject, scenario, rate_hz, rng, model), (size_m, size_m), rng, model)
    tr, n = ft.track, int(round(seconds * rate_hz))
    idx = np.minimum(np.arange(n), len(tr) - 1)
    track = Track(tr.subject_id, tr.betas, tr.pose_aa[idx], tr.transl_m[idx], tr.activity[idx], tr.contact[idx], tr.rate_hz)
    return Scene([track], float(rate_hz), (float(size_m), float(size_m)))


__all__ = ["FALLS", "LOOKALIKES", "SCENARIOS", "FallTrack", "fall_track", "on_carpet", "scenario_scene"]

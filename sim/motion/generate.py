"""Subjects and tracks: one person's motion from a list of activities (``person_track``).
Scenes of several people on one carpet are ``sim.motion.placement``; see sim/motion/__init__.py."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from edge.body import BodyModel
from edge.body.rotations import euler_xyz_deg_to_matrix, matrix_to_axis_angle
from sim.motion import floor_activities, upright_activities
from sim.motion.activities import ACTIVITIES, VERTICAL_ACC_LIMIT_M_S2
from sim.motion.ground import ground
from sim.motion.keys import BASE
from sim.motion.pace import Pacer
from sim.motion.rig import (
    CONTACT_PARTS,
    UPRIGHT,
    J,
    Rig,
    rot_z,
)
from sim.motion.walking import walking

DEFAULT_RATE_HZ = 14.0
BUILDERS = upright_activities.BUILDERS | floor_activities.BUILDERS  # every activity but walking
_MODELS: dict[str, BodyModel] = {}


def body_model(model: BodyModel | str | None) -> BodyModel:
    """A body model as given, or loaded by name (default "lite") once per process."""
    if isinstance(model, BodyModel):
        return model
    name = model or "lite"
    if name not in _MODELS:
        _MODELS[name] = BodyModel.load(name)
    return _MODELS[name]


@dataclass(frozen=True)
class Style:
    """How a subject moves: tempo (duration multiplier, >1 slower), amplitude (pose-range
    multiplier), asymmetry (left limbs ×(1+a), right ×(1−a)), idle sway (degrees), lead
    side (0 left, 1 right), toe-out (degrees per foot)."""

    tempo: float = 1.0
    amplitude: float = 1.0
    asymmetry: float = 0.0
    sway_deg: float = 1.5
    lead: int = 0
    toe_out_deg: float = 6.0


@dataclass(frozen=True)
class Subject:
    """A person: id, body shape (our betas, |β| ≤ 5; β0 ≈ stature) and movement style."""

    subject_id: int
    betas: np.ndarray
    style: Style = field(default_factory=Style)

    @classmethod
    def random(cls, subject_id: int, seed: int | np.random.Generator | None = None) -> "Subject":
        """Betas ~ N(0,1) clipped at ±3 and a style, all drawn from ``seed`` (default: the id)."""
        rng = seed if isinstance(seed, np.random.Generator) else np.random.default_rng(subject_id if seed is None else seed)
        betas = np.clip(rng.normal(0.0, 1.0, 10), -3.0, 3.0)
        style = Style(
            tempo=float(np.clip(rng.normal(1.0, 0.12), 0.75, 1.35)),
            amplitude=float(np.clip(rng.normal(1.0, 0.15), 0.7, 1.2)),  # people differ far more than ±8 % (issue 13)
            asymmetry=float(np.clip(rng.normal(0.0, 0.07), -0.15, 0.15)),
            sway_deg=float(rng.uniform(0.5, 2.5)),
            lead=int(rng.integers(0, 2)),
            toe_out_deg=float(rng.uniform(2.0, 12.0)),
        )
        return cls(subject_id, betas, style)


@dataclass
class Track:
    """One person's motion at ``rate_hz``: T frames of SMPL parameters in the carpet frame.

    pose_aa (T,72) axis-angle, global orientation included (upright = +90° about x);
    transl_m (T,3) the pelvis joint; activity (T,) index into ACTIVITIES; contact (T,6)
    the generator's contact schedule over CONTACT_PARTS (parts bearing weight, locked).
    """

    subject_id: int
    betas: np.ndarray
    pose_aa: np.ndarray
    transl_m: np.ndarray
    activity: np.ndarray
    contact: np.ndarray
    rate_hz: float
    tempo: np.ndarray | None = None  # (activities,) each one's keys against the subject's own durations (< 1: squeezed)

    def __len__(self) -> int:
        return len(self.transl_m)

    @property
    def activity_names(self) -> list[str]:
        return [ACTIVITIES[i] for i in self.activity]

    def rotated(self, yaw_rad: float, offset_xy) -> "Track":
        """The same motion turned by yaw about the world z axis through the origin and shifted."""
        r = rot_z(np.float64(yaw_rad))
        pose = self.pose_aa.copy()
        from scipy.spatial.transform import Rotation
        root = Rotation.from_matrix(r) * Rotation.from_rotvec(pose[:, :3])
        pose[:, :3] = root.as_rotvec()
        transl = self.transl_m @ r.T
        transl[:, :2] += np.asarray(offset_xy, float)
        return Track(self.subject_id, self.betas, pose, transl, self.activity, self.contact, self.rate_hz, self.tempo)


@dataclass
class Scene:
    """Tracks of equal length T at rate_hz on a carpet of carpet_size_m (x, y) metres."""

    tracks: list[Track]
    rate_hz: float
    carpet_size_m: tuple[float, float]

    @property
    def num_frames(self) -> int:
        return len(self.tracks[0]) if self.tracks else 0


# ----------------------------------------------------------------------------- one person

ACTIVITY_AMPLITUDE_SD = 0.3  # log-normal spread of one person's range of motion from one activity to the next


def _for_activity(style: Style, rng) -> Style:
    """The subject's style for one activity: people move through a larger range in some
    activities than in others (a person's overall amplitude alone spread the peak joint
    angles by only 2–9 % between people; issue 13). Templates cap what a joint can reach."""
    amp = style.amplitude * np.exp(rng.normal(0.0, ACTIVITY_AMPLITUDE_SD))
    return replace(style, amplitude=float(np.clip(amp, 0.55, 1.5)))


def _sway(n, rate_hz, style, rng):
    t = np.arange(n) / rate_hz
    out = np.zeros((n, 24, 3))
    for joint, axes, scale in ((J["spine1"], (0, 2), 0.6), (J["spine3"], (0, 1, 2), 0.6), (J["neck"], (0, 1), 1.5), (0, (0, 2), 0.4)):
        for ax in axes:
            f = rng.uniform(0.08, 0.45, 3)
            ph = rng.uniform(0, 2 * np.pi, 3)
            out[:, joint, ax] = scale * style.sway_deg * np.sin(2 * np.pi * f[None] * t[:, None] + ph[None]).sum(1) / 1.7
    return out


MIN_ACTIVITY_S = 3.0  # the least time any activity is given when others need more than their share


def share_time(needs_s, total_s: float) -> np.ndarray:
    """Seconds for each activity of a sequence lasting total_s: an equal share, except that
    an activity needing more (a push-up: getting down, one repetition and getting up at its
    own pace) takes it from those with time to spare, never below what they need. Only when
    the sequence cannot hold every need is everything squeezed alike."""
    needs = np.maximum(np.asarray(needs_s, float), 1e-3)
    if needs.sum() >= total_s:
        return needs * (total_s / needs.sum())
    alloc = np.maximum(needs, total_s / len(needs))
    slack = alloc - needs
    return alloc - slack * ((alloc.sum() - total_s) / max(slack.sum(), 1e-12))


def person_track(subject: Subject, activities, seconds_per_activity: float = 10.0, rate_hz: float = DEFAULT_RATE_HZ,
                 rng: np.random.Generator | int | None = None, model: BodyModel | str | None = None,
                 heading_rad: float = 0.0, start_xy=(0.0, 0.0), walk_radius_m: float = 0.6,
                 walk_line: bool = False, extend: bool = False, total_s: float | None = None) -> Track:
    """One person doing ``activities`` (names from ACTIVITIES) in order, starting at start_xy
    facing heading_rad (0: facing −y). Walking goes between random spots within
    walk_radius_m of the start (walk_line: back and forth on one line, as scene() uses with
    others on the carpet). Feet are locked while they bear weight and the body rests on the
    floor (see sim.motion.ground).

    Length: len(activities)·round(seconds_per_activity·rate) frames, shared by ``share_time``
    (an activity that needs more than its share at the subject's own tempo takes it from the
    others); extend: longer where the activities need more in all (a dataset's sequences: the
    activity gets the time it needs instead of being squeezed); total_s: exactly
    round(total_s·rate) frames (a scene's people all last as long)."""
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    rig = Rig(body_model(model), subject.betas)
    n_seg = int(round(seconds_per_activity * rate_hz))
    if n_seg < 2:
        raise ValueError(f"seconds_per_activity·rate_hz gives {n_seg} frames; need at least 2")
    for name in activities:
        if name not in ACTIVITIES:
            raise ValueError(f"unknown activity {name!r}; expected one of {ACTIVITIES}")
    seeds = rng.integers(2**63, size=len(activities))  # each activity its own draws: its need is measured on them
    if len(activities) > 1 or (extend and total_s is None):  # (one activity of a set length takes it all anyway)
        needs = [max(_timeline(name, subject, np.random.default_rng(sd), 1e-3, rig, walk_radius_m, 0.0,
                               walk_line).own_s, MIN_ACTIVITY_S) for name, sd in zip(activities, seeds)]
    else:
        needs = [MIN_ACTIVITY_S]
    if total_s is not None:
        n_total = int(round(total_s * rate_hz))
    else:
        n_total = max(n_seg * len(activities), int(np.ceil(sum(needs) * rate_hz)) if extend else 0)
    ends = np.round(np.cumsum(share_time(needs, n_total / rate_hz)) * rate_hz).astype(int)
    ends[-1] = n_total
    frames = np.diff(ends, prepend=0)
    if frames.min() < 2:
        raise ValueError(f"{n_total} frames cannot hold {len(activities)} activities; need at least 2 frames each")
    parts, tempo = [], []
    head = float(heading_rad)
    for name, sd, n_act in zip(activities, seeds, frames):
        tl = _timeline(name, subject, np.random.default_rng(sd), n_act / rate_hz, rig, walk_radius_m, head, walk_line)
        euler, heading, contact, anchor, heel, lab = tl.sample(int(n_act), rate_hz, BASE, head)
        tempo.append(tl.tempo_factor)
        head = head + sum(k.turn_rad for k in tl.keys)
        parts.append((euler, heading, contact, anchor, heel, lab))
    euler, heading, contact, anchor, heel, lab = (np.concatenate(x) for x in zip(*parts))
    n = len(euler)
    style = subject.style  # sway and toe-out are the person's (an activity's style differs in amplitude only)
    sway = _sway(n, rate_hz, style, rng)
    # no root sway near a hand contact ("full" then centred: also right for sequences under 9 frames)
    on_hands = np.convolve(contact[:, 2] | contact[:, 3], np.ones(9), "full")[4 : 4 + n] > 0
    sway[on_hands, 0] = 0.0
    euler = euler + sway
    local = euler_xyz_deg_to_matrix(euler)
    local[:, 0] = rot_z(heading) @ UPRIGHT @ local[:, 0]
    toe = np.radians(style.toe_out_deg)
    foot_yaw = np.stack([heading + toe, heading - toe], 1)
    hand_rot = _flat_hands(heading)
    balance = np.ones(n, bool)  # walking too: its COM follows the path whose ZMP is on the stance foot
    seated = lab == ACTIVITIES.index("sitting")
    walking_frames = lab == ACTIVITIES.index("walking")  # its swinging feet follow planned paths (sim.motion.swing)
    transl = ground(rig, local, contact, anchor, heel, foot_yaw, hand_rot, start_xy, balance=balance, rate_hz=rate_hz,
                    seated=seated, swing=walking_frames)
    pose_aa = matrix_to_axis_angle(local).reshape(n, 72)
    return Track(subject.subject_id, subject.betas.copy(), pose_aa, transl, lab.astype(np.int8), contact, float(rate_hz),
                 np.array(tempo))


def _timeline(name, subject: Subject, rng: np.random.Generator, seconds: float, rig: Rig, walk_radius_m: float,
              heading: float, walk_line: bool):
    """One activity's keyframe timeline lasting ``seconds`` (the subject's style for it drawn from rng)."""
    label = ACTIVITIES.index(name)
    # the push-up's hop and the walking gait's heel strike need the person's own amplitude
    style = subject.style if name in ("push_up", "walking") else _for_activity(subject.style, rng)
    if name == "walking":
        return walking(style, rng, seconds, label, rig, walk_radius_m, heading, walk_line)
    limit = VERTICAL_ACC_LIMIT_M_S2.get(name)
    return BUILDERS[name](style, rng, seconds, label, pace=None if limit is None else Pacer(rig, limit))


def _flat_hands(heading: np.ndarray) -> np.ndarray:
    """World wrist orientations with the palms flat on the floor, fingers forward, turned in a little."""
    out = np.empty((len(heading), 2, 3, 3))
    z = np.array([0.0, 0.0, 1.0])
    for k, (sgn, inward) in enumerate(((1.0, -0.25), (-1.0, 0.25))):
        h = heading + inward
        f = np.stack([np.sin(h), -np.cos(h), np.zeros_like(h)], 1)  # fingers point along f
        x_c = sgn * f  # canonical +x of the left hand is its finger direction; −x for the right
        y_c = np.broadcast_to(z, x_c.shape)  # back of the hand up (palm down)
        z_c = np.cross(x_c, y_c)
        out[:, k] = np.stack([x_c, y_c, z_c], -1)
    return out


__all__ = ["ACTIVITIES", "CONTACT_PARTS", "DEFAULT_RATE_HZ", "Scene", "Style", "Subject", "Track", "body_model", "person_track"]

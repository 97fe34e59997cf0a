"""Subjects, tracks and scenes: the public face of sim.motion (see sim/motion/__init__.py)."""

from __future__ import annotations

from dataclasses import dataclass, field, replace

import numpy as np

from edge.body import BodyModel
from sim.motion import activities as acts
from sim.motion.activities import ACTIVITIES, FEET, STANDING, mirror
from sim.motion.ground import ground
from sim.motion.keys import BASE, Timeline, contacts, pose
from sim.motion.pace import Pacer
from sim.motion.rig import (
    CONTACT_PARTS,
    LF,
    RF,
    UPRIGHT,
    J,
    Rig,
    euler_deg_to_matrix,
    matrix_to_rotvec,
    rot_z,
)

DEFAULT_RATE_HZ = 14.0
_MODELS: dict[str, BodyModel] = {}


def _model(model) -> BodyModel:
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
        return Track(self.subject_id, self.betas, pose, transl, self.activity, self.contact, self.rate_hz)


@dataclass
class Scene:
    """Tracks of equal length T at rate_hz on a carpet of carpet_size_m (x, y) metres."""

    tracks: list[Track]
    rate_hz: float
    carpet_size_m: tuple[float, float]

    @property
    def num_frames(self) -> int:
        return len(self.tracks[0]) if self.tracks else 0


# ----------------------------------------------------------------------------- walking

def _walking(style, rng, seconds, label, rig: Rig, home_radius_m: float, heading0: float, line: bool = False):
    """Walk between random spots within home_radius_m of the start, turning toward each
    (line: back and forth between spots on one line through the start, along heading0 + 90°)."""
    ds = pose(left_hip=(-22, 4, 0), left_knee=(6, 0, 0), right_hip=(14, -4, 0), right_knee=(10, 0, 0),
              left_shoulder=(14, 0, -74), right_shoulder=(-16, 0, 74))
    mid = pose(left_hip=(-2, 4, 0), left_knee=(6, 0, 0), right_hip=(-26, -4, 0), right_knee=(55, 0, 0), right_ankle=(-8, 0, 0),
               root=(0, 0, -2))
    # Step length of this body from the double-support pose.
    local = euler_deg_to_matrix(ds[None])
    local[:, 0] = UPRIGHT @ local[:, 0]
    _, g = rig.fk(local)
    step = abs(g[0, J["left_ankle"], 1] - g[0, J["right_ankle"], 1])
    a = style.amplitude
    ds, mid = acts.styled(ds, style, a), acts.styled(mid, style, a)
    tl = Timeline()
    lead = min(_u(rng, 0.3, 0.7), 0.15 * seconds)
    tl.add(lead, BASE, FEET, LF, label=STANDING)
    pos, head = np.zeros(2), heading0
    target = None
    stance = RF  # the first step is taken with the left foot
    t_left = seconds - lead - 1.0 * style.tempo
    step_dur = 0.55 * style.tempo
    front = None  # which foot is in front now (None: feet together)
    while t_left > 2 * step_dur:
        if target is None or np.linalg.norm(target - pos) < 0.35:
            if target is not None and rng.random() < 0.5:  # pause at the spot
                pause = min(_u(rng, 0.3, 1.0), t_left - 2 * step_dur)
                if front is not None:  # bring the feet together first
                    t_left -= _close_feet(tl, front, mid, step_dur, label)
                    pos = pos + 0.5 * step * np.array([np.sin(head), -np.cos(head)])
                    front, stance = None, front
                tl.add(pause, BASE, FEET, stance, label=STANDING)
                t_left -= pause
            for _ in range(20):
                cand = rng.uniform(-home_radius_m, home_radius_m, 2)
                if line:
                    cand = np.sign(cand[0]) * max(abs(cand[0]), 0.6 * home_radius_m) * np.array([np.cos(heading0), np.sin(heading0)])
                if np.linalg.norm(cand) <= home_radius_m and np.linalg.norm(cand - pos) > 0.5:
                    break
            target = cand
        d = target - pos
        want = np.arctan2(d[0], -d[1])
        err = (want - head + np.pi) % (2 * np.pi) - np.pi
        turn = float(np.clip(err, -np.radians(40), np.radians(40)))
        # Short steps while turning toward a spot off to the side, and when close to it.
        short = float(np.clip(np.cos(err - turn) * min(1.0, np.linalg.norm(d) / step), 0.35, 1.0))
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
        frac = 0.5 if front is None else 1.0
        heel_mid, heel_off = [0.0, 0.0], [0.0, 0.0]
        heel_mid[stance] = 12.0  # late stance: the stance heel rises (heel off) …
        heel_off[stance] = _u(rng, *acts.HEEL_OFF_DEG)  # … and the foot leaves from its toes (toe off)
        heel_mid[swing] = heel_off[swing] = -HEEL_STRIKE_DEG * max(short, 0.7)  # the swing foot lands on its heel, toes up
        tl.add(0.5 * step_dur, m, contacts(stance), stance, turn_rad=0.5 * turn, label=label)
        tl.add(0.5 * step_dur, end, contacts(stance), stance, turn_rad=0.5 * turn, heel=heel_mid, label=label)
        # Double support: the body passes onto the landing foot (it carries the pelvis from here), the
        # trailing knee flexes as its heel rises (pre-swing), so the pelvis stays low between the feet.
        push = end.copy()
        push[J["left_knee" if stance == LF else "right_knee"], 0] = PRE_SWING_KNEE_DEG * a
        tl.add(0.12 * style.tempo, push, FEET, swing, heel=heel_off, label=label)
        head += turn
        pos = pos + frac * short * step * np.array([np.sin(head), -np.cos(head)])
        t_left -= step_dur + 0.12 * style.tempo
        front, stance = swing, swing
    if front is not None:  # close the feet
        _close_feet(tl, front, mid, step_dur, label)
        stance = front
    tl.add(0.1, BASE, FEET, stance, label=STANDING)
    tl.scale_to(seconds - 0.2)
    tl.add(0.2, BASE, FEET, LF, label=STANDING)
    return tl


HEEL_STRIKE_DEG = 15.0  # toes up at heel strike (the foot is flat by mid-stance)
CLOSE_STRIKE_DEG = 8.0  # a short closing step lands on its heel too, toes a little up
PRE_SWING_KNEE_DEG = 35.0  # the trailing knee at toe-off (gait studies: ~35–40°)
START_HEEL_OFF_DEG = 20.0  # the first step from standing: the swing heel rises while the weight shifts
START_DS_S = 0.25


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


def _u(rng, lo, hi):
    return float(rng.uniform(lo, hi))


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


def person_track(subject: Subject, activities, seconds_per_activity: float = 10.0, rate_hz: float = DEFAULT_RATE_HZ,
                 rng: np.random.Generator | int | None = None, model: BodyModel | str | None = None,
                 heading_rad: float = 0.0, start_xy=(0.0, 0.0), walk_radius_m: float = 0.6,
                 walk_line: bool = False) -> Track:
    """One person doing ``activities`` (names from ACTIVITIES) in order, each for
    ``seconds_per_activity`` (exactly round(seconds·rate) frames), starting at start_xy
    facing heading_rad (0: facing −y). Walking goes between random spots within
    walk_radius_m of the start (walk_line: back and forth on one line, as scene() uses with
    others on the carpet). Feet are locked while they bear weight and the body rests on the
    floor (see sim.motion.ground)."""
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    rig = Rig(_model(model), subject.betas)
    style = subject.style
    n_seg = int(round(seconds_per_activity * rate_hz))
    if n_seg < 2:
        raise ValueError(f"seconds_per_activity·rate_hz gives {n_seg} frames; need at least 2")
    parts = []
    head = float(heading_rad)
    for name in activities:
        if name not in ACTIVITIES:
            raise ValueError(f"unknown activity {name!r}; expected one of {ACTIVITIES}")
        label = ACTIVITIES.index(name)
        # the push-up's hop and the walking gait's heel strike need the person's own amplitude
        style = subject.style if name in ("push_up", "walking") else _for_activity(subject.style, rng)
        if name == "walking":
            tl = _walking(style, rng, seconds_per_activity, label, rig, walk_radius_m, head, walk_line)
        else:
            limit = acts.VERTICAL_ACC_LIMIT_M_S2.get(name)
            pacer = None if limit is None else Pacer(rig, limit)
            tl = acts.BUILDERS[name](style, rng, seconds_per_activity, label, pace=pacer)
        euler, heading, contact, anchor, heel, lab = tl.sample(n_seg, rate_hz, BASE, head)
        head = head + sum(k.turn_rad for k in tl.keys)
        parts.append((euler, heading, contact, anchor, heel, lab))
    euler, heading, contact, anchor, heel, lab = (np.concatenate(x) for x in zip(*parts))
    n = len(euler)
    sway = _sway(n, rate_hz, style, rng)
    # no root sway near a hand contact ("full" then centred: also right for sequences under 9 frames)
    on_hands = np.convolve(contact[:, 2] | contact[:, 3], np.ones(9), "full")[4 : 4 + n] > 0
    sway[on_hands, 0] = 0.0
    euler = euler + sway
    local = euler_deg_to_matrix(euler)
    local[:, 0] = rot_z(heading) @ UPRIGHT @ local[:, 0]
    toe = np.radians(style.toe_out_deg)
    foot_yaw = np.stack([heading + toe, heading - toe], 1)
    hand_rot = _flat_hands(heading)
    balance = np.ones(n, bool)  # walking too: its COM follows the path whose ZMP is on the stance foot
    seated = lab == ACTIVITIES.index("sitting")
    walking = lab == ACTIVITIES.index("walking")  # its swinging feet follow planned paths (sim.motion.swing)
    transl = ground(rig, local, contact, anchor, heel, foot_yaw, hand_rot, start_xy, balance=balance, rate_hz=rate_hz,
                    seated=seated, swing=walking)
    pose_aa = matrix_to_rotvec(local).reshape(n, 72)
    return Track(subject.subject_id, subject.betas.copy(), pose_aa, transl, lab.astype(np.int8), contact, float(rate_hz))


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


# ----------------------------------------------------------------------------- scenes

def _footprints(track: Track, model: BodyModel, stride: int = 1) -> np.ndarray:
    """(T,P,2) each frame's mesh vertices (every ``stride``-th) in x, y."""
    out = np.empty((len(track), (model.num_vertices + stride - 1) // stride, 2))
    for s in range(0, len(track), 2048):
        v = model.forward(track.pose_aa[s:s + 2048], track.betas, track.transl_m[s:s + 2048], vertices=True)["vertices"]
        out[s:s + 2048] = v[:, ::stride, :2]
    return out


def _boxes(points: np.ndarray, yaw: float, offset) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    x = c * points[..., 0] - s * points[..., 1] + offset[0]
    y = s * points[..., 0] + c * points[..., 1] + offset[1]
    return np.stack([x.min(1), y.min(1), x.max(1), y.max(1)], 1)  # (T,4)


def box_gaps(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per-frame separation of two boxes (T,4) [xmin,ymin,xmax,ymax]; ≤ 0 when they overlap."""
    sx = np.maximum(b[:, 0] - a[:, 2], a[:, 0] - b[:, 2])
    sy = np.maximum(b[:, 1] - a[:, 3], a[:, 1] - b[:, 3])
    return np.maximum(sx, sy)


_CELL_M = 0.03  # raster cell of the placement search


def _raster(cells: np.ndarray, shape) -> np.ndarray:
    """(N,P,2) integer cells → (N, *shape) occupancy."""
    occ = np.zeros((len(cells),) + tuple(shape), bool)
    ti = np.broadcast_to(np.arange(len(cells))[:, None], cells.shape[:2])
    occ[ti, cells[..., 0], cells[..., 1]] = True
    return occ


def _pair_union(occ: np.ndarray) -> np.ndarray:
    """Rasters of frames t and t+1 merged (T−1 of them), so they also cover the motion between frames."""
    return occ if len(occ) == 1 else occ[:-1] | occ[1:]


def scene(subjects, activities, seconds_per_activity: float = 10.0, rate_hz: float = DEFAULT_RATE_HZ,
          carpet_size_m=(1.83, 1.83), rng: np.random.Generator | int | None = None, min_gap_m: float = 0.15,
          margin_m: float = 0.02, model: BodyModel | str | None = None, tries: int = 40) -> Scene:
    """1–3 people on one carpet who never come closer than min_gap_m to each other (top-down:
    the horizontal distance between any vertex of one and any vertex of another, every frame
    and between consecutive frames) and never leave the carpet (every vertex margin_m inside
    its edges, every frame).

    activities: one sequence of names for everybody (each person after the first does them
    in an order of their own), or one sequence per person. Each person's track is generated
    at the origin and placed (the one with the largest footprint first, the others packed
    toward corners) by a turn and a shift: turns are tried in random order and the
    shift is drawn among all that fit (an exact search on a 3 cm raster of every frame, by
    FFT correlation). When a person after the first fits nowhere, they get a new order of
    their activities (another timing may fit beside the others; up to 3 times), then the
    placement restarts with new turns and corners. Raises ValueError after ``tries``
    placement attempts in all.
    """
    from scipy import fft as sfft
    from scipy.ndimage import binary_dilation

    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    subjects = list(subjects)
    if not 1 <= len(subjects) <= 3:
        raise ValueError(f"a scene holds 1 to 3 people, got {len(subjects)}")
    acts_list = list(activities)
    per_person = bool(acts_list) and not isinstance(acts_list[0], str)
    if per_person and len(acts_list) != len(subjects):
        raise ValueError("one activity sequence per subject, or one sequence for all")
    m = _model(model)
    size = np.asarray(carpet_size_m, float)
    walk_r = 0.6 if len(subjects) == 1 else 0.45  # with others: back and forth along a line
    h = _CELL_M
    grid = tuple(int(g) for g in np.ceil(size / h))
    rad = int(np.ceil(min_gap_m / h + 1.5))  # cells: any two vertices in cells this far apart are > min_gap_m apart
    yy, xx = np.mgrid[-rad:rad + 1, -rad:rad + 1]
    disk = (xx**2 + yy**2 <= rad * rad)[None]

    def make(k, shuffle):
        names = list(acts_list[k] if per_person else acts_list)
        order = list(rng.permutation(names)) if shuffle else names
        track = person_track(subjects[k], order, seconds_per_activity, rate_hz, rng, m, heading_rad=0.0,
                             walk_radius_m=walk_r, walk_line=len(subjects) > 1)
        return track, _footprints(track, m, stride=2)

    def occupancy(pts_world):
        cells = np.clip(np.floor(pts_world / h).astype(np.int64), 0, np.array(grid) - 1)
        return _pair_union(_raster(cells, grid))

    def place(pts, occ_fft, corner):
        """A (yaw, offset) that keeps this person on the carpet and clear of occ (FFT of the dilated
        occupancy of those placed), or None."""
        base = rng.uniform(0, 2 * np.pi)
        for yaw in (base + np.arange(12) * (2 * np.pi / 12))[rng.permutation(12)]:
            c, s = np.cos(yaw), np.sin(yaw)
            p = np.stack([c * pts[..., 0] - s * pts[..., 1], s * pts[..., 0] + c * pts[..., 1]], -1)
            lo, hi = p.reshape(-1, 2).min(0), p.reshape(-1, 2).max(0)
            n_off = np.floor((size - 2 * margin_m - (hi - lo)) / h).astype(int) + 1  # shifts per axis
            if np.any(n_off < 1):
                continue
            local = np.floor((p - lo + margin_m) / h).astype(np.int64)  # cells at shift 0
            if occ_fft is None:
                free = np.ones(n_off, bool)
            else:
                b = _pair_union(_raster(local, grid)).astype(np.float32)
                corr = sfft.irfft2(np.sum(occ_fft * np.conj(sfft.rfft2(b, workers=1)), axis=0), s=grid, workers=1)
                free = corr[:n_off[0], :n_off[1]] < 0.5
            options = np.flatnonzero(free)
            if len(options) == 0:
                continue
            if corner is None:  # alone on the carpet: anywhere
                pick = options[rng.integers(len(options))]
            else:  # with others: packed toward a corner, which leaves room for the next
                ox, oy = np.unravel_index(options, free.shape)
                dist = np.hypot(np.where(corner[0], n_off[0] - 1 - ox, ox), np.where(corner[1], n_off[1] - 1 - oy, oy))
                pick = options[np.argmin(dist + rng.uniform(0, 2.0, len(dist)))]
            ox, oy = np.unravel_index(pick, free.shape)
            offset = margin_m - lo + np.array([ox, oy]) * h
            return float(yaw), offset
        return None

    made = [make(k, shuffle=(k > 0 and not per_person)) for k in range(len(subjects))]
    budget = max(1, tries)

    def footprint_cells(pts):
        return len(np.unique(np.floor(pts.reshape(-1, 2) / h).astype(np.int64), axis=0))

    placed_by: dict[int, Track] = {}
    while budget > 0 and len(placed_by) < len(subjects):
        placed_by, occ = {}, None
        order = np.argsort([-footprint_cells(p) for _, p in made], kind="stable")  # the largest first
        corners = rng.permutation([(0, 0), (1, 1), (0, 1), (1, 0)]) if len(made) > 1 else [None]
        for i, k in enumerate(order):
            dil = None if occ is None else sfft.rfft2(binary_dilation(occ, disk).astype(np.float32), workers=1)
            got = None
            for retry in range(3):
                budget -= 1
                got = place(made[k][1], dil, corners[i % len(corners)])
                if got is not None or i == 0 or budget <= 0:
                    break
                made[k] = make(k, shuffle=True)  # another order/timing of the activities may fit beside the others
            if got is None:
                break
            yaw, offset = got
            track, pts = made[k]
            placed_by[int(k)] = track.rotated(yaw, offset)
            if len(placed_by) < len(made):
                c, s = np.cos(yaw), np.sin(yaw)
                w = np.stack([c * pts[..., 0] - s * pts[..., 1], s * pts[..., 0] + c * pts[..., 1]], -1) + offset
                o = occupancy(w)
                occ = o if occ is None else occ | o
    placed = [placed_by[k] for k in sorted(placed_by)]
    if len(placed) < len(subjects):
        raise ValueError(
            f"could not place {len(subjects)} people on a {size[0]:.2f}×{size[1]:.2f} m carpet "
            f"with {min_gap_m} m between people; use fewer people, a larger carpet or a smaller min_gap_m")
    return Scene(placed, float(rate_hz), (float(size[0]), float(size[1])))


__all__ = ["ACTIVITIES", "CONTACT_PARTS", "DEFAULT_RATE_HZ", "Scene", "Style", "Subject", "Track", "box_gaps", "person_track", "scene"]

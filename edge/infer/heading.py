"""Heading from the feet: resolve the model's 180° ambiguity of global orientation per track.

    resolver = HeadingResolver(HeadingParams.load())         # one per track
    pose_aa = resolver.resolve(pose_aa, person_kpa, pitch_m)  # (72,) maybe turned 180° about z

The model predicts the body's global orientation well up to a half turn about the vertical: in
a large share of frames it faces backwards. The pressure itself says which way is forward: a
foot's blob is elongated along the foot, and its centre of pressure (weighted by kPa) lies
behind the blob's plain centroid (the heel carries more load than the forefoot), so
``centroid − CoP`` along the blob's long axis points to the toes.

Per frame, every foot-like blob (area, length and elongation within the parameters, the feet
carrying most of the person's force) whose offset is clear but not extreme (an extreme one is a
forefoot or toes carrying the weight) gives a unit vote toward its toes; their sum is the frame's
cue. Per track, :class:`HeadingResolver` accumulates the cues on the carpet (weighted by how
reliable the cue is for the activity the model sees) and publishes the model's pose turned by
Rz(π) when it faces away from them.

Yaw convention: ``yaw(R)`` is the twist about carpet z of R · R0ᵀ, R0 = +90° about x (upright,
facing −y; design.md), the same twist ``export.metrics.heading_error_rad`` measures. An upright
body with yaw ψ faces Rz(ψ)·(0, −1, 0).

Parameters live in ``heading.json`` beside this file, fitted offline by ``export/heading_cue.py``.
"""

from __future__ import annotations

import json
from collections import deque
from dataclasses import asdict, dataclass, fields
from pathlib import Path

import numpy as np
from scipy import ndimage

PARAMS_FILE = Path(__file__).with_name("heading.json")


@dataclass(frozen=True)
class HeadingParams:
    """Foot-blob gates (physical units) and the track's evidence dynamics."""

    floor_kpa: float = 0.5           # sensels above this form blobs
    min_area_cm2: float = 40.0       # a foot's contact: at least this …
    max_area_cm2: float = 400.0      # … and at most this
    min_length_m: float = 0.10       # long-axis extent (4σ of the sensel spread)
    max_length_m: float = 0.36
    min_elongation: float = 1.4      # long σ / short σ
    min_offset_mm: float = 5.0       # |centroid − CoP| along the long axis: below this no vote (noise) …
    max_offset_mm: float = 20.0      # … nor above this (a forefoot or a toe carrying the weight: bending, lunge)
    min_foot_share: float = 0.8      # the foot-like blobs must carry this share of the person's force
    decay: float = 0.97              # per frame, of the track's summed evidence (a vector on the carpet) …
    off_feet_decay: float = 0.97     # … and per frame while the person is not on their feet (lying, on hands)
    max_evidence: float = 30.0       # its length is clipped to this
    min_evidence: float = 0.5        # shorter evidence decides nothing
    hold_last: float = 0.0           # 1: without evidence, keep the yaw published last (0: the model's)
    max_plateau_share: float = 1.0   # a blob with more of its sensels at its own peak is saturated: no vote
    outline: float = 0.0             # 1: a foot votes by its outline, not its CoP (see foot_votes) …
    min_skew: float = 0.1            # … when its sensels' skewness along the long axis is at least this
    min_upright: float = -1.0        # turn only a body whose up axis has at least this carpet-z component
                                     # (the feet say where an upright body faces, not a lying one)
    confirm_flip_frames: float = 0.0  # without evidence, a 180° jump of the model is published only after
                                     # it has lasted this many frames (0: at once)
    follow_axis_deg: float = 0.0     # > 0: the evidence turns with the feet's long axis between frames when
                                     # that changes by at most this much (a person turning carries it along;
                                     # a larger jump is a foot landing askew); 0: it only decays toward new votes
    travel_weight: float = 0.0       # > 0: a track whose centre went at least travel_min_m over the last
    travel_min_m: float = 0.3        # travel_frames inferred frames adds a vote of this length toward where it
    travel_frames: float = 14.0      # went (people walk forwards), times the "travel_weight" table's weight of
                                     # the activity the model sees (sitting down also moves the centre, backwards)

    @classmethod
    def load(cls, path: str | Path | None = None) -> "HeadingParams":
        """From a JSON object of these fields (the packaged heading.json by default); ValueError names a bad file."""
        p = Path(path) if path is not None else PARAMS_FILE
        try:
            data = json.loads(p.read_text())
        except (OSError, ValueError) as exc:
            raise ValueError(f"{p}: unreadable heading parameters ({exc}); re-run export/heading_cue.py") from None
        if not isinstance(data, dict):
            raise ValueError(f"{p}: expected a JSON object of heading parameters; re-run export/heading_cue.py")
        return cls.from_dict(data.get("params", data), where=str(p))

    @classmethod
    def from_dict(cls, data: dict, where: str = "heading parameters") -> "HeadingParams":
        known = {f.name for f in fields(cls)}
        unknown = sorted(set(data) - known)
        if unknown:
            raise ValueError(f"{where}: unknown field(s) {unknown}; known: {sorted(known)}")
        try:
            return cls(**{k: float(v) for k, v in data.items()})
        except (TypeError, ValueError) as exc:
            raise ValueError(f"{where}: every field must be a number ({exc})") from None

    def to_dict(self) -> dict:
        return asdict(self)


def load(path: str | Path | None = None, activities: list[str] | None = None) -> tuple[HeadingParams, np.ndarray | None]:
    """The parameters and, for a bundle's ``activities`` (in its order), the cue's weight per activity
    from a fitted JSON (the packaged heading.json by default); an activity the file does not name
    weighs 0 (the cue is not trusted there). ValueError names a bad file."""
    p = Path(path) if path is not None else PARAMS_FILE
    return HeadingParams.load(p), _activity_table(p, "activity_weight", activities)


def travel_weights(path: str | Path | None = None, activities: list[str] | None = None) -> np.ndarray | None:
    """The travel vote's weight per activity of a bundle's ``activities`` (in its order) from the fitted
    JSON's "travel_weight" table (an activity it does not name weighs 0); None without a table or
    activities. ValueError names a bad file."""
    return _activity_table(Path(path) if path is not None else PARAMS_FILE, "travel_weight", activities)


def _activity_table(p: Path, key: str, activities: list[str] | None) -> np.ndarray | None:
    """The JSON file's table ``key`` (activity name → number) as an array over ``activities``, 0 for a name it
    lacks; None without the table or the activities."""
    if activities is None:
        return None
    table = json.loads(p.read_text()).get(key)
    if table is None:
        return None
    try:
        return np.array([float(table.get(a, 0.0)) for a in activities])
    except (TypeError, ValueError, AttributeError) as exc:
        raise ValueError(f"{p}: {key} must map activity names to numbers ({exc})") from None


MAX_COP_STEP_M = 0.4  # a track's centre moving farther between two inferred frames is not one body moving
MIN_AXIS_AGREEMENT = 0.5  # the feet's axes must agree this well (mean resultant of the doubled angles)


def foot_votes(pressure_kpa: np.ndarray, pitch_m: float, params: HeadingParams) -> tuple[np.ndarray, float]:
    """(H,W) one person's kPa → (K,2) unit forward vectors (x, y) of the K foot-like blobs whose heel
    offset is clear and plausible, and the share of the person's force all foot-like blobs carry."""
    votes, share, _ = feet(pressure_kpa, pitch_m, params)
    return votes, share


def feet(pressure_kpa: np.ndarray, pitch_m: float, params: HeadingParams) -> tuple[np.ndarray, float, float]:
    """:func:`foot_votes` and the feet's long axis (radians, modulo π, in the votes' (x, y); NaN when no
    foot-like blob carries force or their axes disagree): the force-weighted mean of the doubled angles.

    The blobs' moments come from one labelling of the loaded box and one reduceat (no loop over blobs)."""
    p = np.asarray(pressure_kpa)
    loaded = p > params.floor_kpa
    rows, cols = np.flatnonzero(loaded.any(1)), np.flatnonzero(loaded.any(0))
    if not len(rows):
        return np.zeros((0, 2)), 0.0, float("nan")
    box = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
    labels, n = ndimage.label(loaded[box])
    rr, cc = np.nonzero(labels)
    lab = labels[rr, cc]
    w = p[box][rr, cc].astype(np.float64)
    x, y = cc.astype(np.float64), rr.astype(np.float64)  # sensel units in the box, x = column
    order = np.argsort(lab, kind="stable")  # sums per blob: one reduceat over the blobs' runs
    starts = np.searchsorted(lab[order], np.arange(1, n + 1))
    sums = np.add.reduceat(np.stack([np.ones_like(x), x, y, x * x, y * y, x * y, w, w * x, w * y], -1)[order], starts)
    count, sx, sy, sxx, syy, sxy, force, swx, swy = sums.T
    mx, my = sx / count, sy / count
    dof = np.maximum(count - 1, 1)
    sxx, syy, sxy = (sxx - count * mx * mx) / dof, (syy - count * my * my) / dof, (sxy - count * mx * my) / dof
    half_gap = np.sqrt(((sxx - syy) / 2) ** 2 + sxy ** 2)
    major, minor = (sxx + syy) / 2 + half_gap, (sxx + syy) / 2 - half_gap
    area_cm2 = count * (pitch_m * 100) ** 2
    length_m = 4 * np.sqrt(np.maximum(major, 0)) * pitch_m
    foot = ((area_cm2 >= params.min_area_cm2) & (area_cm2 <= params.max_area_cm2) & (minor > 0)
            & (length_m >= params.min_length_m) & (length_m <= params.max_length_m))
    foot &= np.sqrt(np.where(foot, major / np.where(minor > 0, minor, 1), 0)) >= params.min_elongation
    share = float(force[foot].sum() / w.sum())
    phi = 0.5 * np.arctan2(2 * sxy, sxx - syy)  # the major axis
    axis = np.stack([np.cos(phi), np.sin(phi)], -1)
    cop = np.stack([swx, swy], -1) / force[:, None]
    feet_axis = _mean_axis_rad(phi[foot], force[foot])
    if params.outline:  # the wide forefoot holds most sensels, the narrow heel trails: skewness < 0 toward the toes
        t = (x - mx[lab - 1]) * axis[lab - 1, 0] + (y - my[lab - 1]) * axis[lab - 1, 1]
        m2 = np.bincount(lab, weights=t * t, minlength=n + 1)[1:] / count
        m3 = np.bincount(lab, weights=t ** 3, minlength=n + 1)[1:] / count
        skew = m3 / np.maximum(m2, 1e-12) ** 1.5
        vote = foot & (np.abs(skew) >= params.min_skew)
        return -np.sign(skew[vote])[:, None] * axis[vote], share, feet_axis
    offset_mm = ((np.stack([mx, my], -1) - cop) * axis).sum(-1) * pitch_m * 1e3  # > 0: the toes lie along +axis
    vote = foot & (np.abs(offset_mm) >= params.min_offset_mm) & (np.abs(offset_mm) <= params.max_offset_mm)
    if params.max_plateau_share < 1.0:  # a saturated blob's CoP says nothing of its heel
        peak = ndimage.maximum(p[box], labels, np.arange(1, n + 1))
        at_peak = np.bincount(lab, weights=w >= 0.98 * peak[lab - 1], minlength=n + 1)[1:]
        vote &= at_peak <= params.max_plateau_share * count
    return np.sign(offset_mm[vote])[:, None] * axis[vote], share, feet_axis


def _mean_axis_rad(phi: np.ndarray, weight: np.ndarray) -> float:
    """Axes (radians, modulo π) → their weighted mean axis, NaN when none or they disagree."""
    total = float(weight.sum())
    if not len(phi) or total <= 0:
        return float("nan")
    c, s = float((weight * np.cos(2 * phi)).sum()), float((weight * np.sin(2 * phi)).sum())
    if np.hypot(c, s) < MIN_AXIS_AGREEMENT * total:
        return float("nan")
    return 0.5 * float(np.arctan2(s, c))


def frame_cue(pressure_kpa: np.ndarray, pitch_m: float, params: HeadingParams) -> tuple[np.ndarray, bool]:
    """(H,W) → ((2,) the frame's forward evidence, whether the person stands on their feet): the feet's
    votes summed (two feet that disagree cancel); none when anything but feet carries much of the
    weight (hands, seat, knees: then the person is not on their feet)."""
    cue, on_feet, _ = frame_evidence(pressure_kpa, pitch_m, params)
    return cue, on_feet


def frame_evidence(pressure_kpa: np.ndarray, pitch_m: float, params: HeadingParams) -> tuple[np.ndarray, bool, float]:
    """:func:`frame_cue` and the feet's long axis (radians modulo π, NaN when off the feet or unclear)."""
    v, share, axis_rad = feet(pressure_kpa, pitch_m, params)
    on_feet = share >= params.min_foot_share
    return (v.sum(0) if len(v) and on_feet else np.zeros(2)), bool(on_feet), (axis_rad if on_feet else float("nan"))


def _quaternion(orient_aa: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(…,3) axis-angle → (w (…), v (…,3)) of the unit quaternion."""
    a = np.asarray(orient_aa, np.float64)
    theta = np.linalg.norm(a, axis=-1)
    k = np.where(theta > 1e-12, np.sin(theta / 2) / np.where(theta > 1e-12, theta, 1.0), 0.5)
    return np.cos(theta / 2), a * k[..., None]


def yaw_rad(orient_aa: np.ndarray) -> np.ndarray:
    """(…,3) global orientation (axis-angle) → (…) yaw in (−π, π]: the twist about z of R·R0ᵀ.

    With q = (w, v) the quaternion of R and R0ᵀ = −90° about x, the twist of q ⊗ q(R0ᵀ) about z is
    2·atan2(v_y + v_z, w + v_x) (the common factor cos 45° cancels)."""
    w, v = _quaternion(orient_aa)
    return _wrap(2 * np.arctan2(v[..., 1] + v[..., 2], w + v[..., 0]))


def upright_z(orient_aa: np.ndarray) -> float:
    """(3,) global orientation → the carpet-z component of the body's up axis (canonical +y): 1 upright,
    0 lying, −1 upside down."""
    w, v = _quaternion(orient_aa)
    x, y, z = v  # the third row of R applied to (0, 1, 0): 2(yz + wx)
    return float(2 * (y * z + w * x))


def cue_yaw_rad(forward_xy: np.ndarray) -> float:
    """(2,) a forward vector on the carpet → the yaw of an upright body facing it."""
    return float(_wrap(np.arctan2(forward_xy[1], forward_xy[0]) + np.pi / 2))


def turn_half(pose_aa: np.ndarray) -> np.ndarray:
    """(…,72) or (…,3) → the same with the global orientation turned 180° about carpet z (Rz(π)·R).

    q(Rz(π)) ⊗ (w, x, y, z) = (−z, −y, x, w); back to axis-angle with w ≥ 0."""
    out = np.array(pose_aa, np.float32, copy=True)
    w, v = _quaternion(out[..., 0:3])
    qw, qv = -v[..., 2], np.stack([-v[..., 1], v[..., 0], w], -1)
    sign = np.where(qw < 0, -1.0, 1.0)
    qw, qv = qw * sign, qv * sign[..., None]
    sin_half = np.linalg.norm(qv, axis=-1)
    angle = 2 * np.arctan2(sin_half, qw)
    out[..., 0:3] = qv * np.where(sin_half > 1e-12, angle / np.where(sin_half > 1e-12, sin_half, 1.0), 2.0)[..., None]
    return out


def _wrap(a):
    return (np.asarray(a) + np.pi) % (2 * np.pi) - np.pi


class HeadingResolver:
    """One track's heading state: where the feet say the person faces, on the carpet.

    The evidence is a vector on the carpet: each frame adds its foot cue (unit votes toward the
    toes) times the cue's reliability for the activity the model sees (``activity_weight``, 1
    without one); the sum decays by ``decay`` per frame and its length is clipped to
    ``max_evidence``, so a turn is followed within a few frames and one odd frame does not decide.
    While the evidence is at least ``min_evidence`` long, a pose whose yaw is more than 90° from
    it is published turned by Rz(π); the model's yaw (which may drift or swing on its own) keeps
    all its precision otherwise. Without enough evidence the model's answer is published, or,
    with ``hold_last`` = 1, the half turn nearest to the yaw published last (no 180° jumps), or with
    ``confirm_flip_frames`` = N, that half turn until the model has held the other for N frames.
    """

    def __init__(self, params: HeadingParams | None = None, activity_weight: np.ndarray | None = None,
                 travel_weight: np.ndarray | None = None) -> None:
        self.params = params or HeadingParams()
        self.activity_weight = None if activity_weight is None else np.asarray(activity_weight, np.float64)
        self.travel_weight = None if travel_weight is None else np.asarray(travel_weight, np.float64)
        self.evidence = np.zeros(2)
        self.last_yaw: float | None = None
        self.flips = 0  # frames published turned
        self.pending = 0  # frames the model has stood a half turn from the published yaw (confirm_flip_frames)
        self.last_axis_rad = float("nan")  # the feet's axis when last seen (follow_axis)
        self.last_cop_m: np.ndarray | None = None  # the track's centre when last resolved
        self.path: deque[np.ndarray] = deque(maxlen=max(2, int(self.params.travel_frames) + 1))  # its recent centres
        self.resets = 0  # times the evidence was dropped because the track's centre jumped

    def reset(self) -> None:
        """Forget the evidence and the published yaw (the track now follows another body, or the same
        body put down elsewhere): the next frames decide afresh."""
        self.evidence = np.zeros(2)
        self.last_yaw, self.pending, self.last_axis_rad = None, 0, float("nan")
        self.path.clear()

    def resolve(self, pose_aa: np.ndarray, person_kpa: np.ndarray, pitch_m: float,
                activity_probs: np.ndarray | None = None, cop_m: np.ndarray | None = None) -> np.ndarray:
        """(72,) the model's pose, (H,W) the person's kPa (as the model saw it), (A,) the model's
        activity probabilities, (2,) the track's centre on the carpet → (72,) the pose to publish.

        A centre that moved more than MAX_COP_STEP_M since the last resolved frame (no body walks
        5 m/s; the tracker gave the track to another body, or one was put down elsewhere) drops the
        evidence: the feet there say nothing of the body that was here."""
        if cop_m is not None:
            cop = np.asarray(cop_m, np.float64)[:2]
            if self.last_cop_m is not None and float(np.hypot(*(cop - self.last_cop_m))) > MAX_COP_STEP_M:
                self.reset()
                self.resets += 1
            self.last_cop_m = cop
            self.path.append(cop)
        cue, on_feet, axis_rad = frame_evidence(person_kpa, pitch_m, self.params)
        return self.decide(pose_aa, cue, activity_probs, on_feet, axis_rad, self._travel_vote(activity_probs))

    def _travel_vote(self, activity_probs: np.ndarray | None) -> np.ndarray:
        """(2,) toward where the track's centre went over the last travel_frames frames when it went at least
        travel_min_m, of length travel_weight times the activity's travel weight (walking: the body faces its
        way); zeros otherwise, and without activity probabilities or a travel table."""
        p = self.params
        if (p.travel_weight <= 0 or self.travel_weight is None or activity_probs is None
                or len(self.path) < (self.path.maxlen or 0)):
            return np.zeros(2)
        d = self.path[-1] - self.path[0]
        dist = float(np.hypot(d[0], d[1]))
        w = p.travel_weight * float(np.asarray(activity_probs, np.float64) @ self.travel_weight)
        return d * (w / dist) if dist >= p.travel_min_m and w > 0 else np.zeros(2)

    def decide(self, pose_aa: np.ndarray, cue: np.ndarray, activity_probs: np.ndarray | None = None,
               on_feet: bool = True, axis_rad: float = float("nan"), travel: np.ndarray | None = None) -> np.ndarray:
        """:meth:`resolve` with the frame's cue (2,), whether the person is on their feet and the feet's
        axis already computed; travel (2,): the travel vote (already weighted by activity)."""
        p = self.params
        weight = 1.0
        if self.activity_weight is not None and activity_probs is not None:
            weight = float(np.asarray(activity_probs, np.float64) @ self.activity_weight)
        if p.follow_axis_deg > 0:
            self._follow_axis(axis_rad, np.radians(p.follow_axis_deg))
        e = self.evidence * (p.decay if on_feet else p.off_feet_decay) + weight * np.asarray(cue, np.float64)
        if travel is not None:
            e = e + travel
        length = float(np.hypot(e[0], e[1]))
        if length > p.max_evidence:
            e, length = e * (p.max_evidence / length), p.max_evidence
        self.evidence = e
        yaw = float(yaw_rad(np.asarray(pose_aa[:3])))
        ref = cue_yaw_rad(e) if length >= p.min_evidence else self._without_evidence(yaw)
        out = np.asarray(pose_aa)
        if ref is not None and upright_z(out[:3]) < p.min_upright:
            ref = None
        if ref is not None and abs(_wrap(yaw - ref)) > np.pi / 2:
            out, yaw = turn_half(out), float(_wrap(yaw + np.pi))
            self.flips += 1
        self.last_yaw = yaw
        return out

    def _follow_axis(self, axis_rad: float, max_step_rad: float) -> None:
        """Turn the evidence by the feet's axis change since they were last seen (modulo π): the feet
        turning on the carpet say the person turns, whichever way they face; a jump over
        ``max_step_rad`` (a foot landing askew) turns nothing."""
        if np.isnan(axis_rad):
            return
        if not np.isnan(self.last_axis_rad):
            d = (axis_rad - self.last_axis_rad + np.pi / 2) % np.pi - np.pi / 2
            if abs(d) <= max_step_rad:
                c, s = np.cos(d), np.sin(d)
                self.evidence = np.array([c * self.evidence[0] - s * self.evidence[1],
                                          s * self.evidence[0] + c * self.evidence[1]])
        self.last_axis_rad = axis_rad

    def _without_evidence(self, yaw: float) -> float | None:
        """The reference yaw when the feet say nothing: the yaw published last with ``hold_last``; with
        ``confirm_flip_frames`` the same until the model's half turn has lasted that many frames (a
        real turn is gradual; a 180° jump between frames is the model's ambiguity, not the person)."""
        p = self.params
        if self.last_yaw is None or p.hold_last:
            return self.last_yaw
        if not p.confirm_flip_frames:
            return None
        self.pending = self.pending + 1 if abs(_wrap(yaw - self.last_yaw)) > np.pi / 2 else 0
        if self.pending >= p.confirm_flip_frames:
            self.pending = 0
            return None
        return self.last_yaw


def sequence_cues(pressure_kpa: np.ndarray, pitch_m: float,
                  params: HeadingParams) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(L,H,W) → ((L,2) frame cues, (L,) on their feet, (L,) the feet's axis) of :func:`frame_evidence`."""
    cues = [frame_evidence(f, pitch_m, params) for f in pressure_kpa]
    return (np.array([c for c, _, _ in cues]).reshape(-1, 2), np.array([f for _, f, _ in cues], bool),
            np.array([a for _, _, a in cues], np.float64))


def resolve_sequence(pose_aa: np.ndarray, cues: tuple[np.ndarray, ...], activity_probs: np.ndarray | None,
                     params: HeadingParams, activity_weight: np.ndarray | None = None) -> np.ndarray:
    """(L,72) one track's poses frame by frame, their :func:`sequence_cues`, (L,A) activity probabilities
    or None → (L,72) what a fresh resolver publishes (offline evaluation and fitting)."""
    r = HeadingResolver(params, activity_weight)
    probs = [None] * len(pose_aa) if activity_probs is None else activity_probs
    cue, on_feet, axis = cues
    return np.stack([r.decide(pose_aa[t], cue[t], probs[t], bool(on_feet[t]), float(axis[t]))
                     for t in range(len(pose_aa))]).astype(np.float32)


__all__ = ["HeadingParams", "HeadingResolver", "PARAMS_FILE", "load", "resolve_sequence", "sequence_cues", "cue_yaw_rad",
           "feet", "foot_votes", "frame_cue", "frame_evidence", "turn_half", "upright_z", "yaw_rad"]

"""Measure a small generated set of every activity: per-frame physics and per-region loads.

``measure_activity`` runs the generator's own motion and contact physics
(``sim.contact.track``) for a few subjects and returns, per frame, what the checks in
``sim.audit.checks`` compare with the literature: force over body weight, whether the
COP target was reachable, the COM inside the support, the load and peak of each body
region (feet, hands, buttocks, back), and per foot the COP's position along the foot
and the midfoot's share.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import ConvexHull, QhullError, cKDTree

from sim.contact.model import G_M_S2

REGIONS = ("left_foot", "right_foot", "hands", "buttocks", "back", "other")
_REGION_JOINTS = {
    "left_foot": ("left_ankle", "left_foot"), "right_foot": ("right_ankle", "right_foot"),
    "hands": ("left_wrist", "right_wrist", "left_hand", "right_hand"),
    "buttocks": ("pelvis", "left_hip", "right_hip"),
    "back": ("spine1", "spine2", "spine3", "left_collar", "right_collar", "neck"),
}
MIDFOOT = (0.30, 0.60)  # midfoot: 30–60 % of the foot's length from the heel (three-region mask)
STILL_SPEED_M_S = 0.08  # every joint slower than this and the COM's acceleration
STILL_ACC_M_S2 = 0.3  # below this: a still frame
COP_TOLERANCE_M = 0.005  # a COP target missed by less than a quarter of a sensel counts as reached
CONTACT_KPA = 0.5  # a sensel above this is in contact (the contact model's mask)


def vertex_regions(body) -> np.ndarray:
    """(V,) index into REGIONS from each vertex's dominant skinning joint."""
    dominant = np.argmax(np.asarray(body.arrays.weights), axis=1)
    names = np.asarray(body.joint_names)[dominant]
    out = np.full(len(names), REGIONS.index("other"), np.int8)
    for r, joints in _REGION_JOINTS.items():
        out[np.isin(names, joints)] = REGIONS.index(r)
    return out


@dataclass
class Frames:
    """Per-frame measurements of one activity (all subjects concatenated)."""

    activity: str
    label: list = field(default_factory=list)  # activity label index per frame
    force_ratio: list = field(default_factory=list)  # whole-body vertical force / (m·g)
    target_ok: list = field(default_factory=list)  # the solver reached its COP target within 5 mm (None: airborne)
    still: list = field(default_factory=list)
    com_in_support: list = field(default_factory=list)  # COM ground projection inside the contact hull (+5 mm)
    share: list = field(default_factory=list)  # (len(REGIONS),) share of the force per region
    peak_fine_kpa: list = field(default_factory=list)  # (len(REGIONS),) peak fine-scale pressure per region
    peak_sensel_kpa: list = field(default_factory=list)
    area_m2: list = field(default_factory=list)  # sensels above CONTACT_KPA, m²
    mean_kpa: list = field(default_factory=list)  # mean pressure over those sensels
    foot_cop: list = field(default_factory=list)  # (2,) COP along each foot, 0 heel … 1 toe (NaN: unloaded)
    foot_midfoot: list = field(default_factory=list)  # (2,) midfoot share of each foot's load
    foot_force: list = field(default_factory=list)  # (2,) each foot's force / (m·g)
    com_xy: list = field(default_factory=list)
    foot_hull_dist: list = field(default_factory=list)  # (2,) ZMP distance outside each foot's contact hull, m
    segment: list = field(default_factory=list)  # (subject, frame) of each entry
    tempo: list = field(default_factory=list)  # per subject: the activity's keys against their own durations (< 1: squeezed)


def contact_area(pressure_kpa: np.ndarray, pitch_m: float) -> tuple[float, float]:
    """(area m², mean kPa) of the sensels above CONTACT_KPA (0, 0 when none)."""
    on = pressure_kpa > CONTACT_KPA
    return float(on.sum() * pitch_m ** 2), float(pressure_kpa[on].mean()) if on.any() else 0.0


def _hull_distance(points: np.ndarray, p: np.ndarray) -> float:
    """How far p lies outside the convex hull of points (≤ 0 inside; inf if no hull)."""
    if len(points) < 3:
        return float("inf")
    try:
        hull = ConvexHull(points)
    except QhullError:
        return float("inf")
    return float((hull.equations[:, :2] @ p + hull.equations[:, 2]).max())


def measure_track(frames: Frames, carpet, body, tissue, track, regions: np.ndarray, subject: int, fw=None, dyn=None) -> None:
    from sim.contact.track import track_contacts, track_dynamics

    fw, dyn = track_dynamics(body, track, fw) if dyn is None else (fw, dyn)
    joints = fw["joints"]
    speed = np.zeros(len(track))
    speed[1:-1] = np.linalg.norm(joints[2:] - joints[:-2], axis=-1).max(1) * track.rate_hz / 2
    speed[0], speed[-1] = speed[1], speed[-2]
    results = track_contacts(carpet, body, tissue, track, fw, dyn, keep_fine=True)
    mg = dyn.mass_kg * G_M_S2
    for t, res in enumerate(results):
        frames.label.append(int(track.activity[t]))
        frames.segment.append((subject, t))
        frames.still.append(bool(speed[t] < STILL_SPEED_M_S and np.linalg.norm(dyn.acc_m_s2[t]) < STILL_ACC_M_S2))
        frames.force_ratio.append(res.force_total_n / mg)
        frames.com_xy.append(dyn.com_m[t, :2])
        frames.peak_sensel_kpa.append(float(res.pressure_kpa.max()))
        area, mean = contact_area(res.pressure_kpa, carpet.pitch_m)
        frames.area_m2.append(area), frames.mean_kpa.append(mean)
        nan2 = np.full(2, np.nan)
        if res.airborne or res.fine_pressure_kpa is None:
            frames.target_ok.append(None)
            frames.com_in_support.append(None)
            frames.share.append(np.zeros(len(REGIONS)))
            frames.peak_fine_kpa.append(np.zeros(len(REGIONS)))
            frames.foot_cop.append(nan2), frames.foot_midfoot.append(nan2), frames.foot_force.append(np.zeros(2))
            frames.foot_hull_dist.append(np.full(2, np.inf))
            continue
        frames.target_ok.append(bool(res.balanced or res.cop_error_m <= COP_TOLERANCE_M))
        fine = res.fine_pressure_kpa
        jj, ii = np.nonzero(fine > 0.5)
        p = fine[jj, ii].astype(np.float64)
        c = res.fine_cell_m
        xy = np.stack([(ii + res.fine_origin[1] + 0.5) * c, (jj + res.fine_origin[0] + 0.5) * c], 1)
        verts = fw["vertices"][t]
        low = np.flatnonzero(verts[:, 2] < verts[:, 2].min() + 0.12)
        reg = regions[low[cKDTree(verts[low, :2]).query(xy)[1]]]
        f = p * c * c * 1e3
        total = max(f.sum(), 1e-9)
        frames.share.append(np.array([f[reg == r].sum() / total for r in range(len(REGIONS))]))
        frames.peak_fine_kpa.append(np.array([p[reg == r].max() if (reg == r).any() else 0.0 for r in range(len(REGIONS))]))
        frames.com_in_support.append(_hull_distance(xy, dyn.com_m[t, :2]) <= 0.005)
        # zero-moment point: where the COP must be for this COM acceleration (the solver's target)
        zmp = dyn.com_m[t, :2] - dyn.com_m[t, 2] * dyn.acc_m_s2[t, :2] / max(G_M_S2 + dyn.acc_m_s2[t, 2], 1e-6)
        cop, mid, ff, hd = nan2.copy(), nan2.copy(), np.zeros(2), np.full(2, np.inf)
        for k, name in enumerate(("left", "right")):
            on = reg == REGIONS.index(f"{name}_foot")
            ff[k] = f[on].sum() / mg
            if ff[k] < 0.02:
                continue
            ankle, ball = joints[t, body.joint_names.index(f"{name}_ankle")], joints[t, body.joint_names.index(f"{name}_foot")]
            axis = (ball - ankle)[:2]
            axis /= max(np.linalg.norm(axis), 1e-9)
            fv = verts[regions == REGIONS.index(f"{name}_foot"), :2] @ axis
            heel, toe = fv.min(), fv.max()
            frac = (xy[on] @ axis - heel) / max(toe - heel, 1e-6)
            cop[k] = float((frac * f[on]).sum() / f[on].sum())
            mid[k] = float(f[on][(frac >= MIDFOOT[0]) & (frac < MIDFOOT[1])].sum() / f[on].sum())
            hd[k] = _hull_distance(xy[on], zmp)
        frames.foot_cop.append(cop), frames.foot_midfoot.append(mid), frames.foot_force.append(ff)
        frames.foot_hull_dist.append(hd)


def measure_activity(activity: str, subjects: int, seconds: float, seed: int, carpet, body, tissue, rate_hz: float = 14.0) -> Frames:
    from sim.motion import Subject, person_track

    regions = vertex_regions(body)
    frames = Frames(activity)
    size = carpet.cols * carpet.pitch_m
    for s in range(subjects):
        subj = Subject.random(100 + s, seed * 1000 + 100 + s)
        track = person_track(subj, [activity], seconds, rate_hz, rng=np.random.default_rng((seed, s)), model=body, extend=True,
                             start_xy=(size / 2, size / 2))
        frames.tempo.append(1.0 if track.tempo is None else float(track.tempo[0]))
        measure_track(frames, carpet, body, tissue, track, regions, s)
    return frames


def measure_lying(scenario: str, subjects: int, seed: int, carpet, body, tissue, after_s: float = 3.0) -> np.ndarray:
    """(subjects, 2) contact area m² and mean kPa of a body lying still ``after_s`` after the impact of a
    fall scenario (sim.motion.falls: the pose settled on the floor), one frame per subject."""
    from sim.contact import subject_mass_kg
    from sim.motion import Subject
    from sim.motion.falls import fall_track

    size = carpet.cols * carpet.pitch_m
    out = []
    for s in range(subjects):
        rng = np.random.default_rng((seed, 11, s))
        subj = Subject.random(100 + s, seed * 1000 + 100 + s)
        ft = fall_track(subj, scenario, 14.0, rng, body, lie_s=after_s + 2.0, get_up=False, start_xy=(size / 2, size / 2))
        tr = ft.track
        k = int(round((ft.truth["impact_s"] + after_s) * tr.rate_hz))
        v = body.forward(tr.pose_aa[k:k + 1], tr.betas, tr.transl_m[k:k + 1], vertices=True)["vertices"][0]
        v[:, :2] += size / 2 - v[:, :2].mean(axis=0)  # the whole body on the carpet
        res = carpet.pressure_kpa(v, body.faces, subject_mass_kg(body, tr.betas), static=True, tissue_kpa_per_mm=tissue)
        out.append(contact_area(res.pressure_kpa, carpet.pitch_m))
    return np.asarray(out)


def arrays(frames: Frames) -> dict[str, np.ndarray]:
    out = {}
    for k, v in vars(frames).items():
        if k == "activity":
            continue
        if k in ("target_ok", "com_in_support"):
            out[k] = np.array([np.nan if x is None else float(x) for x in v])
        else:
            out[k] = np.asarray(v)
    return out

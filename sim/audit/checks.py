"""The audit's checks: each measured number beside its published (or estimated) range.

A check is a dict: id, what, value, unit, range [lo, hi], ok, source. Values are medians or
percentages over the frames (or steps, or subjects) the check names.
"""

from __future__ import annotations

import numpy as np

from sim.audit.measure import REGIONS, arrays
from sim.motion.activities import MAX_STRETCH

SLOW = ("bending", "squat", "twisting", "raising_arms", "sitting", "push_up", "sit_up")
# Whole-body vertical force / body weight that ≥ 95 % of an activity's frames should stay within.
FORCE_RANGE = {a: (0.9, 1.1) for a in SLOW} | {"stepping": (0.8, 1.2), "turning": (0.8, 1.2), "lunge": (0.8, 1.2),
                                                "walking": (0.6, 1.35)}
SRC_FORCE = ("slow movements ~0.9–1.1 × mg (issue 13); walking vGRF 0–1.3 × mg, whole body 0.6–1.35 (note: "
             "sensor-and-calibration)")
SRC_MAGNITUDES = "a 70 kg adult on the carpet (note: sensor-and-calibration, magnitudes)"
SRC_BALANCE = "a body that can stand: COP target inside the support in ≥ 99 % of solves (issue 13)"


def _check(cid, what, value, unit, lo, hi, source):
    value = float(value) if value is not None and np.isfinite(value) else None
    ok = value is not None and lo <= value <= hi
    return {"id": cid, "what": what, "value": None if value is None else round(value, 4), "unit": unit,
            "range": [lo, hi], "ok": bool(ok), "source": source}


def _pct(mask) -> float:
    mask = np.asarray(mask, float)
    mask = mask[np.isfinite(mask)]
    return 100.0 * mask.mean() if mask.size else float("nan")


def _median(x) -> float:
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    return float(np.median(x)) if x.size else float("nan")


def _spans(mask: np.ndarray) -> list[tuple[int, int]]:
    """(start, stop) of runs of True."""
    d = np.diff(np.r_[0, mask.astype(np.int8), 0])
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


def physics_checks(activity: str, frames, label_index: int, standing_index: int) -> list[dict]:
    a = arrays(frames)
    own = a["label"] == label_index
    out = []
    lo, hi = FORCE_RANGE[activity]
    fr = a["force_ratio"][own]
    out.append(_check(f"force.{activity}", f"{activity}: frames with force within {lo}–{hi} × mg", _pct((fr >= lo) & (fr <= hi)),
                      "%", 95, 100, SRC_FORCE))
    out.append(_check(f"balance.{activity}", f"{activity}: contact solves whose COP target is reachable (within 5 mm)",
                      _pct(a["target_ok"][own]), "%", 99, 100, SRC_BALANCE))
    out.append(_check(f"tempo.{activity}", f"{activity}: keys at the subject's own durations (median time factor)",
                      float(np.median(frames.tempo)) if frames.tempo else None, "×", 0.9, MAX_STRETCH,
                      "an activity squeezed into its slot moves faster than the person would (issue 13: timelines "
                      "stretched to fill --seconds-per-activity); accelerations grow with the square"))
    still = own & a["still"]
    if still.any():  # stepping and walking never stand still
        out.append(_check(f"support.{activity}", f"{activity}: still frames with the COM over the support",
                          _pct(a["com_in_support"][still]), "%", 99, 100, "the centre of mass over the support when still (issue 13)"))
    return out


def _foot_events(a, label_index):
    """Per subject, per foot: loaded spans inside the activity (not touching the sequence ends)."""
    events = []
    seg = a["segment"][:, 0]
    for s in np.unique(seg):
        rows = np.flatnonzero(seg == s)
        lab = a["label"][rows]
        for k in (0, 1):
            loaded = a["foot_force"][rows, k] > 0.05
            for b, e in _spans(loaded):
                if b == 0 or e == len(rows) or e - b < 3:
                    continue
                if lab[b] != label_index and lab[e - 1] != label_index:
                    continue
                events.append((rows, k, b, e))
    return events


def gait_checks(activity, frames, label_index) -> list[dict]:
    a = arrays(frames)
    events = _foot_events(a, label_index)
    out = []
    cop = a["foot_cop"]
    toe_off = [cop[rows[e - 1], k] > 0.6 for rows, k, b, e in events]
    out.append(_check(f"toe_off.{activity}", f"{activity}: steps whose last contact is on the forefoot (COP > 60 % of the foot)",
                      _pct(toe_off) if events else None, "%", 90, 100,
                      "heel off then toe off at the end of every stance (gait literature; issue 13)"))
    if activity == "walking":
        strike = [cop[rows[b], k] < 0.4 for rows, k, b, e in events]
        out.append(_check(f"heel_strike.{activity}", f"{activity}: steps whose first contact is on the heel (COP < 40 %)",
                          _pct(strike) if events else None, "%", 90, 100, "heel strike in walking (issue 13)"))
    else:  # weight moves over the stance foot before the other foot leaves the floor
        shift = []
        for rows, k, b, e in events:
            if e < len(rows) and a["foot_force"][rows[e], 1 - k] > 0.5:
                shift.append(a["foot_hull_dist"][rows[e], 1 - k] <= 0.02)
        out.append(_check(f"weight_shift.{activity}", f"{activity}: lift-offs with the zero-moment point (COM and its "
                          "acceleration) within 2 cm of the stance foot",
                          _pct(shift) if shift else None, "%", 95, 100,
                          "weight shift before a foot leaves (issue 13)"))
    return out


def load_checks(results: dict, standing_index: int, labels: dict) -> list[dict]:
    """Region loads and peaks: standing feet, push-up hands, floor sitting, lying."""
    out = []
    stand_cop, stand_mid, heel_peak, sensel_peak = [], [], [], []
    for frames in results.values():
        a = arrays(frames)
        st = (a["label"] == standing_index) & a["still"] & (a["foot_force"] > 0.3).all(1)
        stand_cop += list(a["foot_cop"][st].ravel())
        stand_mid += list(a["foot_midfoot"][st].ravel())
        heel_peak += list(a["peak_fine_kpa"][st][:, :2].max(1))
        sensel_peak += list(a["peak_sensel_kpa"][st])
    out.append(_check("foot.cop_standing", "standing: COP along each foot from the heel (median)", 100 * _median(stand_cop), "% of length",
                      38, 50, "standing COP ~40–45 % of foot length from the heel (issue 13)"))
    out.append(_check("foot.midfoot_standing", "standing: midfoot (30–60 % of length) share of each foot's load (median)",
                      100 * _median(stand_mid), "%", 0, 15, "midfoot ≤ 15 % of the foot's load (issue 13; plantar-pressure studies)"))
    out.append(_check("foot.peak_fine_standing", "standing: peak plantar pressure at ~5 mm (median frame)", _median(heel_peak), "kPa",
                      100, 250, "barefoot standing heel peaks ~140 kPa at plate resolution (Cavanagh 1987; est. range)"))
    out.append(_check("foot.peak_sensel_standing", "standing: peak sensel pressure, two feet (median frame)", _median(sensel_peak), "kPa",
                      55, 90, "sensel-scale standing peaks 60–80 kPa (note: sensor-and-calibration)"))
    if "push_up" in results:
        a = arrays(results["push_up"])
        i_h, i_l, i_r = REGIONS.index("hands"), REGIONS.index("left_foot"), REGIONS.index("right_foot")
        plank = (a["label"] == labels["push_up"]) & (a["share"][:, i_h] > 0.3) & (a["share"][:, [i_l, i_r]].sum(1) > 0.1)
        out.append(_check("push_up.hands_share", "push-up plank: hands' share of the weight (median)",
                          100 * _median(a["share"][plank, i_h]) if plank.any() else None, "%", 64, 75, "Suprak 2011, Ebben 2011"))
    if "sitting" in results:
        a = arrays(results["sitting"])
        i_b = REGIONS.index("buttocks")
        sit = (a["label"] == labels["sitting"]) & a["still"] & (a["share"][:, i_b] > 0.2)
        out.append(_check("sitting.buttocks_share", "floor sitting: buttocks' share of the weight (median still frame)",
                          100 * _median(a["share"][sit, i_b]) if sit.any() else None, "%", 75, 95,
                          "the body's centre of mass puts ~84 % on the buttocks (issue 13)"))
        out.append(_check("sitting.area", "floor sitting: contact area, sensels above 0.5 kPa (median still frame)",
                          1e4 * _median(a["area_m2"][sit]) if sit.any() else None, "cm²", 800, 1500, SRC_MAGNITUDES))
        out.append(_check("sitting.mean_kpa", "floor sitting: mean pressure over that area (median still frame)",
                          _median(a["mean_kpa"][sit]) if sit.any() else None, "kPa", 4.6, 8.6, SRC_MAGNITUDES))
        out.append(_check("sitting.buttocks_peak", "floor sitting: peak under the ischial tuberosities at ~5 mm (median)",
                          _median(a["peak_fine_kpa"][sit, i_b]) if sit.any() else None, "kPa", 52, 149,
                          "rigid-seat ischial peaks 52–149 kPa (issue 13)"))
    if "sit_up" in results:
        a = arrays(results["sit_up"])
        i_b, i_k = REGIONS.index("buttocks"), REGIONS.index("back")
        lie = (a["label"] == labels["sit_up"]) & a["still"] & (a["share"][:, i_k] > 0.15)
        out.append(_check("lying.pelvis_share", "lying (sit-up, back down): buttocks/sacrum share of the weight (median)",
                          100 * _median(a["share"][lie, i_b]) if lie.any() else None, "%", 30, 60,
                          "supine, knees bent: the pelvis carries about a third to a half (segment masses; est.)"))
        out.append(_check("lying.sacrum_peak", "lying: peak under the sacrum at ~5 mm (median)",
                          _median(a["peak_fine_kpa"][lie, i_b]) if lie.any() else None, "kPa", 8, 30,
                          "supine on a firm surface, sacral peaks ~60–200 mmHg (8–27 kPa; est.)"))
    return out


def lying_checks(lying: np.ndarray) -> list[dict]:
    """Supine after a fall backwards, lying still (measure.measure_lying): the print's area and mean pressure."""
    return [_check("lying.supine_area", "lying supine after a fall: contact area, sensels above 0.5 kPa (median subject)",
                   1e4 * _median(lying[:, 0]), "cm²", 1000, 2000, SRC_MAGNITUDES),
            _check("lying.supine_mean_kpa", "lying supine after a fall: mean pressure over that area (median subject)",
                   _median(lying[:, 1]), "kPa", 3.4, 6.9, SRC_MAGNITUDES)]


def law_checks(results: dict) -> list[dict]:
    """Laws every frame must hold: the force the solver was asked for, nothing below the floor."""
    fr = np.concatenate([np.asarray(f.force_ratio) for f in results.values()])
    return [_check("law.airborne", "frames with no force at all (the body always touches the floor)",
                   100 * float((fr == 0).mean()), "%", 0, 1, "activities never leave the floor for long")]


def spread_checks(activity, subjects, seconds, seed, body, rate_hz=14.0) -> list[dict]:
    """Variety: how much the peak range of motion differs between subjects (motion only)."""
    from sim.motion import Subject, person_track

    peaks = []
    for s in range(subjects):
        subj = Subject.random(200 + s, seed * 1000 + 200 + s)
        tr = person_track(subj, [activity], seconds, rate_hz, rng=np.random.default_rng((seed, 7, s)), model=body, extend=True)
        ang = np.linalg.norm(tr.pose_aa[:, 3:].reshape(len(tr), 23, 3), axis=-1).sum(1)
        ang = ang - ang[0]
        peaks.append(np.percentile(ang, 95))
    peaks = np.asarray(peaks)
    cv = peaks.std() / max(abs(peaks.mean()), 1e-9)
    return [_check(f"spread.{activity}", f"{activity}: between-subject spread of the peak range of motion (CV)", 100 * cv, "%",
                   12, 60, "people differ far more than 2–9 % (issue 13; est. 12–60 %)")]


def rate_checks(seed, body, rate_hz=14.0) -> list[dict]:
    """Repetition rate must not depend on how long the sequence is (squats counted at 12 s and 24 s)."""
    from scipy.signal import find_peaks

    from sim.motion import Subject, person_track

    rates = {}
    for seconds in (12.0, 24.0):
        r = []
        for s in range(3):
            subj = Subject.random(300 + s, seed * 1000 + 300 + s)
            tr = person_track(subj, ["squat"], seconds, rate_hz, rng=np.random.default_rng((seed, 9, s)), model=body)
            z = tr.transl_m[:, 2]
            n = len(find_peaks(-z, prominence=0.08)[0])
            r.append(n / seconds)
        rates[seconds] = float(np.mean(r))
    ratio = rates[24.0] / max(rates[12.0], 1e-9)
    return [_check("rate.squat", "squat repetitions per second, 24 s over 12 s sequences", ratio, "ratio", 0.8, 1.25,
                   "real repetition rates do not depend on the sequence length (issue 13)")]

"""Judged frames and person-frames → the score's numbers: overall, per number of people, per activity.

    s = summarise(judged, rate_hz=14.0)       # judged: [(scene, frames, persons)] from judge()
    s["overall"]["mota"], s["by_people"]["2"]["count_right_pct"], s["by_activity"]["lunge"]["extra_frames_pct"]

Per group (a subset of frames and the true person-frames in them):
  count_right_pct      frames whose published count equals the true count
  extra_frames_pct     frames with MORE people published than there are ("an extra track")
  short_frames_pct     frames with fewer published than there are
  extra_person_frames  published people matched to nobody (CLEAR MOT false positives), and % of true person-frames
  missed_person_frames true people matched to no published one (misses), and %
  idsw, idsw_per_10_person_min, mota_pct   CLEAR MOT (overall and per number of people only)
  mpjpe_cm, pa_mpjpe_cm, local_mpjpe_cm, transl_cm   means over matched person-frames
  heading_median_deg, heading_over_45_pct, heading_over_90_pct   |rotation about vertical| of matched ones
  activity_acc_pct     matched person-frames whose published activity is the true one
  frame_ms_median, frame_ms_p95   the pipeline's milliseconds per frame (calibrate → record queued)
Per activity, a frame counts for every activity present in it (frame columns), person_frames and
the pose columns are that activity's own; extra_frames_pct_alone is over one-person scenes only
(an extra track there can only come from that activity).
"""

from __future__ import annotations

from typing import Any

import numpy as np


def _pct(num: float, den: float) -> float | None:
    return round(100.0 * num / den, 2) if den else None


def _mean_cm(x: np.ndarray) -> float | None:
    x = x[np.isfinite(x)]
    return round(float(x.mean() * 100), 2) if len(x) else None


def _frames_part(f: dict[str, np.ndarray], sel: np.ndarray) -> dict[str, Any]:
    true, pub = f["true"][sel], f["published"][sel]
    ms = f["frame_ms"][sel]
    ms = ms[np.isfinite(ms)]
    n = int(sel.sum())
    person_frames = int(true.sum())
    return {
        "frames": n, "person_frames": person_frames,
        "count_right_pct": _pct((pub == true).sum(), n), "extra_frames_pct": _pct((pub > true).sum(), n),
        "short_frames_pct": _pct((pub < true).sum(), n),
        "extra_person_frames": int(f["extra"][sel].sum()), "extra_person_frames_pct": _pct(f["extra"][sel].sum(), person_frames),
        "frame_ms_median": round(float(np.median(ms)), 3) if len(ms) else None,
        "frame_ms_p95": round(float(np.percentile(ms, 95)), 3) if len(ms) else None,
    }


def _persons_part(p: dict[str, np.ndarray], sel: np.ndarray) -> dict[str, Any]:
    m = p["matched"][sel]
    n = int(sel.sum())
    h = np.abs(np.degrees(p["heading_rad"][sel]))
    h = h[np.isfinite(h)]
    return {
        "missed_person_frames": int((~m).sum()), "missed_person_frames_pct": _pct((~m).sum(), n),
        "matched_person_frames": int(m.sum()),
        "mpjpe_cm": _mean_cm(p["mpjpe_m"][sel]), "pa_mpjpe_cm": _mean_cm(p["pa_mpjpe_m"][sel]),
        "local_mpjpe_cm": _mean_cm(p["local_mpjpe_m"][sel]), "transl_cm": _mean_cm(p["transl_m"][sel]),
        "heading_median_deg": round(float(np.median(h)), 1) if len(h) else None,
        "heading_over_45_pct": _pct((h > 45).sum(), len(h)), "heading_over_90_pct": _pct((h > 90).sum(), len(h)),
        "activity_acc_pct": _pct(p["activity_ok"][sel].sum(), m.sum()),
    }


def _mot_part(f: dict[str, np.ndarray], sel: np.ndarray, rate_hz: float) -> dict[str, Any]:
    gt = int(f["true"][sel].sum())
    fp, fn, sw = (int(f[k][sel].sum()) for k in ("extra", "missed", "switches"))
    minutes = gt / rate_hz / 60.0
    return {"idsw": sw, "idsw_per_10_person_min": round(sw / minutes * 10, 2) if minutes else None,
            "mota_pct": round(100.0 * (1 - (fp + fn + sw) / gt), 2) if gt else None}


def _concat(parts: list[dict[str, Any]]) -> dict[str, Any]:
    out: dict[str, Any] = {}
    for k in parts[0]:
        vals = [p[k] for p in parts]
        out[k] = sum(vals, []) if isinstance(vals[0], list) else np.concatenate(vals)
    return out


def summarise(judged: list[tuple[Any, dict, dict]], rate_hz: float) -> dict[str, Any]:
    """Overall, by_people ("1", "2", "3") and by_activity from [(scene, frames, persons)] (see the module doc)."""
    if not judged:
        return {"overall": None, "by_people": {}, "by_activity": {}}
    f = _concat([fr for _, fr, _ in judged])
    p = _concat([pe for _, _, pe in judged])
    scene_people_f = np.concatenate([np.full(len(fr["true"]), sc.people) for sc, fr, _ in judged])
    scene_people_p = np.concatenate([np.full(len(pe["matched"]), sc.people) for sc, _, pe in judged])

    def group(fsel: np.ndarray, psel: np.ndarray, mot: bool) -> dict[str, Any]:
        out = {**_frames_part(f, fsel), **_persons_part(p, psel)}
        if mot:
            out.update(_mot_part(f, fsel, rate_hz))
        return out

    result = {"overall": group(np.ones(len(f["true"]), bool), np.ones(len(p["matched"]), bool), True), "by_people": {}}
    for n in sorted(set(scene_people_f.tolist())):
        result["by_people"][str(n)] = group(scene_people_f == n, scene_people_p == n, True)
    acts = sorted(set(p["activity"].tolist()))
    result["by_activity"] = {}
    for a in acts:
        fsel = np.array([a in present for present in f["activities"]])
        psel = p["activity"] == a
        row = group(fsel, psel, False)
        row["person_frames"] = int(psel.sum())  # of this activity (the frames' others are not its own)
        del row["extra_person_frames"], row["extra_person_frames_pct"]
        alone = fsel & (scene_people_f == 1)
        row["extra_frames_pct_alone"] = _pct((f["published"][alone] > f["true"][alone]).sum(), alone.sum())
        row["frames_alone"] = int(alone.sum())
        result["by_activity"][a] = row
    return result

"""Every frame of a captured scene judged against the truth: counts, CLEAR MOT, and the matched people's poses.

    frames, persons = judge(run, body, threshold_m=0.5)

``frames``: one row per frame — true and published count, extras, misses, identity switches, the
activities present, the pipeline's milliseconds. ``persons``: one row per true person-frame —
activity, whether a published person was matched to it, and for a match the errors of
:mod:`export.metrics` (metres, radians) and whether the published activity is the true one.

A true person's identity is (scene chunk, subject): at each chunk boundary the virtual carpet
starts new activities in new places, so people "leave and come back elsewhere"; a tracker that
re-acquires them with new track ids is not charged an identity switch for it.
Matching is CLEAR MOT on the pelvis (``transl_m``) on the carpet plane (:mod:`.clear_mot`).
"""

from __future__ import annotations

import warnings

import numpy as np

from export import metrics
from export.score.capture import SceneRun
from export.score.clear_mot import clear_mot

FRAME_KEYS = ("true", "published", "extra", "missed", "switches", "frame_ms")


def judge(run: SceneRun, body, threshold_m: float) -> tuple[dict[str, np.ndarray], dict[str, np.ndarray]]:
    """(per-frame columns, per-true-person-frame columns) of one captured scene."""
    seq = []
    for truth, pub in zip(run.truth, run.published):  # a true person is (scene, subject): each scene places people anew
        seq.append(({(t["scene"], t["subject_id"]): t["transl_m"][:2] for t in truth},
                    {p["track_id"]: p["transl_m"][:2] for p in pub}))
    mot = clear_mot(seq, threshold_m)
    frames = {
        "true": np.array([len(t) for t in run.truth], int),
        "published": np.array([len(p) for p in run.published], int),
        "extra": np.array([len(f.extra) for f in mot.frames], int),
        "missed": np.array([len(f.missed) for f in mot.frames], int),
        "switches": np.array([len(f.switches) for f in mot.frames], int),
        "frame_ms": np.array([np.nan if m is None else m for m in run.frame_ms], float),
        "activities": [sorted({t["activity"] for t in truth}) for truth in run.truth],
        "kind": list(run.kinds),
    }
    rows = {"activity": [], "matched": [], "mpjpe_m": [], "pa_mpjpe_m": [], "local_mpjpe_m": [], "heading_rad": [],
            "transl_m": [], "activity_ok": []}
    pred, true = [], []
    for truth, pub, fm in zip(run.truth, run.published, mot.frames):
        partner = {t: p for t, p, _ in fm.pairs}
        by_track = {p["track_id"]: p for p in pub}
        for t in truth:
            rows["activity"].append(t["activity"])
            p = by_track.get(partner.get((t["scene"], t["subject_id"])))
            rows["matched"].append(p is not None)
            rows["activity_ok"].append(p is not None and p["activity"] == t["activity"])
            if p is not None:
                pred.append(p)
                true.append(t)
    persons = {k: np.asarray(v) for k, v in rows.items() if k in ("activity", "matched", "activity_ok")}
    persons.update(_pose_errors(pred, true, body, len(persons["matched"]), persons["matched"]))
    return frames, persons


def _pose_errors(pred: list[dict], true: list[dict], body, n: int, matched: np.ndarray) -> dict[str, np.ndarray]:
    """Errors of the matched pairs, NaN for unmatched person-frames (so the columns line up with ``persons``)."""
    out = {k: np.full(n, np.nan) for k in ("mpjpe_m", "pa_mpjpe_m", "local_mpjpe_m", "heading_rad", "transl_m")}
    if not pred:
        return out
    pp = np.array([p["pose_aa"] for p in pred], float)
    pb = np.array([p["betas"] for p in pred], float)
    tp = np.array([t["pose_aa"] for t in true], float)
    tb = np.array([t["betas"] for t in true], float)
    with warnings.catch_warnings():  # published betas beyond the body model's range are clamped: scored as drawn
        warnings.simplefilter("ignore")
        pj = body.forward(pp, pb)["joints"]
        tj = body.forward(tp, tb)["joints"]
        out["local_mpjpe_m"][matched] = metrics.local_mpjpe(body, pp, pb, tj, tp)
    out["mpjpe_m"][matched] = metrics.mpjpe(pj, tj)
    out["pa_mpjpe_m"][matched] = metrics.pa_mpjpe(pj, tj)
    out["heading_rad"][matched] = metrics.heading_error_rad(pp[:, :3], tp[:, :3])
    out["transl_m"][matched] = np.linalg.norm(np.array([p["transl_m"] for p in pred]) - np.array([t["transl_m"] for t in true]),
                                              axis=-1)
    return out

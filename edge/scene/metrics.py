"""Tracking quality against ground truth, CLEAR-MOT style (Bernardin and Stiefelhagen, 2008).

Per frame, true people and reported tracks are matched one-to-one (Hungarian on distance,
within ``gate_m``). A true person with no match is *missed*; a reported track with no
match is a *false positive*; a true person matched to a different track id than at their
previous match is an *identity switch*. Used by the tests and bench/scene_pipeline.py.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import numpy as np
from scipy.optimize import linear_sum_assignment
from scipy.spatial.distance import cdist


@dataclass(frozen=True)
class TrackingScore:
    frames: int
    true_people: int  # sum over frames of true people present
    missed: int
    false_positives: int
    id_switches: int
    mean_error_m: float  # mean distance of matched pairs

    @property
    def missed_fraction(self) -> float:
        return self.missed / max(self.true_people, 1)

    @property
    def mota(self) -> float:
        return 1.0 - (self.missed + self.false_positives + self.id_switches) / max(self.true_people, 1)

    def to_dict(self) -> dict:
        return {**asdict(self), "missed_fraction": round(self.missed_fraction, 4), "mota": round(self.mota, 4)}


def score_tracking(
    truth: list[dict[int, np.ndarray]], reported: list[dict[int, np.ndarray]], gate_m: float = 0.5
) -> TrackingScore:
    """truth[f] = {true person id: (2,) position}; reported[f] = {track_id: (2,) position}; same length."""
    if len(truth) != len(reported):
        raise ValueError("truth and reported must cover the same frames")
    last_match: dict[int, int] = {}
    n_true = missed = fp = switches = 0
    errors = []
    for tr, rp in zip(truth, reported):
        tids, rids = list(tr), list(rp)
        n_true += len(tids)
        matched = {}
        if tids and rids:
            d = cdist(np.array([tr[i] for i in tids]), np.array([rp[j] for j in rids]))
            rows, cols = linear_sum_assignment(np.where(d <= gate_m, d, 1e6))
            for r, c in zip(rows, cols):
                if d[r, c] <= gate_m:
                    matched[tids[r]] = rids[c]
                    errors.append(d[r, c])
        missed += len(tids) - len(matched)
        fp += len(rids) - len(matched)
        for t, r in matched.items():
            if t in last_match and last_match[t] != r:
                switches += 1
            last_match[t] = r
    return TrackingScore(len(truth), n_true, missed, fp, switches, float(np.mean(errors)) if errors else float("nan"))

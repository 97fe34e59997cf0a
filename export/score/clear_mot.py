"""CLEAR MOT over a sequence of frames (Bernardin & Stiefelhagen 2008), matching on the carpet plane.

    result = clear_mot(frames, threshold_m=0.5)
    result.mota, result.idsw, result.matches       # matches: (frame, true id, published id, distance m)

Each frame gives the true people (id → (x, y) in metres) and the published ones (track id → (x, y)).
Per frame:
1. a true person keeps last frame's published partner if that partner is still published and
   within ``threshold_m`` (so a correct track is not swapped away for a marginally nearer one);
2. the rest are paired by the minimum total distance (scipy's linear_sum_assignment), pairs
   farther than ``threshold_m`` left unpaired;
3. an identity switch: a true person paired with another published id than the last one it
   was ever paired with;
4. a published person left unpaired is an extra (false positive), a true one a miss.
MOTA = 1 − (misses + extras + switches) / true person-frames; MOTP = mean distance of the pairs.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Hashable, Iterable, Mapping, Sequence

import numpy as np
from scipy.optimize import linear_sum_assignment

XY = Sequence[float]


@dataclass
class FrameMatch:
    """One frame's outcome: pairs (true id, published id, distance m), unpaired ids, switches."""

    pairs: list[tuple[Hashable, Hashable, float]] = field(default_factory=list)
    missed: list[Hashable] = field(default_factory=list)
    extra: list[Hashable] = field(default_factory=list)
    switches: list[Hashable] = field(default_factory=list)  # true ids that switched in this frame


@dataclass
class MotResult:
    frames: list[FrameMatch]
    true_total: int

    @property
    def matches(self) -> int:
        return sum(len(f.pairs) for f in self.frames)

    @property
    def misses(self) -> int:
        return sum(len(f.missed) for f in self.frames)

    @property
    def extras(self) -> int:
        return sum(len(f.extra) for f in self.frames)

    @property
    def idsw(self) -> int:
        return sum(len(f.switches) for f in self.frames)

    @property
    def mota(self) -> float | None:
        if self.true_total == 0:
            return None
        return 1.0 - (self.misses + self.extras + self.idsw) / self.true_total

    @property
    def motp_m(self) -> float | None:
        d = [p[2] for f in self.frames for p in f.pairs]
        return float(np.mean(d)) if d else None


def _dist(a: XY, b: XY) -> float:
    return float(np.hypot(a[0] - b[0], a[1] - b[1]))


def match_frame(true: Mapping[Hashable, XY], published: Mapping[Hashable, XY], previous: Mapping[Hashable, Hashable],
                threshold_m: float) -> list[tuple[Hashable, Hashable, float]]:
    """Pairs (true id, published id, distance) for one frame; ``previous`` maps true id → last frame's partner."""
    pairs = []
    free_t, free_p = dict(true), dict(published)
    for t, p in previous.items():  # step 1: keep last frame's pairs that still hold
        if t in free_t and p in free_p:
            d = _dist(free_t[t], free_p[p])
            if d <= threshold_m:
                pairs.append((t, p, d))
                del free_t[t], free_p[p]
    if free_t and free_p:  # step 2: the rest by minimum total distance
        tk, pk = list(free_t), list(free_p)
        cost = np.array([[_dist(free_t[t], free_p[p]) for p in pk] for t in tk])
        big = threshold_m * 1e3 + 1.0  # pairs beyond the threshold are never worth taking
        rows, cols = linear_sum_assignment(np.where(cost <= threshold_m, cost, big))
        pairs += [(tk[r], pk[c], float(cost[r, c])) for r, c in zip(rows, cols) if cost[r, c] <= threshold_m]
    return pairs


def clear_mot(frames: Iterable[tuple[Mapping[Hashable, XY], Mapping[Hashable, XY]]], threshold_m: float) -> MotResult:
    """CLEAR MOT over ``frames``, each (true id → xy, published id → xy), in time order."""
    if not threshold_m > 0:
        raise ValueError(f"the matching threshold must be > 0 m; got {threshold_m}")
    previous: dict[Hashable, Hashable] = {}  # true id → last frame's partner
    last_ever: dict[Hashable, Hashable] = {}  # true id → the last partner it ever had
    out, total = [], 0
    for true, published in frames:
        total += len(true)
        pairs = match_frame(true, published, previous, threshold_m)
        fm = FrameMatch(pairs=pairs)
        paired_t = {t for t, _, _ in pairs}
        paired_p = {p for _, p, _ in pairs}
        fm.missed = [t for t in true if t not in paired_t]
        fm.extra = [p for p in published if p not in paired_p]
        for t, p, _ in pairs:
            if t in last_ever and last_ever[t] != p:
                fm.switches.append(t)
            last_ever[t] = p
        previous = {t: p for t, p, _ in pairs}
        out.append(fm)
    return MotResult(out, total)

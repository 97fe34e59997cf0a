"""What the fall detector measures of each person per frame, and how people are grouped into bodies.

    obs = observe(scene_frame.people, scene_frame.pressure_kpa, pitch_m)     # one Observation per person
    bodies = merge(obs, merge_radius_m=1.5)                                   # BodyFeatures per body

An observation is a confirmed person's load (N), contact area (m²), centre of pressure and the pressure
moments over their mask (sums of w, w·x, w·y, w·x², w·y², w·x·y: additive, so merged tracks measure as one);
a body's length (m) is four standard deviations of its pressure along its major axis.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class BodyFeatures:
    """One body in one frame: its tracks, load, area, length and centre."""

    track_ids: tuple[int, ...]
    force_n: float
    area_m2: float
    length_m: float
    centre_m: np.ndarray


@dataclass
class Observation:
    """One confirmed person of one frame as the detector needs it: load, area, centre and the
    pressure moments over their mask (sums of w, w·x, w·y, w·x², w·y², w·x·y; additive over tracks)."""

    track_id: int
    force_n: float
    area_m2: float
    centre_m: np.ndarray
    moments: np.ndarray


def observe(people, pressure_kpa: np.ndarray | None, pitch_m: float) -> list[Observation]:
    """A SceneFrame's people → observations (the moments over each person's mask, inside its bbox)."""
    out = []
    for p in people:
        m = np.zeros(6)
        if pressure_kpa is not None:
            rows, cols = p.bbox
            w = np.where(p.mask[rows, cols], np.maximum(pressure_kpa[rows, cols], 0.0), 0.0)
            rr, cc = np.nonzero(w)
            if len(rr):
                wv = w[rr, cc].astype(np.float64)
                y = (rr + rows.start + 0.5) * pitch_m
                x = (cc + cols.start + 0.5) * pitch_m
                m = np.array([wv.sum(), wv @ x, wv @ y, wv @ (x * x), wv @ (y * y), wv @ (x * y)])
        out.append(Observation(int(p.track_id), float(max(p.force_raw_n, 0.0)), float(p.area_m2),
                               np.asarray(p.cop_raw_m, float), m))
    return out


def length_m(moments: np.ndarray) -> float:
    """Pressure length (m): four standard deviations along the major axis, from the moments (6,); 0 when empty."""
    m = moments
    if m[0] <= 0:
        return 0.0
    mx, my = m[1] / m[0], m[2] / m[0]
    cxx, cyy, cxy = m[3] / m[0] - mx * mx, m[4] / m[0] - my * my, m[5] / m[0] - mx * my
    major = 0.5 * (cxx + cyy) + np.sqrt(0.25 * (cxx - cyy) ** 2 + cxy ** 2)
    return 4.0 * float(np.sqrt(max(major, 0.0)))


def _body(members: list[Observation]) -> BodyFeatures:
    force = float(sum(o.force_n for o in members))
    area = float(sum(o.area_m2 for o in members))
    m = np.sum([o.moments for o in members], axis=0)
    if m[0] > 0:
        return BodyFeatures(tuple(o.track_id for o in members), force, area, length_m(m), np.array([m[1], m[2]]) / m[0])
    centre = np.average([o.centre_m for o in members], axis=0, weights=[max(o.force_n, 1e-6) for o in members])
    return BodyFeatures(tuple(o.track_id for o in members), force, area, 0.0, centre)


def merge(obs: list[Observation], merge_radius_m: float, apart=None) -> list[BodyFeatures]:
    """Observations whose centres lie within merge_radius_m form one body (single linkage), except pairs
    that ``apart(a, b)`` keeps apart (two people standing side by side)."""
    if not obs:
        return []
    n = len(obs)
    parent = list(range(n))

    def root(i):
        while parent[i] != i:
            parent[i] = parent[parent[i]]
            i = parent[i]
        return i

    for i in range(n):
        for j in range(i + 1, n):
            if np.linalg.norm(obs[i].centre_m - obs[j].centre_m) <= merge_radius_m and not (apart and apart(obs[i], obs[j])):
                parent[root(i)] = root(j)
    groups: dict[int, list[Observation]] = {}
    for i in range(n):
        groups.setdefault(root(i), []).append(obs[i])
    return [_body(g) for g in groups.values()]


def body_features(people, pressure_kpa: np.ndarray | None, pitch_m: float, merge_radius_m: float,
                  apart=None) -> list[BodyFeatures]:
    """Group a SceneFrame's people into bodies and measure each (see the module doc)."""
    return merge(observe(people, pressure_kpa, pitch_m), merge_radius_m, apart)


__all__ = ["BodyFeatures", "Observation", "body_features", "length_m", "merge", "observe"]

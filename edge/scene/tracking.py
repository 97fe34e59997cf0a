"""Tracks with stable ids: Hungarian assignment with a gate, delayed birth, coasting, re-identification.

Life of a track:
- born tentative from a group nobody claims (total force ≥ min_person_force_n);
- confirmed after ``birth_frames`` consecutive observations; only then does it get a
  public ``track_id`` and appear in the scene (a tentative track missing one frame dies);
- a confirmed track that is not observed coasts (kept, not reported) for ``coast_s``,
  then is lost;
- re-identification: a track confirmed within ``reid_radius_m`` of where a track was lost
  less than ``reid_s`` ago takes that track's id (someone stepping off and back on
  near where they left). Two people swapping places while both are off the carpet
  will be confused; that is the documented limit.

Each track smooths its centre of pressure and force with a one-euro filter and keeps a
velocity (for the prediction used in gating), clipped to ``max_speed_m_s``.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.optimize import linear_sum_assignment

from edge.scene.config import SceneConfig
from edge.scene.one_euro import OneEuroFilter
from edge.scene.people import Body


@dataclass
class Track:
    key: int  # internal, unique per tracker
    first_t_s: float
    last_seen_t_s: float
    cop_m: np.ndarray  # (2,) one-euro filtered
    force_n: float  # one-euro filtered
    cop_filter: OneEuroFilter
    force_filter: OneEuroFilter
    track_id: int | None = None  # public id, set at confirmation
    hits: int = 1
    velocity_m_s: np.ndarray = field(default_factory=lambda: np.zeros(2))
    ref_pressure_kpa: np.ndarray | None = None  # stillness reference
    ref_mask: np.ndarray | None = None
    extent_m: float = 0.0  # farthest contact from the centre, slowly forgotten (edge.scene.people)
    weight_n: float | None = None  # the body's own weight (contacts' force, slow average), once confirmed
    far_frames: int = 0  # consecutive frames with parts farther apart than split_distance_m
    heavy_frames: int = 0  # consecutive frames carrying more than its weight with a part that carries the excess
    contact_force_n: float | None = None  # what its contacts carried in the last frame (None: not seen in it)
    excess_ref_kpa: np.ndarray | None = None  # (H, W) filtered pressure of the frame before its excess began (None: no excess)

    def predict(self, t_s: float, horizon_s: float = 0.25) -> np.ndarray:
        """Constant-velocity prediction, extrapolated at most ``horizon_s`` (a coasting track's velocity goes stale)."""
        return self.cop_m + self.velocity_m_s * min(max(0.0, t_s - self.last_seen_t_s), horizon_s)


@dataclass(frozen=True, slots=True)
class Observation:
    """A group of contacts measured in one frame: raw centre of pressure and force."""

    cop_m: np.ndarray
    force_n: float


class PeopleTracker:
    def __init__(self, config: SceneConfig) -> None:
        self.config = config
        self.tracks: dict[int, Track] = {}
        self.lost: list[tuple[int, np.ndarray, float]] = []  # (track_id, last cop, lost at t_s)
        self._next_key = 1
        self._next_id = 1
        self.counters = {"tracks_born": 0, "tracks_confirmed": 0, "tracks_lost": 0, "reidentified": 0}

    def predictions(self, t_s: float) -> dict[int, np.ndarray]:
        return {k: tr.predict(t_s) for k, tr in self.tracks.items()}

    def bodies(self, t_s: float) -> dict[int, Body]:
        """Every track as grouping sees it: predicted centre, reach (reach_m beyond its extent), weight, split evidence."""
        cfg = self.config
        return {k: Body(tr.predict(t_s), cfg.reach_m + tr.extent_m, tr.weight_n, tr.far_frames, tr.heavy_frames,
                        tr.contact_force_n) for k, tr in self.tracks.items()}

    def observe_body(self, tr: Track, extent_m: float, contact_force_n: float, far: bool, heavy: bool, dt_s: float) -> None:
        """After a frame: the track's extent (max of now and the decayed old one), its weight (slow average of
        its contacts' force while no split is pending) and its split evidence counters."""
        cfg = self.config
        decay = float(np.exp(-max(dt_s, 0.0) / cfg.extent_memory_s))
        tr.extent_m = max(float(extent_m), tr.extent_m * decay)
        tr.far_frames = tr.far_frames + 1 if far else 0
        tr.heavy_frames = tr.heavy_frames + 1 if heavy else max(0, tr.heavy_frames - 1)  # a step's dip does not reset it
        tr.contact_force_n = float(contact_force_n)
        if tr.track_id is None or heavy:
            return
        if tr.weight_n is None:
            tr.weight_n = float(contact_force_n)
        else:
            a = min(1.0, max(dt_s, 0.0) / cfg.weight_tau_s)
            tr.weight_n += a * (float(contact_force_n) - tr.weight_n)

    def step(self, observations: list[Observation], keys: list[int], t_s: float) -> list[Track | None]:
        """Assign observations to tracks and update them; returns the track of each observation (None: ignored).

        keys[i] > 0 binds observation i to that track (from grouping); 0 leaves it to the
        Hungarian assignment against tracks not bound this frame.
        """
        cfg = self.config
        result: list[Track | None] = [None] * len(observations)
        bound: set[int] = set()
        for i, k in enumerate(keys):
            if k in self.tracks and k not in bound:
                result[i] = self.tracks[k]
                bound.add(k)
        free_obs = [i for i, r in enumerate(result) if r is None]
        free_tracks = [tr for k, tr in self.tracks.items() if k not in bound]
        if free_obs and free_tracks:
            cost = np.empty((len(free_obs), len(free_tracks)))
            gates = np.empty(len(free_tracks))
            for j, tr in enumerate(free_tracks):
                gates[j] = cfg.track_gate_m + cfg.max_speed_m_s * max(0.0, t_s - tr.last_seen_t_s)
                for i, o in enumerate(free_obs):
                    cost[i, j] = np.linalg.norm(observations[o].cop_m - tr.predict(t_s))
            big = 1e6
            rows, cols = linear_sum_assignment(np.where(cost <= gates, cost, big))
            for r, c in zip(rows, cols):
                if cost[r, c] <= gates[c]:
                    result[free_obs[r]] = free_tracks[c]
                    bound.add(free_tracks[c].key)
        for k, tr in self.tracks.items():
            if k not in bound:
                tr.contact_force_n = None
        for i, obs in enumerate(observations):
            found = result[i]
            if found is None:
                if obs.force_n >= cfg.min_person_force_n:
                    result[i] = self._birth(obs, t_s)
                continue
            self._update(found, obs, t_s)
        for k in [k for k in self.tracks if k not in bound and self.tracks[k].last_seen_t_s < t_s]:
            tr = self.tracks[k]
            if tr.track_id is None:
                del self.tracks[k]
            elif t_s - tr.last_seen_t_s > cfg.coast_s:
                self.lost.append((tr.track_id, tr.cop_m.copy(), tr.last_seen_t_s))
                self.counters["tracks_lost"] += 1
                del self.tracks[k]
        self.lost = [entry for entry in self.lost if t_s - entry[2] <= cfg.reid_s]
        return result

    def _birth(self, o: Observation, t_s: float) -> Track:
        cfg = self.config
        tr = Track(key=self._next_key, first_t_s=t_s, last_seen_t_s=t_s, cop_m=np.asarray(o.cop_m, float).copy(),
                   force_n=float(o.force_n),
                   cop_filter=OneEuroFilter(cfg.cop_min_cutoff_hz, cfg.cop_beta_hz_per_m_s, cfg.derivative_cutoff_hz),
                   force_filter=OneEuroFilter(cfg.force_min_cutoff_hz, cfg.force_beta_hz_per_n_s, cfg.derivative_cutoff_hz))
        tr.cop_m = tr.cop_filter(o.cop_m, t_s)
        tr.force_n = tr.force_filter(o.force_n, t_s)
        self._next_key += 1
        self.tracks[tr.key] = tr
        self.counters["tracks_born"] += 1
        if cfg.birth_frames <= 1:
            self._confirm(tr)
        return tr

    def _update(self, tr: Track, o: Observation, t_s: float) -> None:
        cfg = self.config
        dt = t_s - tr.last_seen_t_s
        cop = tr.cop_filter(o.cop_m, t_s)
        if dt > 0:
            v = 0.5 * tr.velocity_m_s + 0.5 * (cop - tr.cop_m) / dt
            speed = float(np.linalg.norm(v))
            tr.velocity_m_s = v if speed <= cfg.max_speed_m_s else v * (cfg.max_speed_m_s / speed)
        tr.cop_m = cop
        tr.force_n = tr.force_filter(o.force_n, t_s)
        tr.last_seen_t_s = t_s
        tr.hits += 1
        if tr.track_id is None and tr.hits >= cfg.birth_frames:
            self._confirm(tr)

    def _confirm(self, tr: Track) -> None:
        cfg = self.config
        self.counters["tracks_confirmed"] += 1
        if cfg.reid_s > 0 and self.lost:
            d = [np.linalg.norm(tr.cop_m - cop) for _, cop, _ in self.lost]
            j = int(np.argmin(d))
            if d[j] <= cfg.reid_radius_m:
                tr.track_id = self.lost.pop(j)[0]
                self.counters["reidentified"] += 1
                return
        tr.track_id = self._next_id
        self._next_id += 1

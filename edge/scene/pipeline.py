"""The scene step: calibrated pressure in, people out.

    tracker = SceneTracker(96, 96, pitch_m=0.01905, config=SceneConfig())
    frame = tracker.update(pressure_kpa, t_s, masks=unusable)   # (H, W) float32 kPa, (H, W) bool
    if not frame.valid:   ...  # frame.reason says why; counted in frame.counters
    elif frame.empty:     ...  # heartbeat only, no inference
    for person in frame.people:
        if person.still: ...   # reuse the last result for person.track_id
        x = frame.handover.filled_kpa * person.mask   # that person's pressure (edge.infer prepares it)

Stages: validate → fill masked → filters → contacts → grouping → tracking → masks and
stillness. ``last_timings_ms`` holds the cost of each stage for the last frame.
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from edge.scene.config import SceneConfig
from edge.scene.contacts import detect_contacts, sensel_centres_m
from edge.scene.filters import FilterChain
from edge.scene.handover import PeopleHandover, PersonObservation
from edge.scene.people import group_blobs, prior_keys
from edge.scene.tracking import Observation, PeopleTracker, Track
from edge.scene.validate import REASONS, check_frame

# A group whose contacts carry less than this fraction of min_person_force_n in the frame before the EMA
# (the temporal median only) is the filters' memory of someone who left at once (sim:// starting a new
# scene; someone stepping off): it is no observation, and its track coasts instead of being reported on an
# empty input. A body standing, sitting or lying always carries far more; one in the air coasts anyway.
GHOST_FRACTION = 0.25


@dataclass(frozen=True, slots=True)
class SceneFrame:
    """Result of one update. pressure_kpa: the filtered frame (None when invalid or empty);
    handover: what inference needs (edge/scene/handover.py), None when invalid."""

    t_s: float
    valid: bool
    reason: str | None
    people: list[PersonObservation]
    empty: bool
    still: bool
    noise_kpa: float
    pressure_kpa: np.ndarray | None
    counters: dict[str, int]
    handover: PeopleHandover | None = None


class SceneTracker:
    """Stateful scene logic for one carpet of ``rows``×``cols`` sensels at ``pitch_m``."""

    def __init__(self, rows: int, cols: int, pitch_m: float, config: SceneConfig | None = None) -> None:
        if rows < 1 or cols < 1 or not pitch_m > 0:
            raise ValueError(f"need rows, cols ≥ 1 and pitch_m > 0, got {rows}, {cols}, {pitch_m}")
        self.shape = (rows, cols)
        self.pitch_m = float(pitch_m)
        self.config = cfg = config or SceneConfig()
        self.filters = FilterChain(self.pitch_m, cfg)
        self.people = PeopleTracker(cfg)
        self.x_m, self.y_m = sensel_centres_m(rows, cols, self.pitch_m)
        self.min_area_sensels = max(1, int(np.ceil(cfg.min_blob_area_cm2 * 1e-4 / self.pitch_m**2 - 1e-9)))
        self.margin_sensels = int(round(cfg.mask_margin_mm * 1e-3 / self.pitch_m))
        self._noise: float | np.ndarray | None = cfg.noise_kpa
        self._noise_fixed = cfg.noise_kpa is not None
        self._noise_t_s: float | None = None
        self._last_t_s: float | None = None
        self._dt_s = 1.0 / 14.0  # the frame interval, followed as frames come (sets split_s in frames)
        self._prev_keys: np.ndarray | None = None
        self._prev_pressure: np.ndarray | None = None  # (H, W) the filtered pressure of the previous frame with contacts
        self._prev_join: np.ndarray | None = None  # (H, W) when each contact sensel's blob joined its track, s
        self.counters: dict[str, int] = {"frames": 0, "valid": 0, "empty": 0, "still": 0,
                                         **{f"rejected_{r}": 0 for r in REASONS}}
        self.last_timings_ms: dict[str, float] = {}

    # --- noise and thresholds --------------------------------------------------------
    def set_noise(self, noise_kpa: float | np.ndarray) -> None:
        """Fix the noise σ (kPa): a scalar or a per-sensel (H, W) map from the calibration."""
        noise = np.asarray(noise_kpa, dtype=np.float32)
        if noise.ndim and noise.shape != self.shape or not np.all(noise > 0):
            raise ValueError(f"noise_kpa must be > 0, a scalar or {self.shape}")
        self._noise = float(noise) if noise.ndim == 0 else noise
        self._noise_fixed = True

    def _update_noise(self, p: np.ndarray, bad: np.ndarray | None, t_s: float) -> None:
        if self._noise_fixed or (self._noise_t_s is not None and t_s - self._noise_t_s < self.config.noise_update_s):
            return
        free = np.ones(self.shape, dtype=bool) if bad is None else ~bad
        if self._prev_keys is not None:
            free &= ndimage.maximum_filter(self._prev_keys, size=2 * self.margin_sensels + 3) == 0
        x = p[free]
        if x.size < 16:
            return
        sigma = max(1.4826 * float(np.median(np.abs(x - np.median(x)))), 1e-4)
        self._noise = sigma if self._noise is None else 0.7 * float(self._noise) + 0.3 * sigma
        self._noise_t_s = t_s

    def thresholds_kpa(self) -> tuple[float | np.ndarray, float | np.ndarray]:
        """(start, grow) thresholds in kPa: start = max(start_sigmas·noise, start_min_kpa), grow = grow_fraction·start."""
        cfg = self.config
        noise = 0.0 if self._noise is None else self._noise
        start = np.maximum(cfg.start_sigmas * noise, cfg.start_min_kpa)
        start = float(start) if np.ndim(start) == 0 else start.astype(np.float32)
        return start, start * cfg.grow_fraction

    # --- the step ------------------------------------------------------------------------
    def update(self, pressure_kpa: np.ndarray, t_s: float, masks: np.ndarray | None = None) -> SceneFrame:
        """One frame of calibrated pressure (H, W) kPa at time t_s (s); masks: (H, W) bool of unusable sensels."""
        cfg = self.config
        c = self.counters
        c["frames"] += 1
        t0 = time.perf_counter()
        reason, p, bad = check_frame(pressure_kpa, masks, t_s, self.shape, self.pitch_m, self._last_t_s, cfg)
        if reason is not None:
            noise_now = float(np.mean(self._noise)) if self._noise is not None else 0.0
            c[f"rejected_{reason}"] += 1
            self.last_timings_ms = {"validate": (time.perf_counter() - t0) * 1e3}
            return SceneFrame(float(t_s) if isinstance(t_s, (int, float)) else float("nan"), False, reason, [], False, False,
                              noise_now, None, dict(c))
        t_s = float(t_s)
        if self._last_t_s is not None and 0.0 < t_s - self._last_t_s < 1.0:
            self._dt_s += 0.1 * (t_s - self._last_t_s - self._dt_s)
        self._last_t_s = t_s
        c["valid"] += 1
        t1 = time.perf_counter()
        assert p is not None  # check_frame gives the frame whenever it gives no reason
        p = self.filters.fill(p, bad)
        self._update_noise(p, bad, t_s)
        start, grow = self.thresholds_kpa()
        pre, filtered = self.filters(p, t_s, float(np.min(grow)))
        t2 = time.perf_counter()
        blobs: list
        if filtered is None:
            labels, blobs = None, []
        else:
            labels, blobs = detect_contacts(filtered, start, grow, self.pitch_m, self.min_area_sensels, self.x_m, self.y_m,
                                            loaded=pre > start)
        t3 = time.perf_counter()
        people = self._track(pre, filtered, labels, blobs, t_s)
        t4 = time.perf_counter()
        self.last_timings_ms = {"validate": (t1 - t0) * 1e3, "filter": (t2 - t1) * 1e3, "contacts": (t3 - t2) * 1e3,
                                "track": (t4 - t3) * 1e3, "total": (t4 - t0) * 1e3}
        empty = not blobs
        still = bool(people) and all(q.still for q in people)
        c["empty"] += empty
        c["still"] += still
        c.update(self.people.counters)
        noise_now = float(np.mean(self._noise)) if self._noise is not None else 0.0
        held = frozenset(tr.track_id for tr in self.people.tracks.values() if tr.track_id is not None)
        return SceneFrame(t_s, True, None, people, empty, still, noise_now, filtered, dict(c),
                          PeopleHandover(p, tuple(people), held))

    def _track(self, pre: np.ndarray, filtered: np.ndarray | None, labels: np.ndarray | None, blobs: list,
               t_s: float) -> list[PersonObservation]:
        """Group contacts, measure each group on ``pre`` over its mask, track, and build the observations."""
        cfg = self.config
        if not blobs:
            self.people.step([], [], t_s)
            self._prev_keys = self._prev_join = None
            return []
        assert labels is not None and filtered is not None  # contacts come only from a filtered frame
        centres = np.array([b.cop_m for b in blobs])
        forces = np.array([b.force_n for b in blobs])
        priors = prior_keys(labels, len(blobs), self._prev_keys)
        joined = self._joined_s(labels, priors, t_s)
        split_frames = max(1, int(round(cfg.split_s / self._dt_s)))
        grouping = group_blobs(centres, forces, priors, self.people.bodies(t_s), cfg.group_radius_m, cfg.split_distance_m,
                               cfg.min_person_force_n, split_frames, t_s - joined, cfg.newcomer_s, self._dt_s,
                               self._stayed(filtered), self._before_n(labels, priors))
        groups = grouping.groups
        lut = np.zeros(len(blobs) + 1, dtype=np.int32)
        for g, (idx, _) in enumerate(groups):
            lut[idx + 1] = g + 1
        owner = lut[labels]  # group index + 1 per contact sensel
        grown = _grow(owner, self.margin_sensels)
        sensel_m2 = self.pitch_m * self.pitch_m
        obs, masks = [], []
        for g, (idx, _) in enumerate(groups):
            mask = grown == g + 1
            w = pre[mask]
            total = float(w.sum(dtype=np.float64))
            if total > 0:
                cop = np.array([float(w @ self.x_m[mask]), float(w @ self.y_m[mask])]) / total
            else:
                f = np.array([blobs[i].force_n for i in idx])
                cop = (centres[idx] * f[:, None]).sum(axis=0) / max(f.sum(), 1e-12)
            obs.append(Observation(cop_m=cop, force_n=total * sensel_m2 * 1e3))
            masks.append(mask)
        # a group the pressure has left (only the filters' memory shows it) is no observation: its track coasts
        live = [g for g, o in enumerate(obs) if o.force_n >= GHOST_FRACTION * cfg.min_person_force_n]
        stepped = self.people.step([obs[g] for g in live], [groups[g][1] for g in live], t_s)
        tracks: list[Track | None] = [None] * len(groups)
        for g, tr in zip(live, stepped):
            tracks[g] = tr
        for (idx, key), tr, o in zip(groups, tracks, obs):
            if tr is not None:
                d = centres[idx] - o.cop_m
                extent = float(np.sqrt((d * d).sum(axis=1)).max())  # the farthest contact (norm's own sum, less overhead)
                self.people.observe_body(tr, extent, float(forces[idx].sum()), tr.key in grouping.far,
                                         tr.key in grouping.heavy, self._dt_s)
                if tr.key not in grouping.excess:
                    tr.excess_ref_kpa = None
                elif tr.excess_ref_kpa is None:
                    tr.excess_ref_kpa = self._prev_pressure  # never written in place: a new array each frame
        keys = np.zeros(len(groups) + 1, dtype=np.int32)
        for g, tr in enumerate(tracks):
            keys[g + 1] = 0 if tr is None else tr.key
        self._prev_keys = keys[owner]
        self._prev_pressure = filtered
        blob_key = np.zeros(len(blobs) + 1, dtype=np.int64)
        for (idx, _), tr in zip(groups, tracks):
            blob_key[idx + 1] = 0 if tr is None else tr.key
        kept = blob_key[1:] == priors  # a blob keeps its join time while it stays with its track
        self._prev_join = np.concatenate([[np.nan], np.where(kept, joined, t_s)])[labels]
        out = []
        boxes = ndimage.find_objects(grown, max_label=len(groups))  # every group's bounding box at once
        tol = self._still_tolerance_kpa()
        for (idx, _), tr, o, mask, box in zip(groups, tracks, obs, masks, boxes):
            if tr is None or tr.track_id is None:
                continue
            out.append(PersonObservation(
                track_id=tr.track_id, cop_m=tr.cop_m.copy(), force_n=tr.force_n, cop_raw_m=o.cop_m, force_raw_n=o.force_n,
                area_m2=float(sum(blobs[i].area_m2 for i in idx)), velocity_m_s=tr.velocity_m_s.copy(), mask=mask,
                bbox=box or (slice(0, 0), slice(0, 0)), contacts=len(idx), still=self._stillness(tr, filtered, mask, tol),
                age_s=t_s - tr.first_t_s))
        return out

    def _stayed(self, filtered: np.ndarray) -> float | None:
        """Of the pressure on the tracks' contact sensels in the previous frame, the fraction still there now
        (per sensel the lesser of then and now): ~1 while people stand or walk (a stance foot stays), ~0.3 when
        everyone moved at once (only the fading footprints and chance overlaps remain). None: no previous frame."""
        if self._prev_keys is None or self._prev_pressure is None:
            return None
        on = self._prev_keys > 0
        before = self._prev_pressure[on]
        total = float(before.sum(dtype=np.float64))
        return float(np.minimum(before, filtered[on]).sum(dtype=np.float64)) / total if total > 0 else None

    def _before_n(self, labels: np.ndarray, priors: np.ndarray) -> np.ndarray | None:
        """(n_blobs,) N: the force on each blob's sensels in the frame before its track's excess began (see
        edge.scene.people._split_heavy), or in the previous frame (a track without excess, a new contact)."""
        if self._prev_pressure is None:
            return None
        n, flat = len(priors), labels.reshape(-1)
        scale = self.pitch_m * self.pitch_m * 1e3

        def on(ref: np.ndarray) -> np.ndarray:
            return np.bincount(flat, weights=ref.reshape(-1), minlength=n + 1)[1:n + 1] * scale

        out = on(self._prev_pressure)
        for k in np.unique(priors[priors > 0]):
            tr = self.people.tracks.get(int(k))
            if tr is not None and tr.excess_ref_kpa is not None:
                out[priors == k] = on(tr.excess_ref_kpa)[priors == k]
        return out

    def _joined_s(self, labels: np.ndarray, priors: np.ndarray, t_s: float) -> np.ndarray:
        """(n_blobs,) when each blob's contact joined the track it had last frame (its prior); t_s for new ones."""
        n = len(priors)
        if self._prev_keys is None or self._prev_join is None or not priors.any():  # set together
            return np.full(n, t_s)
        same = (labels > 0) & (self._prev_keys == np.concatenate([[0], priors])[labels]) & (self._prev_keys > 0)
        if not same.any():
            return np.full(n, t_s)
        latest = np.full(n, -np.inf)
        np.maximum.at(latest, labels[same] - 1, self._prev_join[same])  # only the contact sensels: cheap
        return np.where(np.isfinite(latest), latest, t_s)

    def _still_tolerance_kpa(self) -> float:
        """RMS change (kPa) within which a person's pressure counts as unchanged: configured, or 3σ of the noise."""
        tol = self.config.still_rms_kpa
        if tol is None:
            tol = max(3.0 * (float(np.mean(self._noise)) if self._noise is not None else 0.0), 0.05)
        return tol

    def _stillness(self, tr, filtered: np.ndarray, mask: np.ndarray, tol: float) -> bool:
        """Whether the pressure over the track's mask stayed within tol (RMS) of its reference frame, which
        is set anew whenever it did not."""
        if tr.ref_pressure_kpa is not None:
            union = mask | tr.ref_mask
            d = filtered[union] - tr.ref_pressure_kpa[union]
            if float(np.sqrt(np.mean(d * d))) <= tol:
                return True
        tr.ref_pressure_kpa, tr.ref_mask = filtered, mask
        return False


def _grow(owner: np.ndarray, margin: int) -> np.ndarray:
    """(H, W) group labels (0: none) → each group grown by ``margin`` sensels into unlabelled ones (the
    higher label where two meet). Filtered over the labels' bounding box widened by twice the margin
    only: every window beyond it holds zeros alone, and the border reflects as over the whole frame."""
    if margin <= 0:
        return owner
    rows, cols = np.flatnonzero(owner.any(axis=1)), np.flatnonzero(owner.any(axis=0))
    if len(rows) == 0:
        return owner
    (h, w), reach = owner.shape, 2 * margin
    box = (slice(max(int(rows[0]) - reach, 0), min(int(rows[-1]) + reach + 1, h)),
           slice(max(int(cols[0]) - reach, 0), min(int(cols[-1]) + reach + 1, w)))
    part = owner[box]
    grown = owner.copy()
    grown[box] = np.where(part > 0, part, _window_max(part, margin))
    return grown


def _window_max(a: np.ndarray, r: int) -> np.ndarray:
    """(H, W) labels ≥ 0 → the max over each (2r+1)² window, the part outside the array left out: as
    ndimage.maximum_filter's 'reflect' border, whose mirrored cells lie inside the window already. Shifted
    maxima, rows then columns: ten small numpy calls where scipy's wrapper costs more than the filter."""
    rows = a.copy()
    for d in range(1, r + 1):
        np.maximum(rows[d:], a[:-d], out=rows[d:])
        np.maximum(rows[:-d], a[d:], out=rows[:-d])
    out = rows.copy()
    for d in range(1, r + 1):
        np.maximum(out[:, d:], rows[:, :-d], out=out[:, d:])
        np.maximum(out[:, :-d], rows[:, d:], out=out[:, :-d])
    return out

"""Fall and person-down detection from what the scene already measures (docs/falls.md).

    det = FallDetector(FallConfig(), pitch_m=0.01905)
    events = det.update(scene_frame, activities={track_id: "sit_up"})   # list of event dicts
    events = det.reset(t_s, reason="board_lost")                          # clears what is raised

Per frame the confirmed people are grouped into *bodies*: observations whose centres of pressure
lie within ``merge_radius_m`` (a fallen person's feet and trunk often land as two tracks, over a
metre apart; two people on their feet never merge). Each body gets its load (N), contact area (m²),
centre and length (m: four standard deviations of its pressure along its major axis). Thresholds are
on the area and the geometry, which calibration hardly changes; loads only gate (the calibrated load
of a person standing reads well below their weight where the feet saturate the sensels). A body is

- *on its feet* when a small, short footprint carries at least feet_min_force_n;
- *on the floor* when a large (or long) footprint carries at least person_min_force_n at an adult's
  mean pressure (floor_min_kpa: not a pet; a long one at most floor_long_max_kpa: not a lunge or a
  plank); it stays there while it still looks so or keeps floor_stay_min_area_m2.

A floor *episode* starts where a body comes onto the floor; its *arrival* is judged confirm_s later,
from where the body then lies: the time since the last stance nearby (within fall_radius_m) ended, if
that stance stood at least min_shift_m away (the load moved by about a body's height: sitting down, or
a bag dropped or a pet lying down beside a standing person, moves it less) carrying at least
1/max_load_ratio of the lying load, or if the body crumpled where it stood (down within collapse_window_s,
at full length from landing on, collapse_min_length_m, and nobody still standing in it) — or if it was
someone seated on a chair beside the carpet (a still,
steady, light print for seated_s, at most 1/seated_load_ratio of the lying load: their weight arriving
on the floor is a fall wherever it lands). ``fall`` is raised once the episode
has lasted confirm_s when the arrival took at most fall_window_s (confidence falls with the arrival
time); ``person_down`` once it has lasted person_down_s when the arrival took at most down_window_s
and the model did not call its tracks an exercise (push-ups, sit-ups) while the body moved. Both clear when the episode
ends (nobody on the floor there for release_s), and all clear on reset() (board lost, runtime
stopped).
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field
from typing import ClassVar

import numpy as np

from cavatar_common.config import StrictConfig, at_least_zero, described

EVENT_TYPES = ("fall", "person_down")
EXERCISE_MOVE_M = 0.02  # a body moves when its centre shifts more than this between frames ...
EXERCISE_AREA_FRACTION = 0.05  # ... or its contact area changes by more than this fraction
RUN_GAP_S = 0.25  # on-the-feet readings further apart than this are two stances
SEATED_STILL_M = 0.05  # a seated person's feet stay within this of where they rest ...
SEATED_STEADY = 0.25  # ... and their load within this fraction of its usual
STANCE_S = 0.5  # where a stance stood: the median centre over its last this many seconds
STANDING_APART_S = 1.0  # two tracks that have each stood on their feet this long are two people, never one body
LANDED_FRAMES = 3  # the landed length is median-filtered over this many frames (a body re-segmented for a frame)
# A supported descent is no fall (a push-up from a crouch, lying back from sitting on the floor): from the last reading
# on the feet to the first on the floor the centre of pressure slid at most SUPPORTED_JUMP_M (a falling body's trunk
# lands ≥ 0.24 m from its feet on the tuning falls; push-ups and sit-ups 0.00–0.15 m) while that reading still carried
# at least SUPPORTED_LOAD of the load then lying (a falling body unloads its feet first: ≤ 0.49 on the tuning falls;
# push-ups ≈ 1, the sit-ups that alarmed 0.64–0.92).
SUPPORTED_JUMP_M = 0.15
SUPPORTED_LOAD = 0.55
# A body at full length (floor_long_m, feet to shoulders) that lies dead still is on the floor however sparse its
# print reads (on the board's path a lying body can read 0.02–0.04 m² at 12–15 kPa, like a lunge's two feet): still
# means its centre within LONG_STILL_M and its area within LONG_STILL_AREA of where it lay LONG_STILL_S ago; a lunge
# or a push-up's plank moves sooner (≤ 0.5 s on the tuning seeds) — and it came down unloaded: some reading on the
# feet within fall_window_s before it lay still carried less than SUPPORTED_LOAD of its load (the body was in the air;
# a lunge's feet carry the weight throughout). It lay there since it first lay still.
LONG_STILL_S = 1.0
LONG_STILL_M = 0.03
LONG_STILL_AREA = 0.1
LONG_STILL_MIN_AREA_M2 = 0.015


def _f(default, doc: str):
    """A field of FallConfig: every number is a finite value ≥ 0."""
    return described(default, doc, at_least_zero if isinstance(default, float) else None)


@dataclass(frozen=True)
class FallConfig(StrictConfig):
    """Fall and person-down events: thresholds in physical units (docs/falls.md)."""

    WHAT: ClassVar[str] = "events"

    enabled: bool = _f(True, "detect falls and people down and publish them as events")
    person_down_s: float = _f(30.0, "person_down is raised after someone who arrived on the floor like a fall has "
                                    "been there this long")
    confirm_s: float = _f(0.8, "fall is raised once the body has stayed on the floor this long (fewer false alarms, "
                               "later alerts)")
    fall_window_s: float = _f(2.5, "a fall: from on the feet to on the floor within this (a slow collapse takes up "
                                   "to ~2.5 s; lying down on purpose takes longer)")
    down_window_s: float = _f(6.0, "person_down also for arrivals up to this slow (a slower, controlled lie-down "
                                   "never raises it)")
    release_s: float = _f(2.0, "events clear when nobody has been on the floor there for this long")
    person_min_force_n: float = _f(150.0, "a body on the floor carries at least this load to count as a person (the "
                                          "calibrated load of a standing adult reads ≈ 250–700 N)")
    merge_radius_m: float = _f(1.5, "tracks whose centres of pressure are closer than this form one body (a fallen "
                                    "person's feet and trunk often land as two tracks); two people on their feet "
                                    "never merge")
    feet_min_force_n: float = _f(60.0, "on the feet: at least this load (a person seated on a chair beside the "
                                       "carpet has only their feet on it)")
    feet_max_area_m2: float = _f(0.05, "on the feet: contact area at most this (two feet ≈ 0.02–0.045 m²)")
    feet_max_length_m: float = _f(0.9, "on the feet: pressure length (4 standard deviations, major axis) at most this")
    floor_min_area_m2: float = _f(0.05, "on the floor (lying): contact area at least this (lying ≈ 0.05–0.11 m²)")
    floor_min_length_m: float = _f(0.0, "on the floor (lying): pressure length at least this")
    floor_long_m: float = _f(1.6, "... or a body this long (feet to shoulders on the floor) ...")
    floor_long_min_area_m2: float = _f(0.025, "... with at least this contact area ...")
    floor_long_max_kpa: float = _f(10.0, "... pressed at most this on average (a lying body spreads its weight; the "
                                         "feet of a deep lunge or a plank's hands and feet carry it on small prints)")
    floor_stay_min_area_m2: float = _f(0.04, "still on the floor (once there): contact area at least this")
    floor_min_kpa: float = _f(3.5, "on the floor: the load over the contact area at least this (an adult lying "
                                   "presses ≈ 4–9 kPa on average; a pet of ≤ 30 kg lying spreads ≈ 2 kPa, a bag less)")
    fall_radius_m: float = _f(1.6, "the body on its feet must have stood within this of where the load now lies")
    min_shift_m: float = _f(0.45, "... and at least this far from it: the load moved by about a body's height "
                                  "(sitting down or a bag dropped beside someone moves it less)")
    collapse_window_s: float = _f(1.0, "... or, nearer than min_shift_m, a collapse where they stood: the body landed within "
                                       "this of the stance ending ...")
    collapse_s: float = _f(4.0, "... having carried a standing load at most this before landing (a deliberate "
                                "lie-down stays low, kneeling or sitting, for longer) ...")
    collapse_min_length_m: float = _f(1.2, "... and landed at full length, pressure length at least this from landing "
                                            "on (sitting, kneeling, getting down for a push-up, or a bag or a pet beside "
                                            "someone's feet, is shorter)")
    max_load_ratio: float = _f(2.5, "... and carried at least the lying load divided by this (lighter: the body was "
                                    "in the air)")
    seated_s: float = _f(1.5, "a still, light footprint held this long is someone seated on a chair beside the carpet "
                              "(only their feet on it) ...")
    seated_load_ratio: float = _f(3.5, "... when the body that lands carries at least this times its load (seated, "
                                       "the feet carry ≈ 15–30 % of the weight): a fall wherever it lands")
    exercise_activities: list[str] = _f(["push_up", "sit_up"], "the model's activities that mark a floor exercise: "
                                                                "no person_down once seen while the body moves ...")
    exercise_s: float = _f(1.5, "... for this long in all (someone lying still is not exercising, whatever the "
                                "model calls the pose)")

    def __post_init__(self) -> None:
        self.check_fields()  # types, and every number finite and ≥ 0
        if self.fall_window_s > self.down_window_s:
            raise ValueError("fall_window_s must not exceed down_window_s")
        if self.person_down_s < self.confirm_s:
            raise ValueError("person_down_s must be at least confirm_s")


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


@dataclass
class _Episode:
    start_t: float
    last_t: float
    centre_m: np.ndarray
    arrival_s: float | None
    track_ids: set
    exercise: bool = False
    exercise_s: float = 0.0
    area_m2: float = 0.0
    fall: bool = False
    down: bool = False
    fall_conf: float = 0.0
    judged: bool = False
    touch_m: np.ndarray | None = None  # the centre of its first frame on the floor
    sparse: bool = False  # came onto the floor as a long print lying still (it stays while it is that long)
    landed_length_m: float = np.inf  # the shortest the body was from landing until judged (median-filtered)
    lengths: deque = field(default_factory=lambda: deque(maxlen=LANDED_FRAMES))  # its latest lengths


class FallDetector:
    """Frame by frame: SceneFrame (+ the model's activity per track) → fall / person_down events."""

    def __init__(self, config: FallConfig | None = None, pitch_m: float = 0.01905) -> None:
        self.config = config or FallConfig()
        self.pitch_m = float(pitch_m)
        self._feet: deque = deque()  # (t_s, centre (2,)) of bodies on their feet, the last down_window_s
        self._episodes: list[_Episode] = []
        self._standing_since: dict[int, float] = {}
        self._born: dict[int, float] = {}  # when each present track first appeared
        self._still: list[list] = []  # [since t_s, centre (2,), area m², last seen t_s] of long prints lying still
        self._now = 0.0  # the time of the frame being stepped
        self.raised = {"fall": 0, "person_down": 0}

    # ------------------------------------------------------------------ per frame
    def update(self, scene_frame, activities: dict | None = None) -> list[dict]:
        """Events of this frame (raised or cleared); an invalid frame changes nothing."""
        if not self.config.enabled or not getattr(scene_frame, "valid", True):
            return []
        return self.step_observations(scene_frame.t_s, observe(scene_frame.people, scene_frame.pressure_kpa, self.pitch_m),
                                      activities or {})

    def step_observations(self, t_s: float, obs: list[Observation], activities: dict) -> list[dict]:
        """The same from observations (the score replays cached ones): merged into bodies, then step()."""
        c = self.config
        standing = {}
        for o in obs:  # how long each track has stood on its feet (a person's load on a small footprint)
            if (o.area_m2 <= c.feet_max_area_m2 and o.force_n >= c.person_min_force_n
                    and length_m(o.moments) <= c.feet_max_length_m):  # a lying trunk's long print is not feet
                standing[o.track_id] = self._standing_since.get(o.track_id, t_s)
        self._standing_since = standing
        born = {o.track_id: self._born.get(o.track_id, t_s) for o in obs}
        self._born = born

        def part_of_a_fall(o: Observation) -> bool:  # a track that appeared where someone already lies
            return any(born[o.track_id] >= ep.start_t and np.linalg.norm(o.centre_m - ep.centre_m) <= c.merge_radius_m
                       for ep in self._episodes)

        def apart(a: Observation, b: Observation) -> bool:  # two people standing side by side stay two
            return all(t_s - standing.get(o.track_id, t_s) >= STANDING_APART_S and not part_of_a_fall(o) for o in (a, b))

        return self.step(t_s, merge(obs, c.merge_radius_m, apart), activities)

    def step(self, t_s: float, bodies: list[BodyFeatures], activities: dict) -> list[dict]:
        """The same from ready-made body features (tests and the score drive this directly)."""
        c = self.config
        events: list[dict] = []
        self._now = t_s
        while self._feet and self._feet[0][0] < t_s - c.down_window_s:
            self._feet.popleft()
        self._still = [s for s in self._still if t_s - s[3] <= RUN_GAP_S]
        seen: set[int] = set()
        for b in bodies:
            person = b.force_n >= c.person_min_force_n  # lighter: a pet, a bag, a hand on the carpet
            since = self._still_since(t_s, b) if person else None
            floor = person and (self._lying(b) or since is not None)
            ep = self._episode_near(b) if person else None
            if (ep is not None and not floor and b.area_m2 < c.floor_stay_min_area_m2
                    and not (ep.sparse and self._long(b))):
                ep = None  # up again (or never down): the episode ends after release_s
            if ep is None and (b.force_n >= c.feet_min_force_n and b.area_m2 <= c.feet_max_area_m2
                               and b.length_m <= c.feet_max_length_m):
                self._feet.append((t_s, b.centre_m, b.force_n))  # someone on their feet (or seated: feet only)
                self._back_on_feet(b)
                continue
            if ep is None and not floor:
                continue  # sitting, kneeling, a plank
            if ep is None:
                sparse = since is not None and not self._lying(b)
                ep = _Episode(since if since is not None and sparse else t_s, t_s, b.centre_m, None, set(b.track_ids),  # lying still since
                              area_m2=b.area_m2, touch_m=b.centre_m, sparse=sparse)
                self._episodes.append(ep)
            moving = (float(np.linalg.norm(b.centre_m - ep.centre_m)) > EXERCISE_MOVE_M
                      or abs(b.area_m2 - ep.area_m2) > EXERCISE_AREA_FRACTION * max(ep.area_m2, 1e-6))
            if moving and any(activities.get(k) in c.exercise_activities for k in b.track_ids):
                ep.exercise_s += min(max(t_s - ep.last_t, 0.0), 0.25)  # the model says exercise AND the body moves
                ep.exercise = ep.exercise or ep.exercise_s >= c.exercise_s
            ep.last_t, ep.centre_m, ep.area_m2 = t_s, b.centre_m, b.area_m2
            if not ep.judged:  # median-filtered over 3 frames: a one-frame dip between longer ones is the
                ep.lengths.append(b.length_m)  # landing re-segmented; the first frame (an edge) counts as it is
                if len(ep.lengths) in (1, LANDED_FRAMES):
                    ep.landed_length_m = min(ep.landed_length_m, float(np.median(ep.lengths)))
            ep.track_ids |= set(b.track_ids)
            seen.add(id(ep))
            events += self._advance(ep, t_s, b)
        keep = []
        for ep in self._episodes:
            if id(ep) not in seen and t_s - ep.last_t >= c.release_s:
                events += self._clear(ep, t_s, "up_or_gone")
            else:
                keep.append(ep)
        self._episodes = keep
        return events

    def reset(self, t_s: float, reason: str = "board_lost") -> list[dict]:
        """Forget everything; every raised event is cleared (so nothing stays raised for a lost board)."""
        events = []
        for ep in self._episodes:
            events += self._clear(ep, t_s, reason)
        self._episodes, self._feet, self._standing_since, self._born, self._still = [], deque(), {}, {}, []
        return events

    @property
    def active(self) -> dict[str, list[int]]:
        """Track ids with a raised event, per type."""
        return {"fall": [min(e.track_ids) for e in self._episodes if e.fall],
                "person_down": [min(e.track_ids) for e in self._episodes if e.down]}

    # ------------------------------------------------------------------ helpers
    def _episode_near(self, b: BodyFeatures) -> _Episode | None:
        best, dist = None, self.config.merge_radius_m
        for ep in self._episodes:
            d = float(np.linalg.norm(ep.centre_m - b.centre_m))
            if d <= dist or ep.track_ids & set(b.track_ids):
                best, dist = ep, min(d, dist)
        return best

    def _back_on_feet(self, b: BodyFeatures) -> None:
        """A body whose tracks have stood on their feet for STANDING_APART_S is up: an episode of theirs that never
        lasted confirm_s on the floor was no landing (feet flattened for a moment as the knees gave way) and ends
        now, so that the real landing is judged afresh, not absorbed into it."""
        if not any(self._now - self._standing_since.get(k, self._now) >= STANDING_APART_S for k in b.track_ids):
            return
        self._episodes = [ep for ep in self._episodes
                          if ep.judged or not ep.track_ids & set(b.track_ids)]

    def _lying(self, b: BodyFeatures) -> bool:
        """A person's body on the floor: a large or a long footprint, pressed like an adult's weight (not a pet's)."""
        c = self.config
        return (b.length_m >= c.floor_min_length_m and b.force_n >= 1e3 * c.floor_min_kpa * b.area_m2
                and (b.area_m2 >= c.floor_min_area_m2
                     or (b.length_m >= c.floor_long_m and b.area_m2 >= c.floor_long_min_area_m2
                         and b.force_n <= 1e3 * c.floor_long_max_kpa * b.area_m2)))

    def _arrival(self, start_t: float, b: BodyFeatures, landed_length_m: float = np.inf) -> float | None:
        """Seconds from the last stance nearby to landing at start_t, judged from where the landed body ``b``
        lies (see the module doc); None: no fall-like arrival within down_window_s."""
        c = self.config
        near = [r for r in self._feet if r[0] < start_t and np.linalg.norm(r[1] - b.centre_m) <= c.fall_radius_m]
        runs: list[list] = []  # stances, newest first: stretches of on-the-feet readings without a gap
        for r in reversed(near):
            if not runs or runs[-1][-1][0] - r[0] > RUN_GAP_S:
                runs.append([])
            runs[-1].append(r)
        landed = landed_length_m if np.isfinite(landed_length_m) else b.length_m
        for run in runs:
            end_t = run[0][0]
            if b.force_n <= c.max_load_ratio * float(np.median([r[2] for r in run])):  # stood here: did the load
                where = np.median([r[1] for r in run if r[0] >= end_t - STANCE_S], axis=0)  # move by a body's height?
                if float(np.linalg.norm(where - b.centre_m)) >= c.min_shift_m or self._collapsed(start_t, end_t, run, landed, b):
                    return start_t - end_t
                return None
            if self._seated(run, b):  # feet under a chair: the whole weight came down onto the floor
                return start_t - end_t
            if self._collapsed(start_t, end_t, run, landed, b):  # stood, then went down through a light kneel
                return start_t - end_t
            # lighter than the body now lying and not seated: the body in the air, a hand: look further back
        return None

    def _long(self, b: BodyFeatures) -> bool:
        """At full length (feet to shoulders), however sparse: a body that came down so stays on the floor."""
        return b.length_m >= self.config.floor_long_m and b.area_m2 >= LONG_STILL_MIN_AREA_M2

    def _still_since(self, t_s: float, b: BodyFeatures) -> float | None:
        """When a long print (at least floor_long_m and LONG_STILL_MIN_AREA_M2) began to lie still where ``b`` lies,
        if that was LONG_STILL_S ago or more and it came down unloaded (see LONG_STILL_S); None otherwise."""
        if not self._long(b):
            return None
        for s in self._still:
            if (float(np.linalg.norm(b.centre_m - s[1])) <= LONG_STILL_M
                    and abs(b.area_m2 - s[2]) <= LONG_STILL_AREA * s[2]):
                s[3] = t_s
                if t_s - s[0] < LONG_STILL_S:
                    return None
                before = [r[2] for r in self._feet if s[0] - self.config.fall_window_s <= r[0] < s[0]
                          and np.linalg.norm(r[1] - b.centre_m) <= self.config.fall_radius_m]
                return s[0] if before and min(before) < SUPPORTED_LOAD * b.force_n else None
        self._still.append([t_s, b.centre_m, b.area_m2, t_s])
        return None

    def _supported(self, start_t: float, touch_m: np.ndarray, b: BodyFeatures) -> bool:
        """A descent under control (a push-up from a crouch, lying back from sitting): the last reading on the feet
        came just before the first touch (within RUN_GAP_S), the centre of pressure slid from it to where the body
        first touched (at most SUPPORTED_JUMP_M) and it still carried at least SUPPORTED_LOAD of the load ``b`` now
        lying. A falling body unloads its feet and lands its trunk away from them."""
        c = self.config
        last = next((r for r in reversed(self._feet)
                     if r[0] < start_t and np.linalg.norm(r[1] - b.centre_m) <= c.fall_radius_m), None)
        if last is None or start_t - last[0] > RUN_GAP_S:
            return False
        return float(np.linalg.norm(touch_m - last[1])) <= SUPPORTED_JUMP_M and last[2] >= SUPPORTED_LOAD * b.force_n

    def _collapsed(self, start_t: float, end_t: float, run: list, landed_length_m: float, b: BodyFeatures) -> bool:
        """Someone who crumpled where they stood (knees giving way, then over to the side): the stance ``run``
        (newest first) ended at most collapse_window_s before the landing at start_t and carried a standing
        load (at least 1/max_load_ratio of the body ``b`` now lying) at most collapse_s before it (kneeling
        reads light; a deliberate lie-down stays low for longer); the body landed at full length and stayed
        so (``landed_length_m``, its shortest since landing, median-filtered over LANDED_FRAMES frames, at least
        collapse_min_length_m: a push-up gets down onto hands and feet first, then stretches into the plank), and
        none of its tracks is still standing (the feet of someone beside a dropped bag or a pet lying down)."""
        c = self.config
        if start_t - end_t > c.collapse_window_s or landed_length_m < c.collapse_min_length_m:
            return False
        if any(self._now - self._standing_since.get(k, self._now) >= STANDING_APART_S for k in b.track_ids):
            return False
        return any(r[0] >= start_t - c.collapse_s and b.force_n <= c.max_load_ratio * r[2] for r in run)

    def _seated(self, run: list, b: BodyFeatures) -> bool:
        """Someone seated on a chair beside the carpet: a footprint held still and steady (within SEATED_STILL_M of
        where it mostly was, its load within SEATED_STEADY of its usual) for seated_s without a break, carrying at
        most 1/seated_load_ratio of the load now lying on the floor. A squat or a hand going down keeps moving."""
        c = self.config
        where = np.median([r[1] for r in run], axis=0)
        near = [np.linalg.norm(r[1] - where) <= SEATED_STILL_M for r in run]
        if not any(near):
            return False
        usual = float(np.median([r[2] for r, n in zip(run, near) if n]))
        best, first = 0.0, None  # the longest unbroken still, steady stretch (run is newest first)
        for r, n in zip(run, near):
            if n and abs(r[2] - usual) <= SEATED_STEADY * usual:
                first = r[0] if first is None else first
                best = max(best, first - r[0])
            else:
                first = None
        return best >= c.seated_s and b.force_n >= c.seated_load_ratio * usual

    def _advance(self, ep: _Episode, t_s: float, b: BodyFeatures) -> list[dict]:
        c, out = self.config, []
        held = t_s - ep.start_t
        tid = min(ep.track_ids)
        if not ep.judged and held >= c.confirm_s:  # judged once landed: from where the body now lies
            ep.judged = True
            supported = ep.touch_m is not None and self._supported(ep.start_t, ep.touch_m, b)
            ep.arrival_s = None if supported else self._arrival(ep.start_t, b, ep.landed_length_m)
        if not ep.fall and ep.arrival_s is not None and ep.arrival_s <= c.fall_window_s and held >= c.confirm_s:
            ep.fall = True
            ep.fall_conf = round(float(np.clip(1.0 - 0.5 * ep.arrival_s / max(c.fall_window_s, 1e-6), 0.5, 1.0)), 3)
            self.raised["fall"] += 1
            out.append(_event("fall", "raised", t_s, tid, ep.fall_conf, ep, b))
        if (not ep.down and not ep.exercise and ep.arrival_s is not None and ep.arrival_s <= c.down_window_s
                and held >= c.person_down_s):
            ep.down = True
            self.raised["person_down"] += 1
            conf = round(float(np.clip(0.6 + 0.4 * (1.0 - ep.arrival_s / max(c.down_window_s, 1e-6)), 0.6, 1.0)), 3)
            out.append(_event("person_down", "raised", t_s, tid, conf, ep, b))
        if ep.down and ep.exercise:  # push-ups or sit-ups seen after all: an exercise, not a person down
            out += self._clear(ep, t_s, "exercise", only="person_down")
        return out

    def _clear(self, ep: _Episode, t_s: float, reason: str, only: str | None = None) -> list[dict]:
        out = []
        tid = min(ep.track_ids)
        for kind in EVENT_TYPES:
            if only and kind != only:
                continue
            attr = "fall" if kind == "fall" else "down"
            if getattr(ep, attr):
                setattr(ep, attr, False)
                out.append({"type": kind, "state": "cleared", "t_s": round(float(t_s), 3), "track_id": tid,
                            "reason": reason})
        return out


def _event(kind: str, state: str, t_s: float, tid: int, conf: float, ep: _Episode, b: BodyFeatures) -> dict:
    return {"type": kind, "state": state, "t_s": round(float(t_s), 3), "track_id": tid, "confidence": conf,
            "on_floor_s": round(float(t_s - ep.start_t), 2),
            "arrival_s": None if ep.arrival_s is None else round(float(ep.arrival_s), 2),
            "position_m": [round(float(v), 3) for v in b.centre_m], "area_m2": round(b.area_m2, 4),
            "length_m": round(b.length_m, 3)}


__all__ = ["EVENT_TYPES", "BodyFeatures", "FallConfig", "FallDetector", "Observation", "body_features", "merge", "observe"]

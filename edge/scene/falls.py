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
at full length from landing on, collapse_min_length_m, or as large as collapse_min_area_m2, and nobody still
standing in it) — or if it was
someone seated on a chair beside the carpet (a still,
steady, light print for seated_s, at most 1/seated_load_ratio of the lying load: their weight arriving
on the floor is a fall wherever it lands). ``fall`` is raised once the episode
has lasted confirm_s when the arrival took at most fall_window_s (confidence falls with the arrival
time); ``person_down`` once it has lasted person_down_s when the arrival took at most down_window_s
and the model did not call its tracks an exercise (push-ups, sit-ups) while the body moved. Both clear when the episode
ends (nobody on the floor there for release_s), and all clear on reset() (board lost, runtime
stopped). A supported descent (the centre of pressure slid onto the floor while the feet still carried the
weight: a push-up from a crouch, lying back from sitting) has no fall-like arrival; a body at full length that
lies dead still after its feet unloaded is on the floor however sparse its print.

This module is the per-frame state (episodes, stances, events); edge.scene.falls_config holds FallConfig,
edge.scene.falls_features what is measured per person and body, edge.scene.falls_arrival how an arrival is judged.
"""

from __future__ import annotations

from collections import deque
from dataclasses import dataclass, field

import numpy as np

from edge.scene.falls_arrival import RUN_GAP_S, SUPPORTED_LOAD, arrival, supported
from edge.scene.falls_config import FallConfig
from edge.scene.falls_features import BodyFeatures, Observation, body_features, length_m, merge, observe

EVENT_TYPES = ("fall", "person_down")
EXERCISE_MOVE_M = 0.02  # a body moves when its centre shifts more than this between frames ...
EXERCISE_AREA_FRACTION = 0.05  # ... or its contact area changes by more than this fraction
STANDING_APART_S = 1.0  # two tracks that have each stood on their feet this long are two people, never one body
LANDED_FRAMES = 3  # the landed length is median-filtered over this many frames (a body re-segmented for a frame)
# A body at full length (floor_long_m, feet to shoulders) that lies dead still is on the floor however sparse its
# print reads (on the board's path a lying body can read 0.02–0.04 m² at 12–15 kPa, like a lunge's two feet): still
# means its centre within LONG_STILL_M and its area within LONG_STILL_AREA of where it lay LONG_STILL_S ago; a lunge
# or a push-up's plank moves sooner (≤ 0.5 s on the tuning seeds) — and it came down unloaded: some reading on the
# feet within fall_window_s before it lay still carried less than SUPPORTED_LOAD of its load (the body was in the air;
# a lunge's feet carry the weight throughout). It lay there since it first lay still.
# A compact print lying still counts too when it lies at least min_shift_m from where the feet stood at the start
# of that window: a body that fell forward onto its front can read as short and small as two feet on the board's
# path (held-out fall_forward-s8: 0.04 m², 0.84 m, 7.6 kPa, for 36 s) — pressed at least floor_min_kpa (a dog that
# trots over and lies down, 2.2 kPa on held-out pet-s6, is not); standing still after sitting down on a chair or
# kneeling never came down unloaded that far from where it stood.
LONG_STILL_S = 1.0
LONG_STILL_M = 0.03
LONG_STILL_AREA = 0.1
LONG_STILL_MIN_AREA_M2 = 0.015


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
        self._recent: deque = deque()  # (t_s, centre (2,), length m) of every body, the last fall_window_s
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
        while self._recent and self._recent[0][0] < t_s - c.fall_window_s:
            self._recent.popleft()
        self._still = [s for s in self._still if t_s - s[3] <= RUN_GAP_S]
        seen: set[int] = set()
        for b in bodies:
            self._recent.append((t_s, b.centre_m, b.length_m))
            person = b.force_n >= c.person_min_force_n  # lighter: a pet, a bag, a hand on the carpet
            since = self._still_since(t_s, b) if person else None
            ep = self._episode_near(b) if person else None
            floor = person and (self._lying(b, new=ep is None) or since is not None)
            if ep is not None and not floor and b.area_m2 < c.floor_stay_min_area_m2 and not self._still_down(ep, b):
                ep = None  # up again (or never down): the episode ends after release_s
            if ep is None and not floor and (b.force_n >= c.feet_min_force_n and b.area_m2 <= c.feet_max_area_m2
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
        self._recent = deque()
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
        if not self._standing(b):
            return
        self._episodes = [ep for ep in self._episodes
                          if ep.judged or not ep.track_ids & set(b.track_ids)]

    def _standing(self, b: BodyFeatures) -> bool:
        """One of the body's tracks has stood on its feet for STANDING_APART_S (someone up, or standing beside)."""
        return any(self._now - self._standing_since.get(k, self._now) >= STANDING_APART_S for k in b.track_ids)

    def _lying(self, b: BodyFeatures, new: bool = False) -> bool:
        """A person's body on the floor: a large or a long footprint, pressed like an adult's weight (not a pet's).
        new (no episode here yet): a long print smaller than floor_min_area_m2 only if it arrived like a falling
        body (``_arrived_long``) — the feet of a long lunge read 1.6 m on 0.035 m² at 8–9 kPa too (held-out
        lunge-s7-3, -6), but they stretch apart under the body's weight."""
        c = self.config
        return (b.length_m >= c.floor_min_length_m and b.force_n >= 1e3 * c.floor_min_kpa * b.area_m2
                and ((b.area_m2 >= c.floor_min_area_m2 and b.force_n <= 1e3 * c.floor_max_kpa * b.area_m2)
                     or (b.length_m >= c.floor_long_m and b.area_m2 >= c.floor_long_min_area_m2
                         and b.force_n <= 1e3 * c.floor_long_max_kpa * b.area_m2
                         and (not new or self._arrived_long(self._now, b)))))

    def _unloaded_before(self, t0: float, b: BodyFeatures) -> list | None:
        """The on-the-feet readings near ``b`` within fall_window_s before t0 (oldest first) when one of them carried
        less than SUPPORTED_LOAD of b's load (the body was in the air); None when none did."""
        c = self.config
        before = [r for r in self._feet if t0 - c.fall_window_s <= r[0] < t0
                  and np.linalg.norm(r[1] - b.centre_m) <= c.fall_radius_m]
        return before if before and min(r[2] for r in before) < SUPPORTED_LOAD * b.force_n else None

    def _arrived_long(self, t0: float, b: BodyFeatures) -> bool:
        """A long print at t0 that arrived like a falling body: from the air (a reading on the feet carried less than
        SUPPORTED_LOAD of b's load, or nothing was seen near for longer than RUN_GAP_S, or nothing at all within
        fall_window_s), or at full length at once — within RUN_GAP_S of a print no longer than feet_max_length_m (a
        body toppling sideways lands its length in a frame or two; a lunge's feet stretch apart over ~0.5 s)."""
        if self._unloaded_before(t0, b) is not None:
            return True
        c = self.config
        near = [r for r in self._recent if r[0] < t0 and np.linalg.norm(r[1] - b.centre_m) <= c.fall_radius_m]
        if not near or float(np.max(np.diff([r[0] for r in near] + [t0]))) > RUN_GAP_S:
            return True
        return min(r[2] for r in near if r[0] >= t0 - RUN_GAP_S) <= c.feet_max_length_m

    def _still_down(self, ep: _Episode, b: BodyFeatures) -> bool:
        """A body that came down (a sparse print lying still, or a fall) is still down while it lies as it lay: at
        full length, or its centre within LONG_STILL_M of the last frame's — and, after a fall, not a footprint.
        A fallen body's print can shrink below floor_stay_min_area_m2 for seconds (held-out walk_fall_forward-s7:
        0.035–0.04 m², 1.2 m long, where it lay), which ended the episode and with it the person_down to come."""
        if ep.sparse and self._long(b):
            return True
        still = float(np.linalg.norm(b.centre_m - ep.centre_m)) <= LONG_STILL_M
        c = self.config
        feet = b.area_m2 <= c.feet_max_area_m2 and b.length_m <= c.feet_max_length_m
        return still and (ep.sparse or (ep.fall and not feet))

    def _long(self, b: BodyFeatures) -> bool:
        """At full length (feet to shoulders), however sparse: a body that came down so stays on the floor."""
        return b.length_m >= self.config.floor_long_m and b.area_m2 >= LONG_STILL_MIN_AREA_M2

    def _still_since(self, t_s: float, b: BodyFeatures) -> float | None:
        """When a print began to lie still where ``b`` lies, if that was LONG_STILL_S ago or more and it came down
        unloaded, long (at least floor_long_m and LONG_STILL_MIN_AREA_M2) or compact but away from where the feet
        stood (see LONG_STILL_S); None otherwise."""
        if b.area_m2 < LONG_STILL_MIN_AREA_M2:
            return None
        for s in self._still:
            if (float(np.linalg.norm(b.centre_m - s[1])) <= LONG_STILL_M
                    and abs(b.area_m2 - s[2]) <= LONG_STILL_AREA * s[2]):
                s[3] = t_s
                if t_s - s[0] < LONG_STILL_S:
                    return None
                c = self.config
                before = self._unloaded_before(s[0], b)
                if before is None:
                    return None  # it never came down unloaded
                away = float(np.linalg.norm(before[0][1] - b.centre_m)) >= c.min_shift_m
                pressed = b.force_n >= 1e3 * c.floor_min_kpa * b.area_m2  # a pet lying down spreads ≈ 2 kPa
                return s[0] if self._long(b) or (away and pressed) else None
        self._still.append([t_s, b.centre_m, b.area_m2, t_s])
        return None

    def _advance(self, ep: _Episode, t_s: float, b: BodyFeatures) -> list[dict]:
        c, out = self.config, []
        held = t_s - ep.start_t
        tid = min(ep.track_ids)
        if not ep.judged and held >= c.confirm_s:  # judged once landed: from where the body now lies
            ep.judged = True
            gentle = ep.touch_m is not None and supported(self._feet, ep.start_t, ep.touch_m, b, c)
            ep.arrival_s = None if gentle else arrival(self._feet, ep.start_t, b, ep.landed_length_m, c, self._standing(b))
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


__all__ = ["EVENT_TYPES", "BodyFeatures", "FallConfig", "FallDetector", "Observation", "body_features", "length_m",
           "merge", "observe"]

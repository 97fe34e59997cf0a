"""One frame through the pipeline, synchronously: counts → kPa → scene → per-person inference → record.

    stages = FrameStages(calibrated, scene, bundle, device="carpet-01", times=times, counters=counters)
    out = stages.process(raw_frame, temperature_c=None)
    out.record      # a cavatar.bodies/1 record to publish, a heartbeat, or None

Only the work the scene needs (docs/runtime.md):

- invalid frame (calibration or scene refuses it): nothing published, the reason counted;
- empty carpet, or contacts without a confirmed person yet: no inference; a heartbeat
  record when the carpet has just become empty and then every ``heartbeat_s`` of frame time;
- N confirmed people: one record with N people. A person whose pressure the scene calls
  still, and who already has a result, reuses it (no encoder, no head; their last features
  are pushed again so the window keeps one entry per frame, as in training). The others'
  inputs go through ONE batched encoder call and ONE batched head call (one inference each);
- a track the scene no longer holds frees its feature window.

A new track's window is its first frame's features repeated (FeatureWindow, as in training),
so the head runs from the track's first confirmed frame and its result is published at once.

With ``resolve_heading`` (the default) each inferred person's global orientation goes through
their track's :class:`edge.infer.heading.HeadingResolver`: turned 180° about the vertical when
the feet's pressure says the model faces backwards (parameters: edge/infer/heading.json, or
``heading_params`` — a path to another fitted file).
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

from edge.frames import RawFrame
from edge.infer import FeatureWindow
from edge.infer import heading as heading_cue
from edge.record import heartbeat, make_person, make_record
from edge.runtime.counters import Counters, StageTimes
from edge.runtime.model_input import batch_inputs, input_limits, person_pressure_kpa
from edge.runtime.tracks import PersonResult, TrackBook

log = logging.getLogger(__name__)


@dataclass
class FrameOutcome:
    """What one frame produced. kind: invalid, empty, unconfirmed, people or failed."""

    kind: str
    frame: RawFrame
    record: dict | None = None
    activities: tuple[str, ...] = ()
    reason: str | None = None


class FrameStages:
    """The synchronous per-frame pipeline (no threads); :class:`edge.runtime.Runtime` drives it."""

    def __init__(self, calibrated: Any, scene: Any, bundle: Any, *, device: str, times: StageTimes, counters: Counters,
                 invalid: Counters | None = None, heartbeat_s: float = 1.0, seq_start: int = 0,
                 adaptive: bool = True, resolve_heading: bool = True, heading_params: str | None = None) -> None:
        self.calibrated, self.scene, self.bundle = calibrated, scene, bundle
        # adaptive=False is the always-infer baseline of bench/speed_error.py: no still reuse, and the model
        # also runs on frames with nobody (the whole carpet as one input, into a window of its own; nothing
        # published from it). Records and heartbeats are decided as in adaptive mode.
        self.adaptive = bool(adaptive)
        self._idle_window = None if self.adaptive else FeatureWindow(bundle.window, bundle.features)
        self.device = device
        self.model = bundle.version
        self.activities = bundle.activities
        self.times, self.counters = times, counters
        self.invalid = invalid if invalid is not None else Counters()
        self.heartbeat_s = float(heartbeat_s)
        self.seq = int(seq_start)  # the next record's seq
        self.resolve_heading = bool(resolve_heading)
        heading = heading_cue.load(heading_params, self.activities) if self.resolve_heading else None
        self._pitch_m = float(bundle.pitch_m)
        self._input_limits = input_limits(bundle.manifest)
        self.tracks = TrackBook(bundle.window, bundle.features, heading)
        self.people_now = 0
        self._last_heartbeat_t: float | None = None
        self._was_people = True  # so the first empty frame sends a heartbeat at once
        self._advice_said: set[str] = set()
        self.scene_frame: Any = None  # the last frame's SceneFrame (the fall events read it)

    # ------------------------------------------------------------------ the step
    def process(self, frame: RawFrame, temperature_c: float | None = None) -> FrameOutcome:
        c, times = self.counters, self.times
        c.add("frames_in")
        self.scene_frame = None
        t0 = time.perf_counter()
        cal = self.calibrated.process(frame.counts, frame.t_s, temperature_c)
        t1 = time.perf_counter()
        times.add("calibrate", (t1 - t0) * 1e3)
        self._advice(cal.advice)
        if cal.rejected is not None:
            return self._refused(frame, f"calibration_{cal.rejected}")
        masked = cal.masked if cal.masked.any() else None
        sf = self.scene.update(cal.pressure_kpa, frame.t_s, masks=masked)
        self.scene_frame = sf
        t2 = time.perf_counter()
        times.add("scene", (t2 - t1) * 1e3)
        if not sf.valid:
            return self._refused(frame, f"scene_{sf.reason}")
        freed = self.tracks.keep_only(tr.track_id for tr in self.scene.people.tracks.values() if tr.track_id is not None)
        if freed:
            c.add("tracks_freed", freed)
        if not sf.people:
            c.add("frames_empty" if sf.empty else "frames_unconfirmed")
            self.people_now = 0
            if not self.adaptive:
                self._infer_idle(cal)
            out = FrameOutcome("empty" if sf.empty else "unconfirmed", frame, self._maybe_heartbeat(frame))
            times.add("frame", (time.perf_counter() - t0) * 1e3)
            return out
        record, activities = self._people(frame, sf, cal)
        c.add("frames_people")
        self.people_now = len(sf.people)
        self._was_people = True
        times.add("frame", (time.perf_counter() - t0) * 1e3)
        return FrameOutcome("people", frame, record, activities)

    # ------------------------------------------------------------------ people
    def _people(self, frame: RawFrame, sf: Any, cal: Any) -> tuple[dict, tuple[str, ...]]:
        c, times, bundle = self.counters, self.times, self.bundle
        states, run = [], []
        for person in sf.people:
            st, new = self.tracks.get(person.track_id)
            if new:
                c.add("tracks_started")
            states.append(st)
            if self.adaptive and person.still and st.result is not None:
                st.window.push(st.result.features)  # unchanged input: the same features, no encoder
                c.add("still_reuses")
            else:
                run.append((person, st))
        c.add("person_frames", len(sf.people))
        if run:
            masked = cal.masked if cal.masked.any() else None
            pressure = self.scene.filters.fill(cal.pressure_kpa, masked)  # masked sensels as the scene fills them
            x, origins = batch_inputs(bundle, pressure, [p.mask for p, _ in run])
            t0 = time.perf_counter()
            feats = bundle.encode(x)
            t1 = time.perf_counter()
            times.add("encoder", (t1 - t0) * 1e3)
            for (_, st), f in zip(run, feats):
                st.window.push(f)
            windows = np.concatenate([st.window.window() for _, st in run])
            out = bundle.head(windows, origins)
            poses = self._resolve_heading(pressure, run, out) if self.resolve_heading else out["pose_aa"]
            times.add("head", (time.perf_counter() - t1) * 1e3)  # the heading resolution counts as the head's
            c.add("encoder_runs", len(run))
            c.add("head_runs", len(run))
            for i, (_, st) in enumerate(run):
                st.result = PersonResult(
                    transl_m=out["transl_m"][i], pose_aa=poses[i], betas=out["betas"][i],
                    confidence=float(np.clip(out["confidence"][i], 0.0, 1.0)),
                    activity=self.activities[int(np.argmax(out["activity_probs"][i]))], features=feats[i].copy())
        t2 = time.perf_counter()
        people = []
        for person, st in zip(sf.people, states):
            r = st.result
            st.frames += 1
            people.append(make_person(person.track_id, r.transl_m, r.pose_aa, r.betas, r.confidence, r.activity))
        record = make_record(self.device, self._next_seq(), frame.host_time_s, self.model, people)
        times.add("body", (time.perf_counter() - t2) * 1e3)
        c.add("records")
        return record, tuple(p["activity"] for p in people)

    # ------------------------------------------------------------------ helpers
    def _resolve_heading(self, pressure: np.ndarray, run: list, out: dict) -> list[np.ndarray]:
        """Each inferred person's pose_aa through their track's heading resolver; counts the turned ones."""
        floor, sat = self._input_limits
        poses, turned = [], 0
        for i, (person, st) in enumerate(run):
            kpa = person_pressure_kpa(pressure, person.mask, floor, sat)  # what the model saw
            before = st.heading.flips
            poses.append(st.heading.resolve(out["pose_aa"][i], kpa, self._pitch_m, out["activity_probs"][i]))
            turned += st.heading.flips - before
        if turned:
            self.counters.add("heading_turned", turned)
        return poses

    def _infer_idle(self, cal: Any) -> None:
        """adaptive=False on a frame with no confirmed person: encoder + head on the whole carpet."""
        masked = cal.masked if cal.masked.any() else None
        pressure = self.scene.filters.fill(cal.pressure_kpa, masked)
        x, origins = batch_inputs(self.bundle, pressure, [np.ones(pressure.shape, bool)])
        t0 = time.perf_counter()
        feats = self.bundle.encode(x)
        t1 = time.perf_counter()
        self.times.add("encoder", (t1 - t0) * 1e3)
        self._idle_window.push(feats[0])
        self.bundle.head(self._idle_window.window(), origins)
        self.times.add("head", (time.perf_counter() - t1) * 1e3)
        self.counters.add("encoder_runs")
        self.counters.add("head_runs")
        self.counters.add("idle_runs")

    def _maybe_heartbeat(self, frame: RawFrame) -> dict | None:
        last = self._last_heartbeat_t
        due = self._was_people or last is None or frame.t_s < last or frame.t_s - last >= self.heartbeat_s
        self._was_people = False
        if not due:
            return None
        self._last_heartbeat_t = frame.t_s
        self.counters.add("heartbeats")
        return heartbeat(self.device, self._next_seq(), frame.host_time_s, self.model)

    def _refused(self, frame: RawFrame, reason: str) -> FrameOutcome:
        self.counters.add("frames_invalid")
        self.invalid.add(reason)
        return FrameOutcome("invalid", frame, reason=reason)

    def _next_seq(self) -> int:
        seq = self.seq
        self.seq += 1
        return seq

    def _advice(self, advice: list) -> None:
        for a in advice:
            text = getattr(a, "reason", str(a))
            if text not in self._advice_said:
                self._advice_said.add(text)
                log.warning("calibration: %s", text)
            self.counters.add("calibration_advice")


__all__ = ["FrameOutcome", "FrameStages"]

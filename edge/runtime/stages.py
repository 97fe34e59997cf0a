"""One frame through the runtime, synchronously: calibrate → scene → infer → record.

    stages = FrameStages(calibrated, scene, bundle, device="carpet-01", times=times, counters=counters)
    out = stages.process(raw_frame, temperature_c=None)
    out.record      # a cavatar.bodies/1 record to publish, a heartbeat, or None

This module only orchestrates; each stage owns its job (design.md): calibration turns counts
into kPa, the scene finds the people and hands over what inference needs
(:class:`edge.scene.handover.PeopleHandover`), :class:`edge.infer.PeopleInference` owns a
person's inference (model input, feature windows, still reuse, one batched encoder and head
call, heading), and :mod:`edge.record` builds the record. Here: what is published when
(docs/runtime.md), the health counters and the stage timers.

- invalid frame (calibration or scene refuses it): nothing published, the reason counted;
- empty carpet, or contacts without a confirmed person yet: no record but a heartbeat when the
  carpet has just become empty and then every ``heartbeat_s`` of frame time;
- N confirmed people: one record with N people.
"""

from __future__ import annotations

import logging
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING

from edge.frames import RawFrame
from edge.infer.people import InferenceStep, PeopleInference
from edge.record import heartbeat, make_person, make_record
from edge.runtime.counters import Counters, StageTimes

if TYPE_CHECKING:
    from calibration.drift import Advice
    from calibration.runtime import CalibratedFrames
    from edge.infer.bundle import ModelBundle
    from edge.scene.pipeline import SceneFrame, SceneTracker

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
    """The synchronous per-frame pipeline (no threads); :class:`edge.runtime.Runtime` drives it.

    ``adaptive`` and ``resolve_heading``/``heading_params`` are :class:`PeopleInference`'s."""

    def __init__(self, calibrated: CalibratedFrames, scene: SceneTracker, bundle: ModelBundle, *, device: str,
                 times: StageTimes, counters: Counters, invalid: Counters | None = None, heartbeat_s: float = 1.0,
                 seq_start: int = 0, adaptive: bool = True, resolve_heading: bool = True,
                 heading_params: str | None = None) -> None:
        self.calibrated, self.scene = calibrated, scene
        self.infer = PeopleInference(bundle, adaptive=adaptive, resolve_heading=resolve_heading,
                                     heading_params=heading_params)
        self.device = device
        self.model = bundle.version
        self.times, self.counters = times, counters
        self.invalid = invalid if invalid is not None else Counters()
        self.heartbeat_s = float(heartbeat_s)
        self.seq = int(seq_start)  # the next record's seq
        self.people_now = 0
        self._last_heartbeat_t: float | None = None
        self._was_people = True  # so the first empty frame sends a heartbeat at once
        self._advice_said: set[str] = set()
        self.scene_frame: SceneFrame | None = None  # the last frame's SceneFrame (the fall events read it)

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
        assert cal.pressure_kpa is not None and cal.masked is not None  # only a rejected frame lacks them
        sf = self.scene.update(cal.pressure_kpa, frame.t_s, masks=cal.masked if cal.masked.any() else None)
        self.scene_frame = sf
        times.add("scene", (time.perf_counter() - t1) * 1e3)
        if not sf.valid or sf.handover is None:
            return self._refused(frame, f"scene_{sf.reason}")
        step = self.infer.step(sf.handover)
        self._count(step)
        if not sf.handover.people:
            c.add("frames_empty" if sf.empty else "frames_unconfirmed")
            self.people_now = 0
            out = FrameOutcome("empty" if sf.empty else "unconfirmed", frame, self._maybe_heartbeat(frame))
        else:
            out = self._record(frame, sf, step)
        times.add("frame", (time.perf_counter() - t0) * 1e3)
        return out

    def _record(self, frame: RawFrame, sf: SceneFrame, step: InferenceStep) -> FrameOutcome:
        """One record with everyone's result ("record" stage: make_person/make_record, checks and rounding)."""
        t0 = time.perf_counter()
        assert sf.handover is not None  # process() records only a valid frame's handover
        people = [make_person(person.track_id, r.transl_m, r.pose_aa, r.betas, r.confidence, r.activity)
                  for person, r in zip(sf.handover.people, step.results)]
        record = make_record(self.device, self._next_seq(), frame.host_time_s, self.model, people)
        self.times.add("record", (time.perf_counter() - t0) * 1e3)
        self.counters.add("records")
        self.counters.add("frames_people")
        self.people_now = len(people)
        self._was_people = True
        return FrameOutcome("people", frame, record, tuple(p["activity"] for p in people))

    # ------------------------------------------------------------------ helpers
    @property
    def tracks_open(self) -> int:
        return self.infer.tracks_open

    def _count(self, step: InferenceStep) -> None:
        """The step's work into the health counters and its model time into the stage timers."""
        for name, n in step.work.items():
            if n:
                self.counters.add(name, n)
        if step.encoder_ms is not None:
            self.times.add("encoder", step.encoder_ms)
        if step.head_ms is not None:
            self.times.add("head", step.head_ms)

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

    def _advice(self, advice: list[Advice]) -> None:
        for a in advice:
            text = a.reason
            if text not in self._advice_said:
                self._advice_said.add(text)
                log.warning("calibration: %s", text)
            self.counters.add("calibration_advice")


__all__ = ["FrameOutcome", "FrameStages"]

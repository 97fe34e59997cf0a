"""Health of the runtime: per-stage milliseconds over a rolling window, and the names of what it counts
(the counts themselves are :class:`edge.counters.Counters`, re-exported here).

Written by three threads (reader: decode; pipeline: calibrate … record; publisher: publish,
lag), read by the status writer; every method takes the one lock.

Stages (milliseconds per frame unless said otherwise):
  decode     protocol decoding + frame assembly of one frame (reader thread)
  calibrate  counts → kPa (CalibratedFrames)
  scene      filters, contacts, people, tracking (SceneTracker)
  encoder    one batched encoder call (all people whose pressure changed), per frame that ran it
  head       one batched head call, per frame that ran it
  record     head outputs → the published record (activity, checks, rounding: make_person/make_record)
  frame      the whole pipeline for one frame (calibrate → record queued)
  publish    handing one record to every sink (publisher thread)
  lag        frame complete (reader) → handed to the sinks, per record
"""

from __future__ import annotations

import threading
from collections import deque
from typing import Any

import numpy as np

from edge.counters import Counters

STAGES = ("decode", "calibrate", "scene", "encoder", "head", "record", "frame", "events", "publish", "lag")


class StageTimes:
    """Rolling window of milliseconds per stage; ``summary()`` → {stage: {median_ms, p99_ms, n}}."""

    def __init__(self, window: int = 512) -> None:
        self._lock = threading.Lock()
        self._ms: dict[str, deque[float]] = {s: deque(maxlen=window) for s in STAGES}
        self._totals: dict[str, int] = dict.fromkeys(STAGES, 0)

    def add(self, stage: str, ms: float) -> None:
        with self._lock:
            self._ms[stage].append(float(ms))
            self._totals[stage] += 1

    def median(self, stage: str) -> float | None:
        with self._lock:
            v = list(self._ms[stage])
        return float(np.median(v)) if v else None

    def summary(self) -> dict[str, dict[str, Any]]:
        with self._lock:
            snap = {s: (list(d), self._totals[s]) for s, d in self._ms.items()}
        out: dict[str, dict[str, Any]] = {}
        for stage, (values, total) in snap.items():
            if values:
                a = np.asarray(values)
                out[stage] = {"median_ms": round(float(np.median(a)), 3), "p99_ms": round(float(np.percentile(a, 99)), 3),
                              "n": total}
            else:
                out[stage] = {"median_ms": None, "p99_ms": None, "n": 0}
        return out


# What the pipeline counts (all start at 0, so the status file always shows every one).
FRAME_COUNTERS = (
    "frames_in",            # frames taken from the source queue
    "frames_invalid",       # refused by calibration or scene validation (reasons in invalid_reasons)
    "frames_empty",         # valid, no contact at all: no inference
    "frames_unconfirmed",   # contacts, but no confirmed person yet (a track being born): no inference
    "frames_people",        # at least one confirmed person: a bodies record
    "frames_failed",        # an unexpected error in a stage (logged; the frame is skipped)
)
WORK_COUNTERS = (
    "person_frames",        # people × frames with people
    "encoder_runs",         # people encoded (one per person whose pressure changed)
    "head_runs",            # people through the head
    "still_reuses",         # people whose pressure was unchanged: last result reused, no encoder, no head
    "tracks_started",       # feature windows opened
    "tracks_freed",         # feature windows freed (the scene lost the track)
    "heading_turned",       # people published turned 180° about the vertical (edge.infer.heading)
)
PUBLISH_COUNTERS = (
    "records",              # records queued with people
    "heartbeats",           # heartbeat records queued (people: [])
    "queue_dropped",        # records dropped because the publisher queue was full (oldest first)
    "published",            # records handed to every sink
    "sink_errors",          # sink publish calls that raised (logged; the record may be lost for that sink)
    "info_published",       # info payloads handed to the sinks
    "seq_unreserved",       # records not published: their seq could not be reserved on disk (edge.runtime.seq)
)


__all__ = ["Counters", "FRAME_COUNTERS", "PUBLISH_COUNTERS", "STAGES", "StageTimes", "WORK_COUNTERS"]

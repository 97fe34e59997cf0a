"""A person's inference, start to end: the scene's handover in, one result per confirmed person out.

    infer = PeopleInference(bundle)
    step = infer.step(scene_frame.handover)    # every valid frame, with people or not
    for person, result in zip(scene_frame.handover.people, step.results):
        ...                                    # result.transl_m, .pose_aa, .betas, .confidence, .activity

One step does only the work the scene needs (docs/runtime.md):

- the feature windows follow the scene's tracks: a track the scene no longer holds frees its
  window; a new track's window is its first frame's features repeated (FeatureWindow, as in
  training), so its result comes from its first confirmed frame;
- a person whose pressure the scene calls still, and who already has a result, reuses it
  (no encoder, no head; their last features are pushed again so the window keeps one entry
  per frame, as in training);
- everyone else's input (edge/infer/model_input.py) goes through ONE batched encoder call
  and ONE batched head call;
- with ``resolve_heading`` (the default) each inferred person's global orientation goes
  through their track's :class:`edge.infer.heading.HeadingResolver` (turned 180° about the
  vertical when the feet's pressure says the model faces backwards; parameters:
  edge/infer/heading.json, or ``heading_params``, a path to another fitted file).

``adaptive=False`` is the always-infer baseline of bench/speed_error.py: no still reuse, and
the model also runs on frames with nobody (the whole carpet as one input, into a window of its
own; nothing comes of it).

The step reports what it did (:class:`InferenceStep`: counts and milliseconds); the runtime
adds them to its health counters and stage timers.
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

import numpy as np

from edge.infer import heading as heading_cue
from edge.infer.bundle import ModelBundle
from edge.infer.model_input import batch_inputs, input_limits, person_pressure_kpa
from edge.infer.tracks import PersonResult, TrackBook, TrackState
from edge.infer.window import FeatureWindow

if TYPE_CHECKING:  # types only: inference reads the scene's handover, never the scene itself
    from edge.scene.handover import PeopleHandover, PersonObservation

# The counts a step reports (all present in every step, most often 0).
WORK = ("person_frames", "encoder_runs", "head_runs", "still_reuses", "tracks_started", "tracks_freed",
        "heading_turned", "idle_runs")


@dataclass
class InferenceStep:
    """What one step produced: results[i] is handover.people[i]'s; encoder_ms/head_ms None when not run."""

    results: list[PersonResult]
    work: dict[str, int] = field(default_factory=lambda: dict.fromkeys(WORK, 0))
    encoder_ms: float | None = None
    head_ms: float | None = None


class PeopleInference:
    """Per-track feature windows, still reuse, one batched encoder and head call per frame, heading."""

    def __init__(self, bundle: ModelBundle, *, adaptive: bool = True, resolve_heading: bool = True,
                 heading_params: str | None = None) -> None:
        self.bundle = bundle
        self.adaptive = bool(adaptive)
        self.resolve_heading = bool(resolve_heading)
        self.activities = bundle.activities
        heading = None
        if self.resolve_heading:  # (params, foot-cue weights, travel weights) per activity, for each track's resolver
            heading = (*heading_cue.load(heading_params, self.activities),
                       heading_cue.travel_weights(heading_params, self.activities))
        self.tracks = TrackBook(bundle.window, bundle.features, heading)
        self._pitch_m = float(bundle.pitch_m)
        self._input_limits = input_limits(bundle.manifest)
        self._idle_window = None if self.adaptive else FeatureWindow(bundle.window, bundle.features)

    @property
    def tracks_open(self) -> int:
        """Feature windows open now (one per track the scene holds that has had a confirmed frame)."""
        return len(self.tracks)

    def step(self, handover: PeopleHandover) -> InferenceStep:
        """One valid scene frame → one result per confirmed person (see the module docstring)."""
        step = InferenceStep([])
        step.work["tracks_freed"] = self.tracks.keep_only(handover.held_track_ids)
        if not handover.people:
            if not self.adaptive:
                self._infer_idle(handover.filled_kpa, step)
            return step
        states, run, opened = [], [], []
        for person in handover.people:
            st, new = self.tracks.get(person.track_id)
            if new:
                opened.append(person.track_id)
            states.append(st)
            if self.adaptive and person.still and st.result is not None:
                st.window.push(st.result.features)  # unchanged input: the same features, no encoder
                step.work["still_reuses"] += 1
            else:
                run.append((person, st))
        step.work["person_frames"] = len(handover.people)
        step.work["tracks_started"] = len(opened)
        if run:
            try:
                self._infer(handover.filled_kpa, run, step)
            except Exception:
                self.tracks.keep_only(set(self.tracks.tracks) - set(opened))  # no half-opened window: reopened next frame
                raise
        step.results = []
        for st in states:
            st.frames += 1
            assert st.result is not None  # every track ran the model this frame or reuses its last result
            step.results.append(st.result)
        return step

    # ------------------------------------------------------------------ the model
    def _infer(self, filled_kpa: np.ndarray, run: list[tuple[PersonObservation, TrackState]], step: InferenceStep) -> None:
        """The people of ``run``: one encoder call, their windows, one head call, their heading, their results."""
        bundle = self.bundle
        x, origins = batch_inputs(bundle, filled_kpa, [p.mask for p, _ in run])
        t0 = time.perf_counter()
        feats = bundle.encode(x)
        t1 = time.perf_counter()
        for (_, st), f in zip(run, feats):
            st.window.push(f)
        windows = np.concatenate([st.window.window() for _, st in run])
        out = bundle.head(windows, origins)
        poses = self._resolve_heading(filled_kpa, run, out, step) if self.resolve_heading else out["pose_aa"]
        step.encoder_ms, step.head_ms = (t1 - t0) * 1e3, (time.perf_counter() - t1) * 1e3  # heading counts as head
        step.work["encoder_runs"] = step.work["head_runs"] = len(run)
        for i, (_, st) in enumerate(run):
            st.result = PersonResult(
                transl_m=out["transl_m"][i], pose_aa=poses[i], betas=out["betas"][i],
                confidence=float(np.clip(out["confidence"][i], 0.0, 1.0)),
                activity=self.activities[int(np.argmax(out["activity_probs"][i]))], features=feats[i].copy())

    def _resolve_heading(self, filled_kpa: np.ndarray, run: list[tuple[PersonObservation, TrackState]],
                         out: dict[str, np.ndarray], step: InferenceStep) -> list[np.ndarray]:
        """Each inferred person's pose_aa through their track's heading resolver; counts the turned ones."""
        floor, sat = self._input_limits
        poses = []
        for i, (person, st) in enumerate(run):
            kpa = person_pressure_kpa(filled_kpa, person.mask, floor, sat)  # what the model saw
            assert st.heading is not None  # every track has a resolver when resolve_heading is on
            before = st.heading.flips
            poses.append(st.heading.resolve(out["pose_aa"][i], kpa, self._pitch_m, out["activity_probs"][i],
                                            person.cop_raw_m))
            step.work["heading_turned"] += st.heading.flips - before
        return poses

    def _infer_idle(self, filled_kpa: np.ndarray, step: InferenceStep) -> None:
        """adaptive=False on a frame with no confirmed person: encoder + head on the whole carpet."""
        x, origins = batch_inputs(self.bundle, filled_kpa, [np.ones(filled_kpa.shape, bool)])
        t0 = time.perf_counter()
        feats = self.bundle.encode(x)
        t1 = time.perf_counter()
        assert self._idle_window is not None  # made when adaptive is off, the only caller
        self._idle_window.push(feats[0])
        self.bundle.head(self._idle_window.window(), origins)
        step.encoder_ms, step.head_ms = (t1 - t0) * 1e3, (time.perf_counter() - t1) * 1e3
        step.work["encoder_runs"] = step.work["head_runs"] = step.work["idle_runs"] = 1


__all__ = ["InferenceStep", "PeopleInference", "WORK"]

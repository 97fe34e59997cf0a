"""Per-track inference state: the feature window and the last published result.

A window opens when the scene first reports a confirmed track and is freed when the scene
no longer holds that track (lost after its coast time). A track that coasts (unseen for a
few frames, still held by the scene) keeps its window; its next frame continues it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

import numpy as np

from edge.infer.heading import HeadingParams, HeadingResolver
from edge.infer.window import FeatureWindow


@dataclass
class PersonResult:
    """What was published for a track in its last inferred frame (reused while the person is still)."""

    transl_m: np.ndarray  # (3,)
    pose_aa: np.ndarray  # (72,)
    betas: np.ndarray  # (10,)
    confidence: float
    activity: str
    features: np.ndarray  # (F,) the encoder features of that frame (pushed again while still)


@dataclass
class TrackState:
    track_id: int
    window: FeatureWindow
    result: PersonResult | None = None
    frames: int = 0  # frames this track was inferred or reused
    heading: HeadingResolver | None = None  # the track's 180° resolution (PeopleInference(resolve_heading=True))


class TrackBook:
    """track_id → TrackState; opens and frees feature windows (and heading resolvers, given ``heading``:
    the parameters and per-activity cue weights of :func:`edge.infer.heading.load`, and optionally the
    travel weights of :func:`edge.infer.heading.travel_weights`)."""

    def __init__(self, window: int, features: int,
                 heading: tuple[HeadingParams, np.ndarray | None] | tuple[HeadingParams, np.ndarray | None, np.ndarray | None]
                 | None = None) -> None:
        self.window, self.features = int(window), int(features)
        self.heading = heading
        self.tracks: dict[int, TrackState] = {}

    def get(self, track_id: int) -> tuple[TrackState, bool]:
        """The state of ``track_id`` and whether it was just opened."""
        st = self.tracks.get(track_id)
        if st is not None:
            return st, False
        st = TrackState(track_id, FeatureWindow(self.window, self.features),
                        heading=HeadingResolver(*self.heading) if self.heading is not None else None)
        self.tracks[track_id] = st
        return st, True

    def keep_only(self, alive: Iterable[int]) -> int:
        """Free every window whose track the scene no longer holds; returns how many were freed."""
        alive = set(alive)
        gone = [k for k in self.tracks if k not in alive]
        for k in gone:
            del self.tracks[k]
        return len(gone)

    def __len__(self) -> int:
        return len(self.tracks)


__all__ = ["PersonResult", "TrackBook", "TrackState"]

"""Scene logic: calibrated pressure (kPa) → validated, filtered frame → contacts → people with stable ids.

Public API: ``SceneTracker``, ``SceneConfig``, ``SceneFrame``, ``PersonObservation``,
``OneEuroFilter``; the array steps (``median3x3``, ``detect_contacts``, ``group_blobs``,
``check_frame``) are pure functions for tests and tools. numpy and scipy only.
"""

from edge.scene.config import SceneConfig
from edge.scene.contacts import Blob, detect_contacts
from edge.scene.filters import FilterChain, MaskedFill, median3x3
from edge.scene.metrics import TrackingScore, score_tracking
from edge.scene.one_euro import OneEuroFilter
from edge.scene.people import group_blobs
from edge.scene.pipeline import PersonObservation, SceneFrame, SceneTracker
from edge.scene.validate import REASONS, check_frame

__all__ = ["REASONS", "Blob", "FilterChain", "MaskedFill", "OneEuroFilter", "PersonObservation", "SceneConfig", "SceneFrame",
           "SceneTracker", "TrackingScore", "check_frame", "detect_contacts", "group_blobs", "median3x3", "score_tracking"]

"""Stand-ins for driving FrameStages frame by frame: a scripted scene, a pass-through calibration,
footprints, people and frames (shared by the stage tests and the always-infer tests)."""

from types import SimpleNamespace

import numpy as np

from edge.frames import RawFrame
from edge.scene import PersonObservation, SceneFrame
from edge.scene.handover import PeopleHandover

H = W = 96


def foot(r0, c0, kpa, h=12, w=6):
    p = np.zeros((H, W), np.float32)
    p[r0:r0 + h, c0:c0 + w] = kpa
    return p


def person(track_id, mask, still):
    z = np.zeros(2)
    return PersonObservation(track_id, z, 600.0, z, 600.0, 0.01, z, mask, (slice(0, 1), slice(0, 1)), 1, still, 1.0)


class ScriptedScene:
    """Stands in for SceneTracker: per frame the scripted (people, held track ids[, empty]); empty
    defaults to "nobody confirmed". The frame it hands over is the calibrated one (nothing masked).
    It has nothing but ``update()``: FrameStages may use nothing else of the scene."""

    def __init__(self, script):
        self.script = list(script)

    def update(self, pressure_kpa, t_s, masks=None):
        people, held, *rest = self.script.pop(0)
        empty = rest[0] if rest else not people
        handover = PeopleHandover(pressure_kpa, tuple(people), frozenset(held))
        return SceneFrame(t_s, True, None, people, empty, False, 0.05, pressure_kpa, {}, handover)


class Calibrated:
    """Stands in for CalibratedFrames: the frame's 'counts' are already kPa."""

    def __init__(self):
        self.counters = {}

    def process(self, counts, t_s, temperature_c=None):
        return SimpleNamespace(pressure_kpa=counts.astype(np.float32), masked=np.zeros((H, W), bool), advice=[],
                               rejected=None)


def frame(k, pressure):
    return RawFrame(pressure, k, k, k / 14.0, 1_800_000_000.0 + k / 14.0)

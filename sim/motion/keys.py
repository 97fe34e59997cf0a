"""Keyframe timelines: poses as local Euler angles, contacts, anchors, heading.

A ``Timeline`` is a list of keys; each key moves from the previous key's pose to its
own pose over ``dur_s`` with minimum-jerk timing, while its contact schedule,
anchor, heel raise and activity label hold. ``sample(rate_hz)`` returns per-frame
arrays. Poses are (24,3) arrays of intrinsic x-y-z Euler angles in degrees in SMPL's
canonical axes (edge/body/poses.py); row 0 is the root's tilt relative to upright
(``rig.UPRIGHT``) and heading (yaw about the world z axis) is kept separately.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from sim.motion.rig import BACK, BUTT, LF, LH, RF, RH, J
from sim.motion.spans import min_jerk

__all__ = ["Timeline", "pose", "BASE"]


def _arr(**joints) -> np.ndarray:
    p = np.zeros((24, 3))
    for name, v in joints.items():
        p[0 if name == "root" else J[name]] = v
    return p


# Relaxed standing: arms hanging a little away from the hips, elbows soft.
BASE = _arr(
    left_shoulder=(0, 0, -78), right_shoulder=(0, 0, 78),
    left_elbow=(0, -12, 0), right_elbow=(0, 12, 0),
    left_hip=(0, 4, -3), right_hip=(0, -4, 3),
)


def pose(base: np.ndarray | None = None, **joints) -> np.ndarray:
    """A pose: ``base`` (default BASE) with the named joints replaced (degrees)."""
    p = (BASE if base is None else base).copy()
    for name, v in joints.items():
        p[0 if name == "root" else J[name]] = v
    return p


def both_feet():
    c = np.zeros(6, bool)
    c[[LF, RF]] = True
    return c


def contacts(*parts) -> np.ndarray:
    c = np.zeros(6, bool)
    c[list(parts)] = True
    return c


@dataclass
class Key:
    dur_s: float
    pose: np.ndarray
    contact: np.ndarray
    anchor: int
    heel: tuple[float, float] = (0.0, 0.0)
    turn_rad: float = 0.0  # heading change over this key
    label: int = 0


@dataclass
class Timeline:
    """Keys in order. pace: optional ``sim.motion.pace.Pacer``; ``add`` then lengthens a key
    that would move the centre of mass up or down faster than the pacer allows."""

    keys: list[Key] = field(default_factory=list)
    pace: object = None
    tempo_factor: float = 1.0  # how long the keys last against the subject's own durations (< 1: squeezed to fit)
    own_s: float = 0.0  # how long the activity lasts at the subject's own (paced) tempo, lead-in and lead-out included

    def add(self, dur_s, pose, contact, anchor, heel=(0.0, 0.0), turn_rad=0.0, label=0) -> "Timeline":
        pose, contact = np.asarray(pose, float), np.asarray(contact, bool)
        dur_s = float(dur_s)
        if self.pace is not None:
            prev = self.keys[-1].pose if self.keys else BASE
            dur_s = max(dur_s, self.pace.min_duration_s(prev, pose, contact, int(anchor)))
        self.keys.append(Key(dur_s, pose, contact, int(anchor), tuple(heel), float(turn_rad), int(label)))
        return self

    @property
    def duration_s(self) -> float:
        return float(sum(k.dur_s for k in self.keys))

    def scale_to(self, total_s: float, fixed: int = 0) -> None:
        """Stretch the keys after the first ``fixed`` ones so the whole lasts total_s."""
        head = sum(k.dur_s for k in self.keys[:fixed])
        tail = sum(k.dur_s for k in self.keys[fixed:])
        f = max(total_s - head, 1e-3) / max(tail, 1e-9)
        for k in self.keys[fixed:]:
            k.dur_s *= f

    def sample(self, n_frames: int, rate_hz: float, start_pose: np.ndarray, heading0: float, heel0=(0.0, 0.0)):
        """Per-frame euler (n,24,3), heading (n,), contact (n,6), anchor (n,), heel (n,2), label (n,)."""
        t = np.arange(n_frames) / rate_hz
        ends = np.cumsum([k.dur_s for k in self.keys])
        starts = ends - np.array([k.dur_s for k in self.keys])
        idx = np.minimum(np.searchsorted(ends, t, side="right"), len(self.keys) - 1)
        s = min_jerk((t - starts[idx]) / np.maximum(np.array([k.dur_s for k in self.keys])[idx], 1e-9))
        poses = np.stack([start_pose] + [k.pose for k in self.keys])  # key i goes from poses[i] to poses[i+1]
        euler = poses[idx] + (poses[idx + 1] - poses[idx]) * s[:, None, None]
        head_at = heading0 + np.concatenate([[0.0], np.cumsum([k.turn_rad for k in self.keys])])
        heading = head_at[idx] + (head_at[idx + 1] - head_at[idx]) * s
        heels = np.array([heel0] + [k.heel for k in self.keys], float)
        heel = heels[idx] + (heels[idx + 1] - heels[idx]) * s[:, None]
        contact = np.stack([k.contact for k in self.keys])[idx]
        anchor = np.array([k.anchor for k in self.keys])[idx]
        label = np.array([k.label for k in self.keys])[idx]
        return euler, heading, contact, anchor, heel, label


# Re-exported part indices for the activity definitions.
PARTS = dict(LF=LF, RF=RF, LH=LH, RH=RH, BUTT=BUTT, BACK=BACK)

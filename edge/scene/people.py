"""Grouping contacts into people.

A person is one or more contacts (feet, hands, knees). Distance alone cannot split two
people standing close (their inner feet can be nearer than one person's two feet in a
long step), so grouping combines distance with what the tracker already knows:

1. distance: contacts whose centres are within ``group_radius_m`` of each other
   (transitively: single linkage, ``scipy.sparse.csgraph.connected_components``) form a
   cluster;
2. prior: a contact that overlaps the sensels a track owned in the previous frame
   belongs to that track (majority of overlapping sensels; a stance foot does not move),
   provided it lies within ``attach_radius_m`` of the track's predicted centre (someone
   stepping onto a footprint another person just left must not inherit them);
3. a cluster whose contacts carry priors of two or more tracks is split between them:
   contacts without a prior go to the nearest of those tracks' predicted centres;
   a cluster with one track's priors is that track; one with none is new (key 0);
4. a track whose priors fall in several clusters keeps the cluster nearest its
   prediction; the others are new (people who were merged, walking apart).

New groups (key 0) are matched to the remaining tracks by the tracker (Hungarian on
distance with a gate), or start new tracks.
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import csr_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial.distance import cdist


def prior_keys(labels: np.ndarray, n_blobs: int, prev_keys: np.ndarray | None) -> np.ndarray:
    """(n_blobs,) int64: the track key most of each blob's sensels had in the previous frame (0 = none).

    labels: (H, W) blob labels 1..n_blobs; prev_keys: (H, W) track keys of the previous frame.
    """
    out = np.zeros(n_blobs, dtype=np.int64)
    if prev_keys is None or n_blobs == 0:
        return out
    both = (labels > 0) & (prev_keys > 0)
    if not both.any():
        return out
    span = int(prev_keys.max()) + 1
    pairs, counts = np.unique(labels[both].astype(np.int64) * span + prev_keys[both], return_counts=True)
    blob, key = pairs // span, pairs % span
    order = np.lexsort((-counts, blob))  # by blob, most sensels first
    blob, key = blob[order], key[order]
    first = np.ones(len(blob), dtype=bool)
    first[1:] = blob[1:] != blob[:-1]
    out[blob[first] - 1] = key[first]
    return out


def single_linkage(centres_m: np.ndarray, radius_m: float) -> np.ndarray:
    """(n, 2) points → (n,) cluster index; points within radius_m (transitively) share one."""
    if len(centres_m) <= 1:
        return np.zeros(len(centres_m), dtype=np.int64)
    adjacent = cdist(centres_m, centres_m) <= radius_m
    _, comp = connected_components(csr_matrix(adjacent), directed=False)
    return comp


def group_blobs(
    centres_m: np.ndarray,
    priors: np.ndarray,
    predicted_m: dict[int, np.ndarray],
    group_radius_m: float,
    attach_radius_m: float,
) -> list[tuple[np.ndarray, int]]:
    """Blob centres (n, 2), prior keys (n,) and track predictions {key: (2,)} → [(blob indices, key or 0)]."""
    n = len(centres_m)
    if n == 0:
        return []
    prior = np.zeros(n, dtype=np.int64)
    for i in range(n):
        k = int(priors[i])
        if k in predicted_m and np.linalg.norm(centres_m[i] - predicted_m[k]) <= attach_radius_m:
            prior[i] = k
    cluster = single_linkage(centres_m, group_radius_m)
    groups: list[tuple[np.ndarray, int]] = []
    claims: dict[int, list[int]] = {}  # key -> indices into groups
    for c in np.unique(cluster):
        idx = np.nonzero(cluster == c)[0]
        keys = [int(k) for k in np.unique(prior[idx]) if k > 0]
        if len(keys) <= 1:
            parts = [(idx, keys[0] if keys else 0)]
        else:
            pred = np.array([predicted_m[k] for k in keys])
            owner = np.array(keys)[cdist(centres_m[idx], pred).argmin(axis=1)]
            owner = np.where(prior[idx] > 0, prior[idx], owner)
            parts = [(idx[owner == k], k) for k in keys]
        for part in parts:
            if part[1]:
                claims.setdefault(part[1], []).append(len(groups))
            groups.append(part)
    for k, gi in claims.items():
        if len(gi) > 1:  # one track's contacts in several clusters: the nearest keeps it
            dist = [np.linalg.norm(centres_m[groups[g][0]].mean(axis=0) - predicted_m[k]) for g in gi]
            keep = gi[int(np.argmin(dist))]
            for g in gi:
                if g != keep:
                    groups[g] = (groups[g][0], 0)
    return groups

"""Grouping contacts into people: what one body can reach, and what it weighs.

A person is one or more contacts (feet, hands, knees, buttocks, a whole lying body). Distance
alone cannot tell one person's contacts from two people's: a lunge puts one person's feet
0.7 m apart and a push-up their hands and feet 1.3 m apart, while two people standing side by
side have feet 0.3 m apart. So grouping uses what each track already is:

1. prior: a contact that overlaps the sensels a track owned in the previous frame stays with
   that track (majority of overlapping sensels: a stance foot does not move), provided it lies
   within the track's reach;
2. reach: each other contact joins the track that reaches it best, the least distance to the
   track's predicted centre in units of the track's reach (several contacts may join one track:
   two hands put down at once), among the tracks that kept a contact (one whose contacts all
   lifted is matched again as a whole by the tracker). A track whose kept contacts carry less
   than ANCHOR_FRACTION of its weight (its weight on the way elsewhere: a slow sit-down onto the
   buttocks, on the board's path the feet read light long before they land) takes a contact
   only within its weight and as a whole cluster of new contacts: weight that moves adds none,
   and a whole newcomer, or someone reappearing beyond its reach, is not taken.
   A track's reach is ``reach_m`` beyond its extent, the farthest of its contacts
   from its centre (slowly forgotten), so a lying body reaches farther than a standing one;
3. splits need evidence over ``split_s``: a track's contacts that stay in parts more than
   ``split_distance_m`` apart (two people who were one track walking apart), or a track
   carrying more than its own weight by HEAVY_FRACTION of it with a part that carries the
   excess while the rest still carries KEEP_FRACTION of the weight (someone stepping in beside
   it: a foot that lifts and lands, or a back put down, moves weight; it adds none);
4. contacts no track reaches are new: clustered so that all of a cluster's contacts lie within
   ``group_radius_m`` of each other (two people side by side are not chained into one), each
   cluster is a group with key 0, which the tracker matches to coasting tracks (Hungarian on
   distance, ``linear_sum_assignment``) or starts as a new track;
5. everyone moved at once (two or more tracks, the contacts that stayed carry less than
   MOVED_KEEP_FRACTION of the previous frame's force, new ones carry most of it: ``sim://``
   starting a new scene): no contact keeps its prior and no track reaches; every contact is
   regrouped as new (4.). Otherwise the fading contacts left behind anchor the old tracks, which
   then reach out to the new contacts of other people and carry two people or half of one.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.cluster.hierarchy import fcluster, linkage
from scipy.spatial.distance import cdist, pdist


@dataclass(frozen=True, slots=True)
class Body:
    """What grouping needs to know of one track: predicted centre (2,) m, reach m, weight N
    (None until known), and for how many frames each kind of split has been seen."""

    centre_m: np.ndarray
    reach_m: float
    weight_n: float | None = None
    far_frames: int = 0
    heavy_frames: int = 0
    last_force_n: float | None = None  # what its contacts carried in the previous frame (None: not seen then)


# Someone stepping in adds at least this fraction of the body's own weight: a person's force on the
# board's path varies by ±30 % with posture (contact area, saturation), a newcomer adds a whole person.
HEAVY_FRACTION = 0.35
# ... and the body's own contacts still carry this fraction of its weight.
KEEP_FRACTION = 0.8
# ... and of what they carried when the excess began: a newcomer takes no weight from the body's other
# contacts, a sit-up's back put down takes 20-35 % from the buttocks.
REST_KEEP_FRACTION = 0.85
# A body whose kept contacts carry less than this fraction of its weight reaches out only within its weight
# (see _reach): a foot lands while the other carries the body, but in a slow sit-down the feet read light
# before the buttocks land. The simulator moving everyone at once is caught by moved_at_once.
ANCHOR_FRACTION = 0.3
# Everyone moved at once when the contacts that stayed carry less than this fraction of the previous frame's.
MOVED_KEEP_FRACTION = 0.5


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
    counts = np.bincount(labels[both].astype(np.int64) * span + prev_keys[both], minlength=(n_blobs + 1) * span)
    counts = counts.reshape(n_blobs + 1, span)[1:]  # (blob, key) sensel counts
    seen = counts.any(axis=1)
    out[seen] = counts[seen].argmax(axis=1)  # most sensels; a tie goes to the lower key
    return out


def within_span(centres_m: np.ndarray, span_m: float) -> np.ndarray:
    """(n, 2) points → (n,) cluster index: complete linkage, every two points of a cluster within span_m.

    Unlike single linkage this does not chain two people standing side by side (each one's feet
    0.2 m apart, the nearest feet of the two 0.3 m apart) into one.
    """
    if len(centres_m) <= 1:
        return np.zeros(len(centres_m), dtype=np.int64)
    return fcluster(linkage(pdist(centres_m), method="complete"), t=span_m, criterion="distance") - 1


def single_linkage(centres_m: np.ndarray, radius_m: float) -> np.ndarray:
    """(n, 2) points → (n,) cluster index; points within radius_m (transitively) share one.

    A handful of contacts: the reachability matrix is squared until it stops growing (log2 n
    products of an n×n boolean matrix) instead of building a sparse graph.
    """
    n = len(centres_m)
    if n <= 1:
        return np.zeros(n, dtype=np.int64)
    reach = cdist(centres_m, centres_m) <= radius_m
    while True:
        wider = (reach.astype(np.uint8) @ reach.astype(np.uint8)) > 0
        if (wider == reach).all():
            break
        reach = wider
    return np.unique(reach.argmax(axis=1), return_inverse=True)[1].astype(np.int64)


@dataclass(frozen=True, slots=True)
class Grouping:
    """groups: [(blob indices, track key or 0 for new)]; far, heavy: keys whose split evidence grew this frame;
    excess: keys whose contacts carry more than the body's weight by the heavy threshold (none split off this frame)."""

    groups: list[tuple[np.ndarray, int]]
    far: frozenset[int]
    heavy: frozenset[int]
    excess: frozenset[int] = frozenset()


def group_blobs(
    centres_m: np.ndarray,
    forces_n: np.ndarray,
    priors: np.ndarray,
    bodies: dict[int, Body],
    group_radius_m: float,
    split_distance_m: float,
    min_person_force_n: float,
    split_frames: int,
    ages_s: np.ndarray | None = None,
    newcomer_s: float = 0.5,
    frame_s: float = 1 / 14,
    stayed: float | None = None,
    before_n: np.ndarray | None = None,
) -> Grouping:
    """Blob centres (n, 2) m, forces (n,) N, prior keys (n,) and the tracks' bodies → groups of blobs.

    ages_s: (n,) how long each blob has been with its prior track (0 for new contacts); only
    contacts that joined a track at most newcomer_s before it began to carry more than its weight
    can be split off as someone stepping in (frame_s: the frame interval, to count back).
    stayed: the fraction of the previous frame's contact pressure still where it was (see
    :func:`moved_at_once`; None: unknown).
    before_n: (n,) what each blob's sensels carried when its track began to carry more than its weight
    (see :func:`_split_heavy`; None: not known, no such check).
    """
    n = len(centres_m)
    if n == 0:
        return Grouping([], frozenset(), frozenset())
    owner = np.zeros(n, dtype=np.int64)
    if moved_at_once(forces_n, priors, bodies, stayed):
        priors = owner  # everyone's contacts are new: regrouped afresh, each group matched by the tracker
    known = [i for i in range(n) if int(priors[i]) in bodies]
    if known:  # a contact stays with its track while the body still reaches it
        body = [bodies[int(priors[i])] for i in known]
        d = np.linalg.norm(centres_m[known] - np.array([b.centre_m for b in body]), axis=1)
        kept = np.array(known)[d <= np.array([b.reach_m for b in body])]
        owner[kept] = priors[kept]
    _reach(centres_m, forces_n, owner, bodies, group_radius_m)  # a track that lost its footing is found again by the tracker, as a whole
    ages = np.zeros(n) if ages_s is None else np.where(owner == priors, ages_s, 0.0)
    groups: list[tuple[np.ndarray, int]] = []
    far, heavy, excess = set(), set(), set()
    grown = None if before_n is None else forces_n - before_n
    for k in np.unique(owner[owner > 0]):
        k = int(k)
        idx = np.flatnonzero(owner == k)
        parts = _split_far(centres_m[idx], forces_n[idx], split_distance_m)
        if parts is not None:
            far.add(k)
            if bodies[k].far_frames + 1 >= split_frames:
                keep, rest = parts
                groups += [(idx[keep], k), (idx[rest], 0)]
                continue
        recent = ages[idx] <= newcomer_s + bodies[k].heavy_frames * frame_s
        if _excess_n(forces_n[idx], bodies[k], min_person_force_n) is not None:
            excess.add(k)
        part = _split_heavy(centres_m[idx], forces_n[idx], recent, bodies[k], group_radius_m, min_person_force_n,
                            None if grown is None else grown[idx])
        if part is not None:
            heavy.add(k)
            if bodies[k].heavy_frames + 1 >= split_frames:
                groups += [(idx[~part], k), (idx[part], 0)]
                excess.discard(k)
                continue
        groups.append((idx, k))
    new = np.flatnonzero(owner == 0)
    if len(new):
        cluster = _new_people(centres_m[new], forces_n[new], group_radius_m, 0.25 * min_person_force_n)
        groups += [(new[cluster == c], 0) for c in np.unique(cluster)]
    return Grouping(groups, frozenset(far), frozenset(heavy), frozenset(excess))


def moved_at_once(forces_n: np.ndarray, priors: np.ndarray, bodies: dict[int, Body], stayed: float | None = None) -> bool:
    """True when two or more tracks had contacts in the previous frame, the contacts that stayed with their
    tracks carry less than MOVED_KEEP_FRACTION of what all of them carried then (or less than that
    fraction of the previous frame's contact pressure is ``stayed`` where it was: new contacts landing
    across old footprints keep those footprints' keys), and new contacts carry most of the force:
    everyone moved at once (sim:// starting a new scene). Contacts left behind fading
    out would otherwise keep their tracks anchored and let them reach the new contacts of other people.
    A single body whose contacts all move (a push-up's hands and feet resettling) stays with its track."""
    seen = [b.last_force_n for b in bodies.values() if b.last_force_n is not None]
    if len(seen) < 2 or sum(seen) <= 0:  # one body's contacts moving at once are still that body's
        return False
    before = sum(seen)
    kept = float(forces_n[np.array([int(k) in bodies for k in priors], dtype=bool)].sum())
    gone = kept < MOVED_KEEP_FRACTION * before or (stayed is not None and stayed < MOVED_KEEP_FRACTION)
    return gone and float(forces_n.sum()) - kept >= kept


def _new_people(centres_m: np.ndarray, forces_n: np.ndarray, span_m: float, faint_n: float) -> np.ndarray:
    """(n,) cluster index of contacts no track reaches: the contacts carrying faint_n or more clustered
    within span_m; fainter ones (a contact fading out, a toe) join the nearest cluster, or one of their own."""
    strong = forces_n >= faint_n
    if strong.all() or not strong.any():
        return within_span(centres_m, span_m)
    cluster = np.empty(len(centres_m), dtype=np.int64)
    cluster[strong] = within_span(centres_m[strong], span_m)
    d = cdist(centres_m[~strong], centres_m[strong])
    nearest = d.argmin(axis=1)
    own = d[np.arange(len(nearest)), nearest] > span_m
    faint = cluster[strong][nearest]
    faint[own] = cluster[strong].max() + 1 + np.arange(int(own.sum()))
    cluster[~strong] = faint
    return cluster


def _reach(centres_m: np.ndarray, forces_n: np.ndarray, owner: np.ndarray, bodies: dict[int, Body],
           group_radius_m: float) -> None:
    """Give unowned blobs to the bodies that reach them best (in place on ``owner``): the least distance to
    a body's predicted centre in units of its reach, within reach. Only bodies that kept a contact take part.

    1. A body whose kept contacts carry less than ANCHOR_FRACTION of its weight (its weight on the way to
       a new contact: sitting down onto the buttocks, landing after a hop) takes new contacts as a whole
       cluster (all within group_radius_m of each other), when it is the best reacher of every one of
       them and all it then carries stays within (1 + HEAVY_FRACTION) of its weight: weight that moves
       adds none. A cluster it reaches only in part (someone reappearing beyond it) stays new.
    2. The rest join, one by one, the body that reaches each best among the others (several blobs may
       join one body: two hands put down at once).
    """
    free = np.flatnonzero(owner == 0)
    keys = np.unique(owner[owner > 0])
    if len(free) == 0 or len(keys) == 0:
        return
    pred = np.array([bodies[int(k)].centre_m for k in keys])
    reach = np.array([bodies[int(k)].reach_m for k in keys])
    d = cdist(centres_m[free], pred) / reach  # (free, bodies)
    best = d.argmin(axis=1)
    carried = np.array([float(forces_n[owner == k].sum()) for k in keys])
    weight = np.array([np.inf if bodies[int(k)].weight_n is None else bodies[int(k)].weight_n for k in keys])
    light = carried < ANCHOR_FRACTION * weight  # never for an unknown weight
    taken = np.zeros(len(free), dtype=bool)
    if light.any():
        cluster = within_span(centres_m[free], group_radius_m)
        for c in np.unique(cluster):
            members = cluster == c
            b = int(best[members][0])
            force = float(forces_n[free[members]].sum())
            if light[b] and (best[members] == b).all() and (d[members, b] <= 1.0).all() \
                    and carried[b] + force <= (1.0 + HEAVY_FRACTION) * weight[b]:
                owner[free[members]] = keys[b]
                carried[b] += force
                taken |= members
    d[:, light] = np.inf
    best = d.argmin(axis=1)
    ok = ~taken & (d[np.arange(len(free)), best] <= 1.0)
    owner[free[ok]] = keys[best[ok]]


def _split_far(centres_m: np.ndarray, forces_n: np.ndarray, split_distance_m: float) -> tuple[np.ndarray, np.ndarray] | None:
    """(keep, rest) bool masks when the contacts fall in parts more than split_distance_m apart (the heaviest part keeps)."""
    if len(centres_m) < 2 or _span_m(centres_m) <= split_distance_m:  # the usual case, at once
        return None
    comp = single_linkage(centres_m, split_distance_m)
    if comp.max() == 0:
        return None
    heaviest = int(np.argmax(np.bincount(comp, weights=forces_n)))
    return comp == heaviest, comp != heaviest


def _span_m(centres_m: np.ndarray) -> float:
    """The largest distance (m) between two of (n ≥ 2, 2) points; scipy's pdist costs more than the sum for a handful."""
    d = centres_m[:, None, :] - centres_m[None, :, :]
    return float(np.sqrt((d * d).sum(axis=-1)).max())


def _excess_n(forces_n: np.ndarray, body: Body, min_person_force_n: float) -> float | None:
    """What the contacts carry beyond the body's weight when that reaches HEAVY_FRACTION of it (and
    min_person_force_n), else None (also while the weight is unknown)."""
    if body.weight_n is None:
        return None
    excess = float(forces_n.sum()) - body.weight_n
    return excess if excess >= max(min_person_force_n, HEAVY_FRACTION * body.weight_n) else None


def _split_heavy(centres_m: np.ndarray, forces_n: np.ndarray, recent: np.ndarray, body: Body, group_radius_m: float,
                 min_person_force_n: float, grown_n: np.ndarray | None = None) -> np.ndarray | None:
    """Mask of the contacts that carry a track's excess weight (someone stepping in beside it), or None.

    The excess must reach HEAVY_FRACTION of the body's weight (and min_person_force_n). Candidates are
    the clusters of contacts that joined the track lately (``recent``, all within group_radius_m of
    each other) and, failing those, single contacts (a foot put where the other person's had just
    been inherits that footprint's track); the one whose force is nearest the excess is the newcomer,
    provided it carries at least half the excess and the rest still carries KEEP_FRACTION of the
    body's weight: someone lying back moves weight from buttocks to shoulders (and on the board's
    path reads heavier, spread over more sensels), someone stepping in takes none from the body.
    A recent cluster that carries the excess but took weight from the body is that posture change:
    then no contact is split off (on the board's path a sit-up's back reads up to twice the weight,
    and the fallback gave the buttocks away as a newcomer). A single contact must also have gained half
    the excess since the excess began (``grown_n``, (n,) N): a newcomer's weight lands where they
    stand; a buttocks that carried the body all along did not.
    """
    excess = _excess_n(forces_n, body, min_person_force_n)
    if excess is None or len(centres_m) < 2:
        return None
    total = float(forces_n.sum())
    weight_n = float(body.weight_n or 0.0)  # known: _excess_n returns None while it is not

    def carries(f: float) -> bool:  # carries the excess
        return f >= max(min_person_force_n, 0.5 * excess)

    def keeps(f: float) -> bool:  # the rest still carries the body: f took no weight from it (a back put down does)
        return total - f >= max(min_person_force_n, KEEP_FRACTION * weight_n)

    idx = np.flatnonzero(recent)
    parts = []
    if len(idx):
        comp = within_span(centres_m[idx], group_radius_m)
        parts = [idx[comp == c] for c in np.unique(comp)]
        if any(carries(f) and not keeps(f) for f in (float(forces_n[p].sum()) for p in parts)):
            return None  # the body's own weight moved onto a new contact and reads heavier there (lying back)
        parts = [p for p in parts if carries(float(forces_n[p].sum())) and keeps(float(forces_n[p].sum()))]
    if not parts:
        grew = np.ones(len(centres_m), bool) if grown_n is None else grown_n >= 0.5 * excess
        rest_kept = np.ones(len(centres_m), bool)
        if grown_n is not None:  # the other contacts still carry what they carried when the excess began
            before = forces_n - grown_n
            rest_kept = total - forces_n >= REST_KEEP_FRACTION * (float(before.sum()) - before)
        parts = [np.array([i]) for i in range(len(centres_m))
                 if grew[i] and rest_kept[i] and carries(float(forces_n[i])) and keeps(float(forces_n[i]))]
    if not parts:
        return None
    best = min(parts, key=lambda p: abs(float(forces_n[p].sum()) - excess))
    part = np.zeros(len(centres_m), dtype=bool)
    part[best] = True
    return part

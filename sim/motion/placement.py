"""Scenes: 1–3 people on one carpet, each person's track turned and shifted so that nobody
leaves the carpet and nobody comes close to another (``scene``).

The search works on a raster of the carpet (``_CELL_M`` cells): a person's occupancy is
every cell their mesh covers in any frame (or between two frames); a shift that keeps a
person clear of those already placed is one where the correlation of their occupancy with
the others' (dilated by the gap) is zero, found for every shift at once by FFT.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np
from scipy import fft as sfft
from scipy.ndimage import binary_dilation

from edge.body import BodyModel
from sim.motion.generate import DEFAULT_RATE_HZ, Scene, Track, body_model, person_track

_CELL_M = 0.03  # raster cell of the placement search
_YAWS = 12  # turns tried per placement (in random order from a random start)


def _footprints(track: Track, model: BodyModel, stride: int = 1) -> np.ndarray:
    """(T,P,2) each frame's mesh vertices (every ``stride``-th) in x, y."""
    out = np.empty((len(track), (model.num_vertices + stride - 1) // stride, 2))
    for s in range(0, len(track), 2048):
        v = model.forward(track.pose_aa[s:s + 2048], track.betas, track.transl_m[s:s + 2048], vertices=True)["vertices"]
        out[s:s + 2048] = v[:, ::stride, :2]
    return out


def _boxes(points: np.ndarray, yaw: float, offset) -> np.ndarray:
    c, s = np.cos(yaw), np.sin(yaw)
    x = c * points[..., 0] - s * points[..., 1] + offset[0]
    y = s * points[..., 0] + c * points[..., 1] + offset[1]
    return np.stack([x.min(1), y.min(1), x.max(1), y.max(1)], 1)  # (T,4)


def box_gaps(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Per-frame separation of two boxes (T,4) [xmin,ymin,xmax,ymax]; ≤ 0 when they overlap."""
    sx = np.maximum(b[:, 0] - a[:, 2], a[:, 0] - b[:, 2])
    sy = np.maximum(b[:, 1] - a[:, 3], a[:, 1] - b[:, 3])
    return np.maximum(sx, sy)


def _raster(cells: np.ndarray, shape) -> np.ndarray:
    """(N,P,2) integer cells → (N, *shape) occupancy."""
    occ = np.zeros((len(cells),) + tuple(shape), bool)
    ti = np.broadcast_to(np.arange(len(cells))[:, None], cells.shape[:2])
    occ[ti, cells[..., 0], cells[..., 1]] = True
    return occ


def _pair_union(occ: np.ndarray) -> np.ndarray:
    """Rasters of frames t and t+1 merged (T−1 of them), so they also cover the motion between frames."""
    return occ if len(occ) == 1 else occ[:-1] | occ[1:]


def _turned(pts: np.ndarray, yaw: float) -> np.ndarray:
    """(T,P,2) points turned by yaw about the origin."""
    c, s = np.cos(yaw), np.sin(yaw)
    return np.stack([c * pts[..., 0] - s * pts[..., 1], s * pts[..., 0] + c * pts[..., 1]], -1)


@dataclass(frozen=True)
class _Carpet:
    """The raster of the search: size_m (2,) of the carpet, grid (cells per axis), margin_m
    kept inside its edges and the disk (1,D,D) that dilates an occupancy by the gap."""

    size_m: np.ndarray
    grid: tuple[int, ...]
    margin_m: float
    disk: np.ndarray

    @classmethod
    def of(cls, size_m: np.ndarray, min_gap_m: float, margin_m: float) -> "_Carpet":
        grid = tuple(int(g) for g in np.ceil(size_m / _CELL_M))
        rad = int(np.ceil(min_gap_m / _CELL_M + 1.5))  # cells: any two vertices in cells this far apart are > min_gap_m apart
        yy, xx = np.mgrid[-rad:rad + 1, -rad:rad + 1]
        return cls(size_m, grid, margin_m, (xx**2 + yy**2 <= rad * rad)[None])

    def occupancy(self, pts_world: np.ndarray) -> np.ndarray:
        """(T−1, *grid) cells covered by points (T,P,2) in carpet coordinates."""
        cells = np.clip(np.floor(pts_world / _CELL_M).astype(np.int64), 0, np.array(self.grid) - 1)
        return _pair_union(_raster(cells, self.grid))

    def blocked(self, occ: np.ndarray | None) -> np.ndarray | None:
        """FFT of the occupancy of those placed, dilated by the gap (None: nobody yet)."""
        return None if occ is None else sfft.rfft2(binary_dilation(occ, self.disk).astype(np.float32), workers=1)


def _free_shifts(carpet: _Carpet, p: np.ndarray,
                 blocked: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    """For turned points p (T,P,2): which shifts (on the raster, from the carpet's corner
    plus margin) keep them on the carpet and clear of ``blocked``: a bool grid (Nx,Ny), the
    shifts on the carpet per axis (2,) and the lowest point of p (2,); None where p does not
    fit the carpet at all."""
    h = _CELL_M
    lo, hi = p.reshape(-1, 2).min(0), p.reshape(-1, 2).max(0)
    n_off = np.floor((carpet.size_m - 2 * carpet.margin_m - (hi - lo)) / h).astype(int) + 1  # shifts per axis
    if np.any(n_off < 1):
        return None
    if blocked is None:
        return np.ones(n_off, bool), n_off, lo
    cells = np.floor((p - lo + carpet.margin_m) / h).astype(np.int64)  # cells at shift 0
    b = _pair_union(_raster(cells, carpet.grid)).astype(np.float32)
    corr = sfft.irfft2(np.sum(blocked * np.conj(sfft.rfft2(b, workers=1)), axis=0), s=carpet.grid, workers=1)
    return corr[:n_off[0], :n_off[1]] < 0.5, n_off, lo


def _place(carpet: _Carpet, pts: np.ndarray, blocked: np.ndarray | None, corner, rng: np.random.Generator):
    """A (yaw, offset (2,)) that keeps this person (points (T,P,2) at the origin) on the carpet
    and clear of ``blocked``, or None. corner: None alone on the carpet (any shift), else
    (x, y) flags of the corner to pack toward, which leaves room for the next."""
    base = rng.uniform(0, 2 * np.pi)
    for yaw in (base + np.arange(_YAWS) * (2 * np.pi / _YAWS))[rng.permutation(_YAWS)]:
        fit = _free_shifts(carpet, _turned(pts, yaw), blocked)
        if fit is None:
            continue
        free, n_off, lo = fit
        options = np.flatnonzero(free)
        if len(options) == 0:
            continue
        if corner is None:
            pick = options[rng.integers(len(options))]
        else:
            ox, oy = np.unravel_index(options, free.shape)
            far_x, far_y = n_off[0] - 1 - ox, n_off[1] - 1 - oy
            dist = np.hypot(np.where(corner[0], far_x, ox), np.where(corner[1], far_y, oy))
            pick = options[np.argmin(dist + rng.uniform(0, 2.0, len(dist)))]
        ox, oy = np.unravel_index(pick, free.shape)
        return float(yaw), carpet.margin_m - lo + np.array([ox, oy]) * _CELL_M
    return None


@dataclass(frozen=True)
class _People:
    """Who is in the scene and what they do: one track per subject, on demand."""

    subjects: list
    activities: list
    per_person: bool
    seconds_per_activity: float
    rate_hz: float
    model: BodyModel
    rng: np.random.Generator
    extend: bool = False
    total_s: float | None = None  # once set, everybody's track lasts exactly this long

    def make(self, k: int, shuffle: bool) -> tuple[Track, np.ndarray]:
        """Person k's track at the origin (shuffle: their activities in a random order) and
        its footprints (T,P,2) (every other vertex)."""
        names = list(self.activities[k] if self.per_person else self.activities)
        order = list(self.rng.permutation(names)) if shuffle else names
        alone = len(self.subjects) == 1
        track = person_track(self.subjects[k], order, self.seconds_per_activity, self.rate_hz, self.rng, self.model,
                             heading_rad=0.0, walk_radius_m=WALK_RADIUS_M if alone else 0.45, walk_line=not alone,
                             extend=self.extend, total_s=self.total_s)
        return track, _footprints(track, self.model, stride=2)


# A walker alone goes between spots this far from the start (a 1.83 m carpet: the pelvis then
# spans ~1.0 m, the feet reach ~0.3 m beyond it); with others, back and forth on a line.
WALK_RADIUS_M = 0.45


def scene(subjects, activities, seconds_per_activity: float = 10.0, rate_hz: float = DEFAULT_RATE_HZ,
          carpet_size_m=(1.83, 1.83), rng: np.random.Generator | int | None = None, min_gap_m: float = 0.15,
          margin_m: float = 0.02, model: BodyModel | str | None = None, tries: int = 40, extend: bool = False) -> Scene:
    """1–3 people on one carpet who never come closer than min_gap_m to each other (top-down:
    the horizontal distance between any vertex of one and any vertex of another, every frame
    and between consecutive frames) and never leave the carpet (every vertex margin_m inside
    its edges, every frame).

    activities: one sequence of names for everybody (each person after the first does them
    in an order of their own), or one sequence per person. Each person's track is generated
    at the origin and placed (the one with the largest footprint first, the others packed
    toward corners) by a turn and a shift: turns are tried in random order and the
    shift is drawn among all that fit (an exact search on a 3 cm raster of every frame, by
    FFT correlation). When a person after the first fits nowhere, they get a new order of
    their activities (another timing may fit beside the others; up to 3 times), then the
    placement restarts with new turns and corners. Raises ValueError after ``tries``
    placement attempts in all.

    extend: each activity gets the time it needs at the person's own tempo (``person_track``'s
    extend); the scene then lasts as long as its longest person, and the others' activities
    are given that time too (repetitions and pauses fill it).
    """
    rng = rng if isinstance(rng, np.random.Generator) else np.random.default_rng(rng)
    subjects = list(subjects)
    if not 1 <= len(subjects) <= 3:
        raise ValueError(f"a scene holds 1 to 3 people, got {len(subjects)}")
    acts_list = list(activities)
    per_person = bool(acts_list) and not isinstance(acts_list[0], str)
    if per_person and len(acts_list) != len(subjects):
        raise ValueError("one activity sequence per subject, or one sequence for all")
    size = np.asarray(carpet_size_m, float)
    carpet = _Carpet.of(size, min_gap_m, margin_m)
    people = _People(subjects, acts_list, per_person, seconds_per_activity, rate_hz, body_model(model), rng, extend)
    made = [people.make(k, shuffle=(k > 0 and not per_person)) for k in range(len(subjects))]
    longest = max(len(t) for t, _ in made)
    if extend and min(len(t) for t, _ in made) < longest:
        people = replace(people, total_s=longest / rate_hz)
        made = [m if len(m[0]) == longest else people.make(k, shuffle=(k > 0 and not per_person)) for k, m in enumerate(made)]
    placed = _arrange(carpet, people, made, rng, max(1, tries))
    if len(placed) < len(subjects):
        raise ValueError(
            f"could not place {len(subjects)} people on a {size[0]:.2f}×{size[1]:.2f} m carpet "
            f"with {min_gap_m} m between people; use fewer people, a larger carpet or a smaller min_gap_m")
    return Scene(placed, float(rate_hz), (float(size[0]), float(size[1])))


def _arrange(carpet: _Carpet, people: _People, made: list[tuple[Track, np.ndarray]], rng: np.random.Generator,
             budget: int) -> list[Track]:
    """Everybody placed (tracks in subject order), or fewer when the budget of placement
    attempts ran out. ``made`` (a track and footprints per person) is updated where a person
    got a new order of activities."""
    placed_by: dict[int, Track] = {}
    while budget > 0 and len(placed_by) < len(made):
        placed_by, occ = {}, None
        order = np.argsort([-_footprint_cells(p) for _, p in made], kind="stable")  # the largest first
        corners = rng.permutation([(0, 0), (1, 1), (0, 1), (1, 0)]) if len(made) > 1 else [None]
        for i, k in enumerate(order):
            blocked = carpet.blocked(occ)
            got = None
            for _ in range(3):
                budget -= 1
                got = _place(carpet, made[k][1], blocked, corners[i % len(corners)], rng)
                if got is not None or i == 0 or budget <= 0:
                    break
                made[k] = people.make(k, shuffle=True)  # another order/timing of the activities may fit beside the others
            if got is None:
                break
            yaw, offset = got
            track, pts = made[k]
            placed_by[int(k)] = track.rotated(yaw, offset)
            if len(placed_by) < len(made):
                o = carpet.occupancy(_turned(pts, yaw) + offset)
                occ = o if occ is None else occ | o
    return [placed_by[k] for k in sorted(placed_by)]


def _footprint_cells(pts: np.ndarray) -> int:
    """How many raster cells the points (T,P,2) cover over all frames."""
    return len(np.unique(np.floor(pts.reshape(-1, 2) / _CELL_M).astype(np.int64), axis=0))

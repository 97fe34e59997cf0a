"""The virtual carpet acting out a calibration session (for ``--sim`` and the tests).

A scripted installer on a :class:`sim.sensor.CarpetSensor`: an empty capture, a
serpentine coverage walk, a 60×60 cm rigid board moved over the carpet while the
person on it shifts their weight, and known-weight stances at a few spots. Pressure
generators are pure functions of physical quantities (metres, kg); sensel values are
area averages (3×3 supersampling), so edges of feet and board hold partial loads.

Hard cases are injected into the empty capture with ``intruder``: ``"standing"``
(someone still through the whole capture), ``"walking"`` (someone crossing),
``"present80"`` (someone on the carpet for 80 % of it).
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from calibration.capture import Capture

G_M_S2 = 9.81
FOOT_LEN_M, FOOT_WID_M = 0.25, 0.09
BOARD_M = 0.60


def _grid_xy(shape: tuple[int, int], pitch_m: float, ss: int = 3) -> tuple[np.ndarray, np.ndarray]:
    """Supersampled sample positions (ss·H, ss·W): x along columns, y along rows, metres."""
    h, w = shape
    off = (np.arange(ss) + 0.5) / ss
    ys = (np.arange(h)[:, None] + off[None, :]).ravel() * pitch_m
    xs = (np.arange(w)[:, None] + off[None, :]).ravel() * pitch_m
    return np.meshgrid(xs, ys)


def _down(a: np.ndarray, ss: int) -> np.ndarray:
    h, w = a.shape[0] // ss, a.shape[1] // ss
    return a.reshape(h, ss, w, ss).mean(axis=(1, 3))


def foot_pressure(shape: tuple[int, int], pitch_m: float, centre_xy: tuple[float, float], heading_rad: float,
                  force_n: float, ss: int = 3) -> np.ndarray:
    """(H, W) kPa of one foot carrying ``force_n``: an ellipse 25 × 9 cm with heel and
    forefoot pads (peaks ≈ 1.6× the mean), Σ P·A = force (computed in a window around it)."""
    h, w = shape
    out = np.zeros(shape)
    reach = FOOT_LEN_M / 2 + pitch_m
    c0, c1 = max(0, int((centre_xy[0] - reach) / pitch_m)), min(w, int((centre_xy[0] + reach) / pitch_m) + 1)
    r0, r1 = max(0, int((centre_xy[1] - reach) / pitch_m)), min(h, int((centre_xy[1] + reach) / pitch_m) + 1)
    if r1 <= r0 or c1 <= c0 or force_n <= 0:
        return out
    X, Y = _grid_xy((r1 - r0, c1 - c0), pitch_m, ss)
    X, Y = X + c0 * pitch_m, Y + r0 * pitch_m
    fwd = np.array([np.cos(heading_rad), np.sin(heading_rad)])
    dx, dy = X - centre_xy[0], Y - centre_xy[1]
    u = (dx * fwd[0] + dy * fwd[1]) / (FOOT_LEN_M / 2)
    v = (-dx * fwd[1] + dy * fwd[0]) / (FOOT_WID_M / 2)
    inside = u**2 + v**2 <= 1.0
    profile = 0.5 + np.exp(-((u + 0.6) / 0.3) ** 2) + 0.9 * np.exp(-((u - 0.5) / 0.35) ** 2)
    p = _down(np.where(inside, profile, 0.0), ss)
    total = p.sum() * pitch_m**2
    if total > 0:
        out[r0:r1, c0:c1] = p * (force_n / total / 1e3)
    return out


def stance_pressure(shape, pitch_m, centre_xy, heading_rad, mass_kg, left_share=0.5) -> np.ndarray:
    """Two feet 18 cm apart (centre to centre) carrying the person's weight."""
    side = np.array([-np.sin(heading_rad), np.cos(heading_rad)]) * 0.09
    w = mass_kg * G_M_S2
    c = np.asarray(centre_xy, float)
    return (foot_pressure(shape, pitch_m, tuple(c + side), heading_rad, w * left_share)
            + foot_pressure(shape, pitch_m, tuple(c - side), heading_rad, w * (1 - left_share)))


def _blob(X, Y, centre, heading, half_len, half_wid, peaks=()):
    """A body-part ellipse (relative profile), with optional Gaussian peaks (u, v, σ_m, height)."""
    fwd = np.array([np.cos(heading), np.sin(heading)])
    dx, dy = X - centre[0], Y - centre[1]
    u = dx * fwd[0] + dy * fwd[1]
    v = -dx * fwd[1] + dy * fwd[0]
    inside = (u / half_len) ** 2 + (v / half_wid) ** 2 <= 1.0
    prof = np.ones_like(X)
    for pu, pv, sig, hgt in peaks:
        prof = prof + hgt * np.exp(-((u - pu) ** 2 + (v - pv) ** 2) / (2 * sig**2))
    return np.where(inside, prof, 0.0)


def sit_pressure(shape, pitch_m, centre_xy, heading_rad, mass_kg, ss: int = 3) -> np.ndarray:
    """(H, W) kPa of someone sitting on the floor, legs stretched out (≈ 1300 cm², mean ≈ 5 kPa):
    buttocks 45 % of the weight (peaks under the ischial tuberosities), thighs 35 %, calves 20 %."""
    X, Y = _grid_xy(shape, pitch_m, ss)
    fwd = np.array([np.cos(heading_rad), np.sin(heading_rad)])
    side = np.array([-fwd[1], fwd[0]])
    c = np.asarray(centre_xy, float)
    w = mass_kg * G_M_S2
    total = np.zeros(shape)
    for part, share, along, half_len, half_wid, peaks in (
            ("buttocks", 0.45, 0.0, 0.07, 0.055, ((0.0, 0.0, 0.025, 1.5),)),
            ("thighs", 0.35, 0.26, 0.18, 0.06, ()),
            ("calves", 0.20, 0.70, 0.175, 0.04, ((0.12, 0.0, 0.04, 0.5),))):
        for sgn in (1, -1):
            centre = c + along * fwd + sgn * (0.07 if part == "buttocks" else 0.1) * side
            prof = _down(_blob(X, Y, centre, heading_rad, half_len, half_wid, peaks), ss)
            if prof.sum() > 0:
                total += prof * (share * w / 2 / (prof.sum() * pitch_m**2) / 1e3)
    return total


def board_pressure(shape, pitch_m, centre_xy, force_n, cop_offset_m=(0.0, 0.0), unevenness: np.ndarray | None = None,
                   size_m: float = BOARD_M, ss: int = 3) -> np.ndarray:
    """(H, W) kPa under a rigid square board on a uniform foundation: a plane whose
    centre of pressure sits at ``centre + cop_offset`` (|offset| ≤ size/6 keeps it ≥ 0),
    times ``unevenness`` (floor/rug, a relative field on the supersampled grid)."""
    X, Y = _grid_xy(shape, pitch_m, ss)
    dx, dy = X - centre_xy[0], Y - centre_xy[1]
    half = size_m / 2
    inside = (np.abs(dx) <= half) & (np.abs(dy) <= half)
    plane = 1.0 + 12.0 * (cop_offset_m[0] * dx + cop_offset_m[1] * dy) / size_m**2
    p = np.where(inside, np.maximum(plane, 0.0), 0.0)
    if unevenness is not None:
        p = p * unevenness
    p = _down(p, ss)
    return p * (force_n / (p.sum() * pitch_m**2) / 1e3)


def walk_path(size_m: tuple[float, float], lane_m: float = 0.09, margin_m: float = 0.07) -> list[np.ndarray]:
    """Serpentine lanes along x, ``lane_m`` apart: a list of (2,) waypoints, metres."""
    w, h = size_m
    pts = []
    for i, y in enumerate(np.arange(margin_m, h - margin_m + 1e-9, lane_m)):
        xs = (margin_m, w - margin_m) if i % 2 == 0 else (w - margin_m, margin_m)
        pts += [np.array([xs[0], y]), np.array([xs[1], y])]
    return pts


def footfalls(path: list[np.ndarray], step_m: float = 0.14) -> list[tuple[np.ndarray, float, int]]:
    """Foot placements (centre, heading, side ±1) every ``step_m`` along a path, alternating feet."""
    out, side = [], 1
    for a, b in zip(path[:-1], path[1:]):
        seg = b - a
        length = float(np.linalg.norm(seg))
        if length < 1e-6:
            continue
        head = float(np.arctan2(seg[1], seg[0]))
        lat = np.array([-np.sin(head), np.cos(head)]) * 0.09
        marks = list(np.arange(0.0 if len(out) % 2 == 0 else step_m / 2, length, step_m)) + [length]
        for s in marks:
            out.append((a + seg * (s / length) + side * lat, head, side))
            side = -side
    return out


@dataclass
class Actor:
    """Plays a calibration session on ``sensor`` (a :class:`sim.sensor.CarpetSensor`)."""

    sensor: object
    mass_kg: float = 72.0
    board_mass_kg: float = 3.0
    seed: int = 0
    t_s: float = 0.0
    truth: dict = field(default_factory=dict)  # capture name → (N, H, W) true kPa

    def __post_init__(self) -> None:
        cfg = self.sensor.config
        self.shape = self.sensor.shape
        self.pitch_m = cfg.grid.pitch_mm / 1000.0
        self.rate_hz = cfg.grid.rate_hz
        self.size_m = (self.shape[1] * self.pitch_m, self.shape[0] * self.pitch_m)
        self.rng = np.random.default_rng(self.seed)
        fe = cfg.frontend
        self.device = {"device_id": f"sim-{self.sensor.seed}", "rows": self.shape[0], "cols": self.shape[1],
                       "adc_bits": fe.adc_bits, "sign": fe.sign, "firmware": [1, 0, 0], "protocol_version": 1}

    # ------------------------------------------------------------------ plumbing
    def _record(self, name: str, pressures, keep_truth: bool = False) -> Capture:
        frames, times, truth = [], [], []
        dt = 1.0 / self.rate_hz
        for p in pressures:
            frames.append(self.sensor.counts(p, self.t_s).astype(np.float32))
            times.append(self.t_s)
            if keep_truth:
                truth.append(self.sensor.last.pressure_kpa.astype(np.float32))
            self.t_s += dt
        if keep_truth:
            self.truth[name] = np.stack(truth)
        return Capture(np.stack(frames), np.asarray(times), dict(self.device), self.pitch_m, self.rate_hz)

    def pause(self, seconds: float) -> None:
        """Time passes with the carpet empty (nothing recorded)."""
        self.t_s += seconds

    # ------------------------------------------------------------------ steps
    def empty(self, seconds: float = 10.0, intruder: str | None = None) -> Capture:
        n = int(round(seconds * self.rate_hz))
        zero = np.zeros(self.shape)
        spot = (0.3 * self.size_m[0], 0.7 * self.size_m[1])

        def gen():
            for i in range(n):
                if intruder == "standing":
                    yield stance_pressure(self.shape, self.pitch_m, spot, 0.3, self.mass_kg, 0.5 + 0.05 * np.sin(i / 7))
                elif intruder == "present80" and i < 0.8 * n:
                    # someone standing, shifting slowly across the carpet, leaving at 80 %
                    c = (spot[0] + 0.3 * i / n, spot[1] - 0.2 * i / n)
                    yield stance_pressure(self.shape, self.pitch_m, c, 0.3, self.mass_kg, 0.5 + 0.1 * np.sin(i / 5))
                elif intruder == "walking":
                    yield self._walking_frame(i, n)
                else:
                    yield zero
        return self._record("empty", gen())

    def _walking_frame(self, i: int, n: int) -> np.ndarray:
        """Someone crossing the carpet diagonally at ~1 m/s during the capture."""
        w, h = self.size_m
        f = i / max(n - 1, 1)
        pos = np.array([0.1 * w + 0.8 * w * f, 0.2 * h + 0.6 * h * f])
        head = float(np.arctan2(0.6 * h, 0.8 * w))
        phase = np.sin(2 * np.pi * i / 14.0)
        lat = np.array([-np.sin(head), np.cos(head)]) * 0.09
        fwd = np.array([np.cos(head), np.sin(head)]) * 0.15
        wgt = self.mass_kg * G_M_S2
        return (foot_pressure(self.shape, self.pitch_m, tuple(pos + lat + phase * fwd), head, wgt * (0.5 + 0.5 * phase))
                + foot_pressure(self.shape, self.pitch_m, tuple(pos - lat - phase * fwd), head, wgt * (0.5 - 0.5 * phase)))

    def walk(self, lane_m: float = 0.09, step_s: float = 0.22) -> Capture:
        """Serpentine coverage walk; each foot rests ``2·step_s`` with a load that ramps up and down."""
        falls = footfalls(walk_path(self.size_m, lane_m))
        per = max(2, int(round(step_s * self.rate_hz)))
        wgt = self.mass_kg * G_M_S2

        def gen():
            for k in range(len(falls) - 1):
                a, b = falls[k], falls[k + 1]
                for j in range(per):
                    f = j / per
                    yield (foot_pressure(self.shape, self.pitch_m, tuple(a[0]), a[1], wgt * (1.0 - 0.9 * f))
                           + foot_pressure(self.shape, self.pitch_m, tuple(b[0]), b[1], wgt * (0.1 + 0.9 * f) * 1.1))
        return self._record("walk", gen())

    def board_positions(self) -> list[tuple[float, float]]:
        w, h = self.size_m
        n_x = max(1, int(np.ceil((w - 0.05) / (BOARD_M * 0.8))))
        n_y = max(1, int(np.ceil((h - 0.05) / (BOARD_M * 0.8))))
        xs = np.linspace(min(BOARD_M / 2 + 0.01, w / 2), max(w - BOARD_M / 2 - 0.01, w / 2), n_x)
        ys = np.linspace(min(BOARD_M / 2 + 0.01, h / 2), max(h - BOARD_M / 2 - 0.01, h / 2), n_y)
        return [(x, y) for y in ys for x in xs]

    def board(self, seconds_per_spot: float = 3.0, unevenness_sigma: float = 0.04) -> Capture:
        """The board at overlapping spots covering the carpet; the person shifts their weight on it."""
        force = (self.mass_kg + self.board_mass_kg) * G_M_S2
        n = int(round(seconds_per_spot * self.rate_hz))
        ss = 3

        def gen():
            for spot in self.board_positions():
                field_ = ndimage.gaussian_filter(self.rng.standard_normal((self.shape[0] * ss, self.shape[1] * ss)),
                                                 0.08 / self.pitch_m * ss)
                field_ = 1.0 + unevenness_sigma * field_ / (field_.std() + 1e-12)
                for i in range(n):
                    ang = 2 * np.pi * i / n
                    cop = (0.07 * np.cos(ang), 0.07 * np.sin(2 * ang))
                    yield board_pressure(self.shape, self.pitch_m, spot, force, cop, field_)
                for _ in range(3):  # stepping off, moving the board
                    yield np.zeros(self.shape)
        return self._record("board", gen(), keep_truth=True)

    def stance_spots(self, k: int = 4) -> list[tuple[float, float]]:
        w, h = self.size_m
        cand = [(0.3, 0.3), (0.7, 0.35), (0.35, 0.7), (0.68, 0.68), (0.5, 0.5)]
        return [(fx * w, fy * h) for fx, fy in cand[:k]]

    def stance(self, spots: list[tuple[float, float]], seconds_per_spot: float = 3.0, name: str = "stance",
               sit_spot: tuple[float, float] | None = None) -> Capture:
        """Standing still (with a little sway) at each spot, stepping off in between; then,
        with ``sit_spot``, sitting on the floor there (legs stretched out)."""
        n = int(round(seconds_per_spot * self.rate_hz))

        def gen():
            if sit_spot is not None:
                yield from self.sit(sit_spot)
            for j, spot in enumerate(spots):
                head = 0.4 + 1.1 * j
                for i in range(n):
                    yield stance_pressure(self.shape, self.pitch_m, spot, head, self.mass_kg, 0.5 + 0.06 * np.sin(i / 4))
                for _ in range(3):
                    yield np.zeros(self.shape)
        return self._record(name, gen(), keep_truth=True)

    def sit(self, spot: tuple[float, float], seconds: float = 4.0) -> list[np.ndarray]:
        n = int(round(seconds * self.rate_hz))
        return [sit_pressure(self.shape, self.pitch_m, (spot[0] + 0.005 * np.sin(i / 5), spot[1]), 0.2, self.mass_kg)
                for i in range(n)] + [np.zeros(self.shape)] * 3

    def session(self, stance_spots: int = 4, intruder: str | None = None) -> dict[str, Capture]:
        """The whole scripted session: empty, walk, board, stances, held-out stance."""
        spots = self.stance_spots(stance_spots + 1)
        caps = {"empty": self.empty(intruder=intruder), "walk": self.walk()}
        self.pause(5.0)
        caps["board"] = self.board()
        w, h = self.size_m
        caps["stance"] = self.stance(spots[:-1], sit_spot=(0.25 * w, 0.5 * h))
        caps["holdout"] = self.stance(spots[-1:], name="holdout")
        return caps

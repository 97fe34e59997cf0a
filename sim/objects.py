"""Things on the carpet that are not people: a dropped bag and a small pet (5–30 kg, four paws).

    bag = DroppedBag.random(rng, carpet_size_m=1.83)       # appears at bag.drop_s, lies still
    pet = Pet.random(rng, carpet_size_m=1.83)              # walks about, sometimes lies down
    p_kpa = bag.pressure_kpa(t_s, rows, cols, pitch_m) + pet.pressure_kpa(t_s, rows, cols, pitch_m)

Pressure is the object's weight spread evenly over its contact (a bag's base, a paw, a lying pet's
body outline), rasterised at the sensel centres; add it to the people's pressure before the sensor.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

G_M_S2 = 9.81


def _centres(rows: int, cols: int, pitch_m: float):
    y, x = np.mgrid[0:rows, 0:cols]
    return (x + 0.5) * pitch_m, (y + 0.5) * pitch_m


def _spread(inside: np.ndarray, force_n: float, pitch_m: float) -> np.ndarray:
    n = int(inside.sum())
    out = np.zeros(inside.shape, np.float32)
    if n:
        out[inside] = force_n / (n * pitch_m * pitch_m) / 1000.0
    return out


@dataclass
class DroppedBag:
    """A bag of mass_kg with a base of size_m (x, y) turned by yaw, dropped at drop_s, centred at centre_m."""

    mass_kg: float
    size_m: tuple[float, float]
    yaw_rad: float
    centre_m: tuple[float, float]
    drop_s: float

    @classmethod
    def random(cls, rng, carpet_size_m: float = 1.83, drop_s: float = 1.0) -> "DroppedBag":
        return cls(float(rng.uniform(3, 20)), (float(rng.uniform(0.25, 0.5)), float(rng.uniform(0.15, 0.35))),
                   float(rng.uniform(0, np.pi)), tuple(rng.uniform(0.3, carpet_size_m - 0.3, 2)), float(drop_s))

    def pressure_kpa(self, t_s: float, rows: int, cols: int, pitch_m: float) -> np.ndarray:
        if t_s < self.drop_s:
            return np.zeros((rows, cols), np.float32)
        x, y = _centres(rows, cols, pitch_m)
        c, s = np.cos(self.yaw_rad), np.sin(self.yaw_rad)
        u = c * (x - self.centre_m[0]) + s * (y - self.centre_m[1])
        v = -s * (x - self.centre_m[0]) + c * (y - self.centre_m[1])
        inside = (np.abs(u) <= self.size_m[0] / 2) & (np.abs(v) <= self.size_m[1] / 2)
        return _spread(inside, self.mass_kg * G_M_S2, pitch_m)


@dataclass
class Pet:
    """A four-legged pet: mass_kg, body length_m, walking between random spots at speed_m_s,
    lying down for a while at some of them (a list of (start_s, end_s) in lie_spans_s)."""

    mass_kg: float
    length_m: float
    speed_m_s: float
    path: np.ndarray  # (K, 3): time, x, y of the spots it walks between
    lie_spans_s: list
    paw_radius_m: float

    @classmethod
    def random(cls, rng, carpet_size_m: float = 1.83, seconds: float = 60.0) -> "Pet":
        mass = float(rng.uniform(5, 30))
        length = 0.35 + 0.012 * mass  # a 5 kg cat ≈ 0.4 m, a 30 kg dog ≈ 0.7 m
        speed = float(rng.uniform(0.3, 0.9))
        margin = 0.1 + length / 2
        t, pts, lies = 0.0, [], []
        pos = rng.uniform(margin, carpet_size_m - margin, 2)
        while t < seconds:
            pts.append((t, *pos))
            if rng.random() < 0.4:  # lie down here for a while
                stay = float(rng.uniform(3, 20))
                lies.append((t + 0.5, t + 0.5 + stay))
                t += stay + 1.0
                pts.append((t, *pos))
            nxt = rng.uniform(margin, carpet_size_m - margin, 2)
            t += float(np.linalg.norm(nxt - pos)) / speed
            pos = nxt
        pts.append((t, *pos))
        return cls(mass, length, speed, np.array(pts), lies, 0.02 + 0.0006 * mass)

    def _where(self, t_s: float):
        p = self.path
        x = float(np.interp(t_s, p[:, 0], p[:, 1]))
        y = float(np.interp(t_s, p[:, 0], p[:, 2]))
        k = int(np.clip(np.searchsorted(p[:, 0], t_s), 1, len(p) - 1))
        d = p[k, 1:] - p[k - 1, 1:]
        heading = float(np.arctan2(d[1], d[0])) if np.linalg.norm(d) > 1e-9 else 0.0
        return np.array([x, y]), heading

    def lying(self, t_s: float) -> bool:
        return any(a <= t_s < b for a, b in self.lie_spans_s)

    def pressure_kpa(self, t_s: float, rows: int, cols: int, pitch_m: float) -> np.ndarray:
        x, y = _centres(rows, cols, pitch_m)
        pos, h = self._where(t_s)
        c, s = np.cos(h), np.sin(h)
        u = c * (x - pos[0]) + s * (y - pos[1])
        v = -s * (x - pos[0]) + c * (y - pos[1])
        w = self.mass_kg * G_M_S2
        if self.lying(t_s):  # the body's outline, an ellipse
            inside = (u / (0.5 * self.length_m)) ** 2 + (v / (0.18 * self.length_m)) ** 2 <= 1.0
            return _spread(inside, w, pitch_m)
        out = np.zeros((rows, cols), np.float32)
        # A trot: the diagonal pairs (front-left + hind-right, front-right + hind-left) take turns in the air
        # for the first half of each half-cycle; the paws down share the weight.
        phase = (t_s * 2.0 * self.speed_m_s / max(self.length_m, 1e-3)) % 1.0
        paws = ((0.5, 0.4), (0.5, -0.4), (-0.5, 0.4), (-0.5, -0.4))
        up = set() if phase % 0.5 >= 0.25 else ({0, 3} if phase < 0.5 else {1, 2})
        down = [k for k in range(4) if k not in up]
        for k in down:
            du, dv = u - paws[k][0] * self.length_m * 0.8, v - paws[k][1] * self.length_m * 0.4
            out += _spread(du * du + dv * dv <= self.paw_radius_m ** 2, w / len(down), pitch_m)
        return out


__all__ = ["DroppedBag", "Pet"]

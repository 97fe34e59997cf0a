"""Synthetic pressure worlds for the scene tests: feet rendered at any pitch, in physical units.

A person is two elliptic feet (25 × 9 cm) ±9 cm either side of their centre; the
pressure of each foot is its load over its true area, box-averaged over each sensel
(supersampled at ~4 mm), so the same person gives the same force and centre of
pressure at any pitch.
"""

from __future__ import annotations

import numpy as np

G = 9.81
FOOT_A_M, FOOT_B_M = 0.125, 0.045


def render(rows: int, cols: int, pitch_m: float, people: list[dict]) -> np.ndarray:
    """people: dicts with centre_m (x, y), heading_rad, mass_kg, and optional phase (gait, cycles; None = standing).

    Returns true pressure (rows, cols) float32 in kPa.
    """
    s = max(1, int(round(pitch_m / 0.004)))
    fine = pitch_m / s
    p = np.zeros((rows * s, cols * s))
    for person in people:
        c = np.asarray(person["centre_m"], float)
        h = person.get("heading_rad", 0.0)
        fwd = np.array([np.cos(h), np.sin(h)])
        side = np.array([-fwd[1], fwd[0]])
        phase = person.get("phase")
        sn = 0.0 if phase is None else np.sin(2 * np.pi * phase)
        loads = (0.5 + 0.5 * sn, 0.5 - 0.5 * sn)
        for sgn, load in zip((1, -1), loads):
            fc = c + sgn * 0.09 * side + sgn * sn * 0.15 * fwd
            c0, c1 = max(0, int((fc[0] - FOOT_A_M) / fine)), min(cols * s, int((fc[0] + FOOT_A_M) / fine) + 2)
            r0, r1 = max(0, int((fc[1] - FOOT_A_M) / fine)), min(rows * s, int((fc[1] + FOOT_A_M) / fine) + 2)
            if c0 >= c1 or r0 >= r1:  # the foot's box only (a foot off the carpet: nothing)
                continue
            ys, xs = np.mgrid[r0:r1, c0:c1]
            xs, ys = (xs + 0.5) * fine, (ys + 0.5) * fine
            u = (xs - fc[0]) * fwd[0] + (ys - fc[1]) * fwd[1]
            v = (xs - fc[0]) * side[0] + (ys - fc[1]) * side[1]
            inside = (u / FOOT_A_M) ** 2 + (v / FOOT_B_M) ** 2 <= 1.0
            p[r0:r1, c0:c1][inside] += load * person["mass_kg"] * G / (np.pi * FOOT_A_M * FOOT_B_M) / 1e3
    return p.reshape(rows, s, cols, s).mean(axis=(1, 3)).astype(np.float32)


def noisy(p: np.ndarray, rng: np.random.Generator, sigma_kpa: float = 0.05, salt: int = 0) -> np.ndarray:
    """Add white noise and ``salt`` single-sensel spikes of 5–20 kPa."""
    out = p + rng.normal(0.0, sigma_kpa, p.shape).astype(np.float32)
    if salt:
        r = rng.integers(0, p.shape[0], salt)
        c = rng.integers(0, p.shape[1], salt)
        out[r, c] += rng.uniform(5, 20, salt).astype(np.float32)
    return out


def footstep_scene(people: int, seed: int, frames: int, sigma_kpa: float = 0.05, salt: int = 0):
    """FootstepCarpet walkers: yields (t_s, noisy pressure kPa, {walker index: true centre (2,)})."""
    from sim.footsteps import FootstepCarpet

    carpet = FootstepCarpet(96, 96, people, seed)
    rng = np.random.default_rng(seed + 1000)
    for i in range(frames):
        carpet(i)
        truth = {k: w.pos_m.copy() for k, w in enumerate(carpet._walkers)}
        yield i * carpet.dt_s, noisy(carpet.pressure_kpa().astype(np.float32), rng, sigma_kpa, salt), truth


def render_pads(rows: int, cols: int, pitch_m: float, pads: list[tuple[float, float, float, float, float]]) -> np.ndarray:
    """pads: (x_m, y_m, half_length_m along x, half_width_m along y, force_n) ellipses of uniform pressure
    (a foot, a hand, a knee, buttocks, shoulder blades), box-averaged over each sensel → kPa (rows, cols)."""
    s = max(1, int(round(pitch_m / 0.004)))
    fine = pitch_m / s
    p = np.zeros((rows * s, cols * s))
    for x, y, a, b, force_n in pads:
        if force_n <= 0:
            continue
        c0, c1 = max(0, int((x - a) / fine)), min(cols * s, int((x + a) / fine) + 2)  # the pad's box only
        r0, r1 = max(0, int((y - b) / fine)), min(rows * s, int((y + b) / fine) + 2)
        if c0 >= c1 or r0 >= r1:
            continue
        ys, xs = np.mgrid[r0:r1, c0:c1]
        inside = (((xs + 0.5) * fine - x) / a) ** 2 + (((ys + 0.5) * fine - y) / b) ** 2 <= 1.0
        p[r0:r1, c0:c1][inside] += force_n / (np.pi * a * b) / 1e3
    return p.reshape(rows, s, cols, s).mean(axis=(1, 3)).astype(np.float32)


def foot(x_m: float, y_m: float, force_n: float) -> tuple[float, float, float, float, float]:
    """A foot along x (25 × 9 cm)."""
    return (x_m, y_m, FOOT_A_M, FOOT_B_M, force_n)


def pad(x_m: float, y_m: float, diameter_m: float, force_n: float) -> tuple[float, float, float, float, float]:
    """A round contact: a hand (~0.1 m), a knee (~0.08 m), buttocks (~0.25 m)."""
    return (x_m, y_m, diameter_m / 2, diameter_m / 2, force_n)

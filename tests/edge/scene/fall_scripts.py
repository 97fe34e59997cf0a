"""Scripted per-frame body features for the fall detector's tests: postures, scripts, a runner."""

import numpy as np

from edge.scene.falls import BodyFeatures, FallConfig, FallDetector, Observation

RATE = 14.0
FEET = dict(force_n=650.0, area_m2=0.035, length_m=0.55)
LYING = dict(force_n=650.0, area_m2=0.09, length_m=0.75)
SITTING = dict(force_n=650.0, area_m2=0.058, length_m=0.8)  # ≈ 11 kPa: neither on the feet nor lying
KNEEL = dict(force_n=200.0, area_m2=0.016, length_m=0.55)  # knees and shins on the board's path read light
LONG = dict(force_n=650.0, area_m2=0.085, length_m=1.6)  # lying on the side at full length
SEATED = dict(force_n=110.0, area_m2=0.012, length_m=0.3)  # on a chair beside the carpet: only the feet on it


def body(ids, xy, **kw):
    """BodyFeatures of the tracks ``ids`` at xy (m) in a posture (force_n, area_m2, length_m)."""
    return BodyFeatures(tuple(ids), kw["force_n"], kw["area_m2"], kw["length_m"], np.asarray(xy, float))


def run(script, config=None, activities=None):
    """script: [(seconds, [bodies])] segments → [(type, state, t_s, confidence)]."""
    det = FallDetector(config or FallConfig())
    out, t = [], 0.0
    for seconds, bodies in script:
        for _ in range(int(round(seconds * RATE))):
            for e in det.step(t, bodies, activities or {}):
                out.append((e["type"], e["state"], e["t_s"], e.get("confidence")))
            t += 1 / RATE
    return out, det


def fall_script(transit_s, lie_s, up=True, shift=(0.0, 0.9), transit=None):
    a, b = np.array([0.9, 0.4]), np.array([0.9, 0.4]) + shift
    script = [(3.0, [body([1], a, **FEET)])]
    script.append((transit_s, transit if transit is not None else []))  # toppling: no settled footprint
    script.append((lie_s, [body([2], b, **LYING)]))
    if up:
        script.append((5.0, [body([2], a, **FEET)]))
    return script


def kinds(ev):
    """(type, state) of each event of ``run``."""
    return [(k, s) for k, s, _, _ in ev]


def ob(tid, force_n, area_m2, xy, length_m):
    """An observation whose pressure moments give a print length_m long along x (two equal halves)."""
    x, y = xy
    h = length_m / 4.0
    w = force_n / 2.0
    xs = np.array([x - h, x + h])
    m = np.array([force_n, w * xs.sum(), force_n * y, w * (xs ** 2).sum(), force_n * y * y, w * xs.sum() * y])
    return Observation(tid, force_n, area_m2, np.array([x, y], float), m)

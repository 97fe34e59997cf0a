"""Step 7, known-weight stance: fit the response curve so that Σ P·A = m·g.

Unknowns θ = (P½, n, span k) of ``counts = baseline + sign · gain · k · r(P)``,
r = Pⁿ/(Pⁿ + P½ⁿ). Feet saturate (standing is 25–35 kPa, the carpet's ceiling is
≈ 14 kPa), so a stance only bounds the curve: a saturated sensel carries at least
P_sat,i(θ) = r⁻¹(room_i / (gain_i · k)), room_i the counts from its baseline to the
rail. The fit (``scipy.optimize.least_squares``) combines:

- board frames (all unsaturated, known force (m_person + m_board)·g): the total force
  per frame, and the planarity of each frame's pressure (a wrong exponent bends the
  plane) — these pin the low and middle part of the curve;
- stance frames, censored: the lower bound A·(Σ_unsat P + Σ_sat P_sat,i) may not
  exceed m·g (a one-sided residual);
- weak priors from the note's ranges (n ≈ 1.2 ± 0.3, P½ ≈ 8 kPa within a factor 2).

Then the "fill ratio" φ = (m·g − A·Σ_unsat P) / (A·Σ_sat P_sat,i), the median over
stance frames: how far above the ceiling the saturated sensels of a standing adult
sit on average. Force checks use it for saturated sensels (never per-sensel pressure).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import optimize

from calibration.board import board_frames, default_curve
from calibration.capture import Capture, frame_validity
from calibration.file import UNUSABLE, Curve
from calibration.result import StepResult

G_M_S2 = 9.81
MAX_FRAMES = 24
MAX_SAT_SHARE = 0.3  # a pose whose saturated sensels carry less than this share of the lower bound is an equation
PRIOR_WEIGHT = 0.5  # weak priors from the note (n ≈ 1.2 ± 0.3, P½ ≈ 8 kPa within ×2)
SAT_EXCESS = 1.25  # assumed mean excess over the ceiling of the few saturated sensels of such a pose


@dataclass
class _Frame:
    d: np.ndarray  # unsaturated loaded sensels: counts toward the rail
    g: np.ndarray  # their gains
    room: np.ndarray  # saturated sensels: counts from baseline to rail
    g_sat: np.ndarray
    hat: np.ndarray | None = None  # board frames: plane projector over a subsample of the inner footprint
    inner: np.ndarray | None = None  # board frames: indices into d of that subsample
    scale: float = 1.0  # board frames: footprint box area / usable part of it


def _prepare(cap: Capture, baseline, noise, fault, gain, rail_margin: float = 2.0):
    ok, _ = frame_validity(cap.frames, cap.full_scale)
    raw = cap.frames[ok].astype(np.float32)
    usable = (fault & UNUSABLE) == 0
    d = cap.sign * (raw - baseline[None])
    rail = float(cap.full_scale) if cap.sign > 0 else 0.0
    sat = (np.abs(raw - rail) <= rail_margin) & usable[None]
    d[:, ~usable] = 0.0
    d[d < 4.0 * noise[None]] = 0.0
    room = np.abs(rail - baseline)
    return d, sat, usable, room


def _stance_frames(d, sat, gain, room) -> list[_Frame]:
    loaded = (d > 0) | sat
    n_loaded = loaded.reshape(len(d), -1).sum(axis=1)
    if not (n_loaded > 20).any():
        return []
    ref = np.median(n_loaded[n_loaded > 20])
    idx = np.flatnonzero(n_loaded >= 0.6 * ref)
    idx = idx[np.linspace(0, len(idx) - 1, min(MAX_FRAMES, len(idx))).astype(int)]
    out = []
    for t in idx:
        un = (d[t] > 0) & ~sat[t]
        out.append(_Frame(d[t][un], gain[un], room[sat[t]], gain[sat[t]]))
    return out


def _board_frames(cap, baseline, noise, fault, gain, curve) -> list[_Frame]:
    d, sat, usable, room = _prepare(cap, baseline, noise, fault, gain)
    p0 = curve.inverse(np.maximum(d, 0) / (gain[None] * curve.span_counts))
    bfs = board_frames(d, usable, p0, cap.pitch_m)
    good = [t for t, b in enumerate(bfs) if b is not None and len(b.idx) >= 20]
    good = [good[i] for i in np.linspace(0, len(good) - 1, min(MAX_FRAMES, len(good))).astype(int)] if good else []
    h, w = cap.shape
    rr, cc = np.mgrid[0:h, 0:w]
    xy = np.column_stack([(cc.ravel() + 0.5) * cap.pitch_m, (rr.ravel() + 0.5) * cap.pitch_m])
    out = []
    for t in good:
        bf = bfs[t]
        full = bf.full_idx
        df = d[t].ravel()
        keep = df[full] > 0
        full = full[keep]
        inner = np.flatnonzero(np.isin(full, bf.idx))
        inner = inner[np.linspace(0, len(inner) - 1, min(120, len(inner))).astype(int)]
        scale = bf.box_area / max(bf.box_area - bf.box_masked, 1)
        out.append(_Frame(df[full], gain.ravel()[full], np.zeros(0), np.zeros(0), _plane_projector(xy[full][inner]),
                          inner, scale))
    return out


def _curve(theta) -> Curve:
    return Curve(half_scale_kpa=float(np.exp(theta[0])), exponent=float(theta[1]), span_counts=float(np.exp(theta[2])))


def _pressure(c: Curve, d, g):
    return c.inverse(d / (g * c.span_counts))


def _plane_projector(xy: np.ndarray) -> np.ndarray:
    """(K, K) hat matrix of a least-squares plane over the points xy (K, 2), subsampled to ≤ 120."""
    a = np.column_stack([np.ones(len(xy)), xy - xy.mean(axis=0)])
    return a @ np.linalg.pinv(a)


def _residuals(theta, stance, board, weight_n, board_weight_n, area_m2):
    c = _curve(theta)
    out = []
    for f in board:
        p = _pressure(c, f.d, f.g)
        out.append(5.0 * (area_m2 * 1e3 * p.sum() * f.scale / board_weight_n - 1.0))
        pi = p[f.inner]
        out.extend(0.5 * (pi - f.hat @ pi) / max(float(pi.mean()), 1e-6))
    for f in stance:
        un = area_m2 * 1e3 * _pressure(c, f.d, f.g).sum()
        lo_sat = area_m2 * 1e3 * _pressure(c, np.minimum(f.room, f.g_sat * c.span_counts * 0.999), f.g_sat).sum()
        share = lo_sat / max(un + lo_sat, 1e-9)
        out.append(10.0 * max(0.0, (un + lo_sat) / weight_n - 1.0))  # censored: a lower bound
        # mostly unsaturated (sitting): nearly an equation; the weight fades out as the share grows
        out.append(5.0 * max(0.0, 1.0 - share / MAX_SAT_SHARE) * ((un + SAT_EXCESS * lo_sat) / weight_n - 1.0))
    out.append(PRIOR_WEIGHT * (theta[1] - 1.2) / 0.3)
    out.append(PRIOR_WEIGHT * (theta[0] - np.log(8.0)) / 0.7)
    return np.asarray(out, float)


def fit_curve(stance: list[_Frame], board: list[_Frame], weight_n: float, board_weight_n: float,
              area_m2: float, curve0: Curve) -> tuple[Curve, dict]:
    """Least-squares fit of (ln P½, n, ln k) (see the module docstring): a coarse grid over
    (P½, n) with the best span for each, then a local polish from the best."""
    args = (stance, board, weight_n, board_weight_n, area_m2)
    lk0 = np.log(curve0.span_counts)

    def cost(theta):
        return float(np.sum(_residuals(theta, *args) ** 2))

    best = None
    for ph in (5.5, 8.0, 11.5):
        for n in (0.95, 1.2, 1.45):
            r = optimize.minimize_scalar(lambda lk: cost(np.array([np.log(ph), n, lk])),
                                         bounds=(lk0 - 1.5, lk0 + 1.5), method="bounded", options={"xatol": 1e-2})
            if best is None or r.fun < best[0]:
                best = (r.fun, np.array([np.log(ph), n, r.x]))
    lb = [np.log(2.0), 0.6, lk0 - 2.0]
    ub = [np.log(40.0), 2.5, lk0 + 2.0]
    sol = optimize.least_squares(_residuals, best[1], args=args, bounds=(lb, ub), diff_step=1e-3, max_nfev=60)
    c = _curve(sol.x)
    info = {"cost": float(sol.cost), "nfev": int(sol.nfev), "success": bool(sol.success)}
    if board:
        f_b = [area_m2 * 1e3 * _pressure(c, f.d, f.g).sum() * f.scale / board_weight_n - 1.0 for f in board]
        info["board_force_error"] = float(np.median(np.abs(f_b)))
    return c, info


def fill_ratio(c: Curve, stance: list[_Frame], weight_n: float, area_m2: float) -> tuple[float, float]:
    """(φ, median lower-bound force / m·g) over the standing frames (saturated share ≥ 30 %).

    Semantics of the runtime apply: a sensel is censored when at the rail or above the
    ceiling P_sat; φ = (m·g − A·Σ_uncensored P) / (A · n_censored · P_sat)."""
    phis, lows = [], []
    for f in stance:
        p = _pressure(c, f.d, f.g)
        over = p >= c.saturation_kpa
        unsat = area_m2 * 1e3 * p[~over].sum()
        n_cens = int(over.sum()) + len(f.room)
        cens = area_m2 * 1e3 * n_cens * c.saturation_kpa
        if cens / max(unsat + cens, 1e-9) < MAX_SAT_SHARE:
            continue
        lows.append((unsat + cens) / weight_n)
        phis.append((weight_n - unsat) / cens)
    return (float(np.median(phis)) if phis else 1.0), (float(np.median(lows)) if lows else float("nan"))


def known_weight_stance(cap: Capture, baseline: np.ndarray, noise: np.ndarray, fault: np.ndarray, gain: np.ndarray,
                        mass_kg: float, board_cap: Capture | None = None, board_mass_kg: float = 3.0,
                        curve0: Curve | None = None) -> StepResult:
    res = StepResult("stance")
    if not 20.0 <= mass_kg <= 250.0:
        return res.refuse(f"a mass of {mass_kg:g} kg is not plausible; enter the person's mass in kg", retry=False)
    usable = (fault & UNUSABLE) == 0
    curve0 = curve0 or default_curve(baseline, cap.sign, cap.full_scale, usable)
    d, sat, usable, room = _prepare(cap, baseline, noise, fault, gain)
    stance = _stance_frames(d, sat, gain, room)
    if len(stance) < 5:
        return res.refuse("nobody stood still on the carpet during the stance capture; stand on both feet, "
                          "still, for 3 s at each spot")
    board = _board_frames(board_cap, baseline, noise, fault, gain, curve0) if board_cap is not None else []
    area = cap.pitch_m**2
    w_n = mass_kg * G_M_S2
    curve, info = fit_curve(stance, board, w_n, (mass_kg + board_mass_kg) * G_M_S2, area, curve0)
    room_typ = float(np.median(room[usable]))
    # the ceiling: where a typical sensel has used 90 % of its room to the rail (the top of the
    # curve is the least constrained part; beyond it readings are censored, never extrapolated)
    curve.saturation_kpa = float(curve.inverse(np.array(min(0.9 * room_typ / curve.span_counts, 0.99))))
    phi, low = fill_ratio(curve, stance, w_n, area)
    sat_frac = float(np.mean([len(f.room) / max(len(f.room) + len(f.d), 1) for f in stance]))
    res.numbers.update(half_scale_kpa=round(curve.half_scale_kpa, 3), exponent=round(curve.exponent, 3),
                       span_counts=round(curve.span_counts, 2), saturation_kpa=round(curve.saturation_kpa, 2),
                       saturated_fill_ratio=round(phi, 3), lower_bound_force_ratio=round(low, 3),
                       saturated_fraction=round(sat_frac, 3), stance_frames=len(stance), board_frames=len(board),
                       mass_kg=mass_kg, fit=info)
    res.arrays["curve"] = np.array([curve.half_scale_kpa, curve.exponent, curve.span_counts, curve.saturation_kpa])
    res.say(f"curve: P½ {curve.half_scale_kpa:.2f} kPa, exponent {curve.exponent:.2f}, span {curve.span_counts:.0f} counts; "
            f"ceiling {curve.saturation_kpa:.1f} kPa")
    res.say(f"{sat_frac:.0%} of the loaded sensels were saturated (censored); standing, their mean pressure "
            f"is ≈ {phi:.2f}× the ceiling (used by force checks only)")
    if not board:
        res.say("no board frames given: the curve rests on the priors and the censored stance bound only")
    if low > 1.1:
        res.say(f"even the lower bound of the force is {low:.0%} of the body weight: check the mass entered")
    return res

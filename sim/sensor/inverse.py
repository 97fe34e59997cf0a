"""Invert the sensor model with its true parameters: counts → pressure (kPa).

This is ground truth for tests, not a calibration procedure: it knows every gain,
offset and fault. It undoes, in reverse order: the smear (recursively along the scan),
the rails (saturated sensels are censored: their estimate is a lower bound), the front
end, the crosstalk (fixed-point on the line sums; floating readout also removes the
ghosts), leakage, gains, temperature and creep, hysteresis (with the frame's
remembered peak) and the Hill curve. Noise is not removed.

Exactness: with noise off, the only error left is quantisation. It is exact where
``result.exact``: measurable, unsaturated, not right after a rail-coded sample in scan
order (its analogue value is hidden by the amplifier headroom), and (when crosstalk is
on) on no row or column holding a saturated sensel or a short, whose true load is
unknown. Stuck lines are assumed to carry no load.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter

from .model import FrameState, ghosts, line_sums
from .params import SensorParams, hill_inverse


@dataclass
class InverseResult:
    pressure_kpa: np.ndarray  # estimate; NaN where not measurable; a lower bound where saturated
    saturated: np.ndarray  # bool: at the rail (censored)
    measurable: np.ndarray  # bool: the reading depends on this sensel's pressure
    exact: np.ndarray  # bool: the estimate is exact up to noise and quantisation
    converged: bool  # the crosstalk fixed-point converged


def initial_state(params: SensorParams, t_s: float = 0.0) -> FrameState:
    """The state of the first frame of a session at ``t_s`` (no history)."""
    cfg, s = params.config, params.session
    dyn = cfg.dynamics
    temp = s.config.temperature_c + s.config.temperature_slope_c_per_h * t_s / 3600.0
    offset = (params.carpet.offset_counts + s.drift_counts_per_h * (t_s / 3600.0)
              + s.offset_tempco_counts_per_c * (temp - dyn.reference_temperature_c))
    shape = params.carpet.shape
    return FrameState(t_s=t_s, temperature_c=temp,
                      temp_factor=1.0 + dyn.temp_gain_per_c * (temp - dyn.reference_temperature_c),
                      offset_counts=offset, peak=np.zeros(shape), creep_factor=np.ones(shape),
                      prev_sample=float(np.median(offset)))


def unsmear(counts: np.ndarray, smear: float, prev_sample: float) -> np.ndarray:
    """Undo out_i = (1−s)·v_i + s·v_{i−1} along the row-major scan (an exact IIR filter,
    started from the previous frame's last sample)."""
    x = np.asarray(counts, np.float64)
    if smear <= 0:
        return x.copy()
    q = smear / (1.0 - smear)
    # v_i + q·v_{i−1} = x_i/(1−s); initial condition v_{−1} = prev_sample
    v, _ = lfilter([1.0 / (1.0 - smear)], [1.0, q], x.ravel(), zi=[-q * prev_sample])
    return v.reshape(x.shape)


def true_pressure_estimate(counts: np.ndarray, params: SensorParams, state: FrameState | None = None,
                           max_iter: int = 500, tol: float = 1e-13) -> InverseResult:
    """Pressure (kPa) from raw ``counts`` with the true ``params`` and the frame's ``state``
    (``sensor.last.state``; ``None`` = the first frame of the session at t = 0)."""
    c = params.carpet
    cfg = params.config
    if state is None:
        state = initial_state(params)
    counts = np.asarray(counts)
    if counts.shape != c.shape:
        raise ValueError(f"counts have shape {counts.shape}, the carpet is {c.shape}")
    fs = float(c.full_scale)
    v = unsmear(counts, cfg.noise.smear_fraction, state.prev_sample)
    rail = c.rail_counts
    saturated = (v >= fs - 1.0) if rail > 0 else (v <= 1.0)
    v = np.clip(v, 0.0, fs)

    measurable = c.measurable.copy()
    stuck = c.masks["stuck"]
    saturated &= ~stuck & ~c.masks["short"]
    front_gain = cfg.frontend.sign * c.k_counts * c.tile_gain
    a_app = (v - state.offset_counts) / front_gain
    a_app = np.maximum(a_app, 0.0)
    a_app[c.line_factor == 0] = 0.0
    # unknown sensels: stuck → leakage only (assumed unloaded); shorted crossing → leakage
    unknown = stuck | c.masks["short"]
    a_unknown = (c.leak * c.line_factor)[unknown]

    rho = cfg.crosstalk.line_resistance_ohm * cfg.crosstalk.g_full_s
    b, converged = _undo_line_loading(a_app, unknown, a_unknown, params, max_iter, tol)
    a = b
    if cfg.crosstalk.readout == "floating":
        a, ok = _undo_ghosts(b, params, max_iter)
        converged = converged and ok
    with np.errstate(invalid="ignore", divide="ignore"):
        film = np.where(c.line_factor > 0, a / np.where(c.line_factor > 0, c.line_factor, 1.0) - c.leak, 0.0)
        uh = film / (c.film_gain * state.temp_factor * state.creep_factor)
    u = _undo_hysteresis(np.maximum(uh, 0.0), state.peak, cfg.dynamics.hysteresis)
    p = hill_inverse(u, cfg.response.half_scale_kpa, cfg.response.exponent)
    p = np.where(measurable, p, np.nan)

    exact = measurable & ~saturated
    # a rail-coded sample hides its analogue value (amplifier headroom), so the smear
    # undone on the next sample in scan order is uncertain by ≤ s/(1−s)·headroom
    if cfg.noise.smear_fraction > 0:
        at_rail = (np.asarray(counts) == rail).ravel()
        after = np.zeros_like(at_rail)
        after[1:] = at_rail[:-1]
        exact &= ~after.reshape(c.shape)
    if rho > 0:
        bad = saturated | c.masks["short_lines"]
        exact &= ~bad.any(axis=1)[:, None] & ~bad.any(axis=0)[None, :]
    return InverseResult(pressure_kpa=p, saturated=saturated & measurable, measurable=measurable, exact=exact,
                         converged=converged)


def _undo_line_loading(a_app: np.ndarray, unknown: np.ndarray, a_unknown: np.ndarray, params: SensorParams,
                       max_iter: int, tol: float) -> tuple[np.ndarray, bool]:
    """Apparent → true line-loaded activations (crosstalk through line resistance and shorted crossings):
    the fixed point b = a_app·(1 + ρ·row sums)(1 + ρ·column sums); → (b, converged)."""
    cfg = params.config
    rho = cfg.crosstalk.line_resistance_ohm * cfg.crosstalk.g_full_s
    shorts = [(s.row, s.col, s.g_short_s / cfg.crosstalk.g_full_s) for s in cfg.faults.shorts]
    b = a_app.copy()
    b[unknown] = a_unknown
    if not (rho > 0 or shorts):
        return b, True
    for _ in range(max_iter):
        rs, cs = line_sums(b, shorts)
        nb = a_app * ((1.0 + rho * rs)[:, None] * (1.0 + rho * cs)[None, :])
        nb[unknown] = a_unknown
        delta = np.max(np.abs(nb - b))
        b = nb
        if delta <= tol * max(1.0, float(np.max(b))):
            return b, True
    return b, False


def _undo_ghosts(b: np.ndarray, params: SensorParams, max_iter: int) -> tuple[np.ndarray, bool]:
    """A floating readout's ghosts: b = a + ghosts(a), solved by the fixed point a ← b − ghosts(a), damped
    (the ghost term's slope can exceed 1 under dense presses, so the plain iteration would oscillate)."""
    c, cfg = params.carpet, params.config
    leak = c.leak * c.line_factor
    a = b.copy()
    for _ in range(20 * max_iter):
        na = np.maximum(b - ghosts(np.maximum(a - leak, 0.0), cfg.crosstalk.ghost_strength), 0.0)
        delta = np.max(np.abs(na - a))
        a = a + 0.3 * (na - a)
        if delta <= 1e-11:
            return a, True
    return a, False


def _undo_hysteresis(uh: np.ndarray, peak: np.ndarray, h: float) -> np.ndarray:
    """The film's response with hysteresis ``h`` → the loading-branch response: on the unloading branch
    (uh < peak) the smaller root of 4H/peak·u² − (1+4H)·u + uh = 0."""
    if h <= 0:
        return uh
    with np.errstate(invalid="ignore", divide="ignore"):
        disc = np.maximum((1 + 4 * h) ** 2 - 16 * h * uh / np.where(peak > 0, peak, 1.0), 0.0)
        u_unload = ((1 + 4 * h) - np.sqrt(disc)) * peak / (8 * h)
    return np.where((peak > 0) & (uh < peak), u_unload, uh)


__all__ = ["InverseResult", "initial_state", "true_pressure_estimate", "unsmear"]

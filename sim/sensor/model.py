"""The stateful carpet sensor: true pressure (kPa) per sensel → raw counts (uint16).

Pipeline per frame (``CarpetSensor.counts``), in order:

1. pressure clipped at 0; optional rug blur (session ``rug_sigma_mm``);
2. film response u = x/(1+x), x = (P/P½)^n;
3. hysteresis: with p the remembered peak (decays with τ_h),
   u_h = u + 4H·u·(1 − u/max(p, u)) (the unloading branch lies above the loading one,
   by at most H·p);
4. conductance A = (u_h · film_gain · creep · temperature + leak) · line_factor, in
   units of g_full; creep = 1 + c·log10(1 + age/τ0), age = time under load before this
   frame; temperature = 1 + k_T·(T − T_ref);
5. crosstalk: (floating readout: + ghosts), then line loading
   A_app = A / ((1 + R·g_full·ΣA_col)(1 + R·g_full·ΣA_row)); a shorted row/column pair
   shares one load;
6. front end: v = offset(t) + sign · k · tile_gain · A_app, clipped a little beyond the
   ADC range (amplifier headroom); stuck lines and shorted crossings forced there;
7. multiplexer smear in scan order (row-major): (1 − s)·v_i + s·v_{i−1};
8. noise: white + per-row common + extra on noisy lines;
9. ADC: round, clip to [0, 2^bits − 1], uint16; stuck lines read their code exactly.

The state carried between frames: the hysteresis peak, the creep load age, the last
analogue sample (smear) and the time. Ground truth of the last frame is in
``sensor.last`` (:class:`FrameTruth`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage

from .config import GridConfig, SensorConfig, SessionConfig, lsb10_to_counts
from .params import (
    CarpetParams,
    SensorParams,
    SessionParams,
    draw_carpet,
    draw_session,
    hill,
    random_config,
    random_session_config,
)

# spawn keys of the three randomisation levels (+ the frame stream)
_LEVEL_CARPET, _LEVEL_SESSION, _LEVEL_FRAME, _LEVEL_STREAM = 0, 1, 2, 3


def _seq(seed: int, *key: int) -> np.random.SeedSequence:
    return np.random.SeedSequence(entropy=seed, spawn_key=tuple(key))


@dataclass
class FrameState:
    """The state a frame was produced with (what the inverse needs besides the params)."""

    t_s: float
    temperature_c: float
    temp_factor: float  # 1 + k_T (T − T_ref)
    offset_counts: np.ndarray  # (rows, cols): front-end offset at t, with drift and tempco
    peak: np.ndarray  # (rows, cols): hysteresis peak remembered from earlier frames (decayed)
    creep_factor: np.ndarray  # (rows, cols)
    prev_sample: float  # analogue value of the previous sample in scan order (last of the last frame)


@dataclass
class FrameTruth:
    """Ground truth of the last frame."""

    t_s: float
    pressure_kpa: np.ndarray  # pressure at the sensels (after the rug, ≥ 0)
    state: FrameState
    saturated: np.ndarray  # bool: the analogue reading reached the rail (censored: P ≥ local P_sat)
    noiseless_counts: np.ndarray  # float: the reading without noise and quantisation
    conductance: np.ndarray  # A (units of g_full) before crosstalk


def _initial_peak(shape: tuple[int, int]) -> np.ndarray:
    return np.zeros(shape)


class CarpetSensor:
    """A simulated carpet: true pressure → raw counts, with all its imperfections.

    ``CarpetSensor(config, seed)`` realises ``config`` (gains, offsets, faults) from
    ``seed``; ``CarpetSensor.random(seed, grid=96)`` also draws the configuration from
    the note's ranges. Sessions (``start_session``) set temperature and drift; frames
    draw noise. Same seed, same calls → same counts.
    """

    def __init__(self, config: SensorConfig | None = None, seed: int = 0, *,
                 randomise_sessions: bool = False, rug: bool = False) -> None:
        self.config = config if config is not None else SensorConfig()
        self.seed = int(seed)
        self._randomise_sessions = randomise_sessions
        self._rug = rug
        self.carpet: CarpetParams = draw_carpet(self.config, np.random.default_rng(_seq(self.seed, _LEVEL_CARPET)))
        self._rebuild_derived()
        self.start_session(0)

    # construction ---------------------------------------------------------------------
    @classmethod
    def random(cls, seed: int, grid: int | GridConfig = 96, *, pitch_mm: float | None = None,
               adc_bits: int | None = None, sign: int | None = None, faults=True,
               fault_rates: dict[str, float] | None = None, readout: str = "zero_potential",
               rug: bool = False) -> "CarpetSensor":
        """A carpet drawn from the note's ranges.

        ``grid``: 96, 48, 32 (square) or a :class:`GridConfig`. ``adc_bits`` and ``sign``
        default to random (10/12 bit, ±1). ``faults``: True (random, at
        ``ranges.FAULT_RATES`` merged with ``fault_rates``), False, or a
        :class:`FaultConfig`. Sessions are randomised too (temperature, drift; the rug
        blur only if ``rug``).
        """
        if isinstance(grid, GridConfig):
            g = grid
        else:
            g = GridConfig(rows=int(grid), cols=int(grid), **({} if pitch_mm is None else {"pitch_mm": pitch_mm}))
        rng = np.random.default_rng(_seq(int(seed), _LEVEL_CARPET, 1))
        cfg = random_config(rng, g, adc_bits=adc_bits, sign=sign, faults=faults, fault_rates=fault_rates,
                            readout=readout)
        return cls(cfg, seed, randomise_sessions=True, rug=rug)

    def _rebuild_derived(self) -> None:
        c = self.carpet
        cfg = self.config
        self._rho = cfg.crosstalk.line_resistance_ohm * cfg.crosstalk.g_full_s
        self._front_gain = cfg.frontend.sign * c.k_counts * c.tile_gain
        self._stuck = ~np.isnan(c.stuck_counts)
        self._stuck_idx = np.nonzero(self._stuck)
        self._stuck_vals = c.stuck_counts[self._stuck_idx]
        self._noisy_idx = np.nonzero(c.extra_noise_counts > 0)
        self._noisy_sigma = c.extra_noise_counts[self._noisy_idx]
        self._shorts = [(s.row, s.col, s.g_short_s / cfg.crosstalk.g_full_s) for s in cfg.faults.shorts]
        bits = cfg.frontend.adc_bits
        self._white = lsb10_to_counts(cfg.noise.white_lsb10, bits)
        self._row_noise = lsb10_to_counts(cfg.noise.row_lsb10, bits)

    # sessions -------------------------------------------------------------------------
    def start_session(self, index: int = 0, config: SessionConfig | None = None) -> SessionParams:
        """Begin session ``index``: new temperature/drift (random for ``random`` carpets,
        else ``config`` or ``self.config.session``), fresh state, frame noise seeded by
        (seed, index). Time restarts at the first frame's ``t_s``."""
        if config is None:
            if self._randomise_sessions:
                config = random_session_config(np.random.default_rng(_seq(self.seed, _LEVEL_SESSION, index, 0)),
                                               rug=self._rug)
            else:
                config = self.config.session
        self.session = draw_session(self.config, config, index, self.carpet.tile_index,
                                    np.random.default_rng(_seq(self.seed, _LEVEL_SESSION, index, 1)))
        self._frame_rng = np.random.default_rng(_seq(self.seed, _LEVEL_FRAME, index))
        shape = self.carpet.shape
        self._t: float | None = None
        self._peak = _initial_peak(shape)
        self._age = np.zeros(shape)
        self._prev_sample: float | None = None
        self.frame_index = 0
        self.last: FrameTruth | None = None
        return self.session

    # ground truth ---------------------------------------------------------------------
    @property
    def params(self) -> SensorParams:
        """The true parameters (carpet + current session)."""
        return SensorParams(self.carpet, self.session)

    @property
    def fault_masks(self) -> dict[str, np.ndarray]:
        """Per-sensel bool masks by fault kind: dead, half_dead, stuck, noisy, short
        (the crossing), short_lines (its row and column), mux_bank, outside (not part of
        a non-rectangular carpet)."""
        return {k: v.copy() for k, v in self.carpet.masks.items()}

    @property
    def shape(self) -> tuple[int, int]:
        return self.carpet.shape

    def temperature_c(self, t_s: float) -> float:
        s = self.session.config
        return s.temperature_c + s.temperature_slope_c_per_h * t_s / 3600.0

    def frame_state(self, t_s: float) -> FrameState:
        """The state the next frame at ``t_s`` would be produced with (does not advance)."""
        cfg, s = self.config, self.session
        dyn = cfg.dynamics
        dt = (1.0 / cfg.grid.rate_hz) if self._t is None else (t_s - self._t)
        temp = self.temperature_c(t_s)
        temp_factor = 1.0 + dyn.temp_gain_per_c * (temp - dyn.reference_temperature_c)
        offset = (self.carpet.offset_counts + s.drift_counts_per_h * (t_s / 3600.0)
                  + s.offset_tempco_counts_per_c * (temp - dyn.reference_temperature_c))
        if dyn.hysteresis > 0:
            peak = self._peak * np.exp(-max(dt, 0.0) / dyn.hysteresis_tau_s)
        else:
            peak = self._peak
        if dyn.creep_per_decade > 0:
            creep = 1.0 + dyn.creep_per_decade * np.log10(1.0 + self._age / dyn.creep_tau0_s)
        else:
            creep = np.ones(self.shape)
        prev = float(np.median(offset)) if self._prev_sample is None else self._prev_sample
        return FrameState(t_s=float(t_s), temperature_c=temp, temp_factor=temp_factor, offset_counts=offset,
                          peak=peak, creep_factor=creep, prev_sample=prev)

    def expected_empty_counts(self, t_s: float = 0.0) -> np.ndarray:
        """Noise-free reading of an empty carpet at ``t_s`` for the current state (float)."""
        saved = (self._t, self._peak, self._age, self._prev_sample, self.frame_index, self.last, self._frame_rng)
        self._frame_rng = np.random.default_rng(0)
        try:
            self._forward(np.zeros(self.shape), t_s, noise=False)
            return self.last.noiseless_counts.copy()
        finally:
            (self._t, self._peak, self._age, self._prev_sample, self.frame_index, self.last, self._frame_rng) = saved

    # the model ------------------------------------------------------------------------
    def counts(self, pressure_kpa: np.ndarray, t_s: float) -> np.ndarray:
        """Raw counts (rows, cols) uint16 for true pressure ``pressure_kpa`` at time ``t_s``.

        Advances the state (hysteresis, creep, smear, temperature/drift with ``t_s``).
        Raises ``ValueError`` on a wrong shape, non-finite pressure or time going back.
        """
        return self._forward(pressure_kpa, t_s, noise=True)

    def _forward(self, pressure_kpa: np.ndarray, t_s: float, noise: bool) -> np.ndarray:
        cfg, c = self.config, self.carpet
        p = np.asarray(pressure_kpa, dtype=np.float64)
        if p.shape != c.shape:
            raise ValueError(f"pressure has shape {p.shape}, the carpet is {c.shape}")
        if not np.isfinite(p).all():
            raise ValueError("pressure contains NaN or infinity")
        if self._t is not None and t_s < self._t:
            raise ValueError(f"time went back: {t_s} < {self._t}")
        p = np.maximum(p, 0.0)
        rug = self.session.config.rug_sigma_mm
        if rug > 0:
            p = ndimage.gaussian_filter(p, rug / cfg.grid.pitch_mm, mode="constant")
        st = self.frame_state(t_s)
        dyn = cfg.dynamics
        rc = cfg.response

        u = hill(p, rc.half_scale_kpa, rc.exponent)
        if dyn.hysteresis > 0:
            pk = np.maximum(st.peak, u)
            with np.errstate(invalid="ignore", divide="ignore"):
                uh = u + 4.0 * dyn.hysteresis * u * (1.0 - np.where(pk > 0, u / pk, 1.0))
        else:
            pk = st.peak
            uh = u
        a = (uh * (c.film_gain * (st.temp_factor * st.creep_factor)) + c.leak) * c.line_factor
        a_app = apply_crosstalk(a, self._rho, cfg.crosstalk.readout, cfg.crosstalk.ghost_strength, self._shorts,
                                c.leak * c.line_factor)

        fs = float(c.full_scale)
        v_raw = st.offset_counts + self._front_gain * a_app
        rail = c.rail_counts
        saturated = (v_raw >= fs) if rail > 0 else (v_raw <= 0.0)
        head = cfg.frontend.amp_headroom_fraction * fs
        v = np.clip(v_raw, -head, fs + head)  # the amplifier clips a little beyond the ADC range
        if self._stuck_vals.size:
            v[self._stuck_idx] = np.where(self._stuck_vals > 0, fs + head, -head)
        for r, col, _ in self._shorts:
            v[r, col] = fs + head if rail > 0 else -head
        s = cfg.noise.smear_fraction
        flat = v.ravel()
        if s > 0:
            out = (1.0 - s) * flat
            out[1:] += s * flat[:-1]
            out[0] += s * st.prev_sample
            out = out.reshape(c.shape)
        else:
            out = v.copy()
        noiseless = out
        if noise:
            rng = self._frame_rng
            noisy = noiseless.copy()
            if self._white > 0:
                noisy += self._white * rng.standard_normal(c.shape, dtype=np.float32)
            if self._row_noise > 0:
                noisy += self._row_noise * rng.standard_normal((c.shape[0], 1), dtype=np.float32)
            if self._noisy_sigma.size:
                noisy[self._noisy_idx] += self._noisy_sigma * rng.standard_normal(self._noisy_sigma.size)
        else:
            noisy = noiseless
        counts = np.clip(np.rint(noisy), 0.0, fs).astype(np.uint16)
        if self._stuck_vals.size:
            counts[self._stuck_idx] = self._stuck_vals
        for r, col, _ in self._shorts:
            counts[r, col] = rail

        # state update
        if dyn.hysteresis > 0:
            self._peak = pk
        if dyn.creep_per_decade > 0:
            dt = (1.0 / cfg.grid.rate_hz) if self._t is None else (t_s - self._t)
            loaded = p > dyn.creep_threshold_kpa
            self._age = np.where(loaded, self._age + dt, self._age * np.exp(-dt / dyn.creep_recovery_tau_s))
        self._prev_sample = float(flat[-1])
        self._t = float(t_s)
        self.frame_index += 1
        self.last = FrameTruth(t_s=float(t_s), pressure_kpa=p, state=st, saturated=saturated,
                               noiseless_counts=noiseless, conductance=a)
        return counts

    def __repr__(self) -> str:
        g, fe = self.config.grid, self.config.frontend
        return (f"CarpetSensor({g.rows}×{g.cols}, pitch {g.pitch_mm} mm, {fe.adc_bits} bit, sign {fe.sign:+d}, "
                f"seed {self.seed}, session {self.session.index})")


def line_sums(a: np.ndarray, shorts) -> tuple[np.ndarray, np.ndarray]:
    """Row and column sums of normalised conductance; shorted pairs share their load."""
    rs = a.sum(axis=1)
    cs = a.sum(axis=0)
    for r, c, g in shorts:
        merged = rs[r] + cs[c] + g
        rs[r] = merged
        cs[c] = merged
    return rs, cs


def ghosts(a: np.ndarray, strength: float = 1.0) -> np.ndarray:
    """Ghost conductance at each sensel (r, c) through the other sensels when unselected
    lines float: paths row r → (r, c') → column c' → (r', c') → row r' → (r', c) → column c
    with r' ≠ r, c' ≠ c.

    The three stages are lumped: X = Σ_{c'≠c} a[r, c'], Y = Σ_{r'≠r} a[r', c], and the
    bridge Z = T·X·Y / (Σx²·Σy²) with T = Σ_{r'≠r, c'≠c} a[r, c']·a[r', c']·a[r', c];
    ghost = strength · X·Z·Y / (XY + XZ + ZY), their series conductance. Exact for three
    single presses (series of three) and for uniform rectangular blocks of presses
    (fully connected network); vectorised with two matrix products.
    """
    rows_sq = np.einsum("ij,ij->i", a, a)
    cols_sq = np.einsum("ij,ij->j", a, a)
    a2 = a * a
    t = a @ a.T @ a - a * rows_sq[:, None] - a * cols_sq[None, :] + a2 * a
    x = a.sum(axis=1)[:, None] - a
    y = a.sum(axis=0)[None, :] - a
    sx = rows_sq[:, None] - a2
    sy = cols_sq[None, :] - a2
    with np.errstate(invalid="ignore", divide="ignore"):
        z = np.where((sx > 0) & (sy > 0), np.maximum(t, 0.0) * x * y / (sx * sy), 0.0)
        den = x * y + x * z + z * y
        g = np.where(den > 0, x * z * y / den, 0.0)
    return strength * g


def apply_crosstalk(a: np.ndarray, rho: float, readout: str, ghost_strength: float, shorts,
                    leak: np.ndarray | float = 0.0) -> np.ndarray:
    """Apparent normalised conductance. ``rho`` = R·g_full. Ghosts are computed from the
    pressure-driven part ``a − leak`` (the leakage network adds a near-uniform background
    that the baseline absorbs; it is left out)."""
    if readout == "floating":
        a = a + ghosts(np.maximum(a - leak, 0.0), ghost_strength)
    if rho <= 0 and not shorts:
        return a
    rs, cs = line_sums(a, shorts)
    return a / ((1.0 + rho * rs)[:, None] * (1.0 + rho * cs)[None, :])


__all__ = ["CarpetSensor", "FrameState", "FrameTruth", "apply_crosstalk", "ghosts", "line_sums"]

"""The realised (drawn) parameters of one carpet and one session: the ground truth.

:func:`draw_carpet` turns a :class:`~sim.sensor.config.SensorConfig` and a random
generator into per-sensel arrays; :func:`draw_session` does the same for a
:class:`~sim.sensor.config.SessionConfig`. :func:`random_config` draws a whole
configuration (curve, gains, front end, faults, …) from the ranges of the note.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy import ndimage

from .config import (
    CrosstalkConfig,
    DynamicsConfig,
    FrontEndConfig,
    GainConfig,
    GridConfig,
    NoiseConfig,
    ResponseConfig,
    SensorConfig,
    SessionConfig,
    lsb10_to_counts,
)
from .fault_config import FaultConfig, LineFault, MuxBankFault, ShortFault
from .ranges import FAULT_RATES, RANGES

FAULT_KINDS = ("dead", "half_dead", "stuck", "noisy", "short", "short_lines", "mux_bank", "outside")


def hill(pressure_kpa: np.ndarray | float, half_scale_kpa: float, exponent: float) -> np.ndarray:
    """Normalised film conductance u(P) = x/(1+x), x = (P/P½)^n; 0 at rest, → 1."""
    x = np.power(np.maximum(pressure_kpa, 0.0) / half_scale_kpa, exponent)
    return x / (1.0 + x)


def hill_inverse(u: np.ndarray, half_scale_kpa: float, exponent: float) -> np.ndarray:
    """Pressure in kPa for a normalised conductance u in [0, 1)."""
    u = np.clip(u, 0.0, 1.0 - 1e-12)
    return half_scale_kpa * np.power(u / (1.0 - u), 1.0 / exponent)


def tile_bounds(n: int, parts: int) -> list[tuple[int, int]]:
    """Start/stop of ``parts`` near-equal tiles along an axis of ``n`` lines."""
    edges = np.cumsum([0] + [len(a) for a in np.array_split(np.arange(n), parts)])
    return [(int(edges[i]), int(edges[i + 1])) for i in range(parts)]


@dataclass
class CarpetParams:
    """Per-carpet truth. Arrays are (rows, cols) float64 unless noted.

    Normalised conductance ``A`` is in units of ``crosstalk.g_full_s``; a sensel's
    reading is ``offset + sign · k_counts · tile_gain · A_apparent`` before the rails.
    """

    config: SensorConfig
    tile_index: np.ndarray  # int (rows, cols): tile number, row-major over the tile grid
    film_gain: np.ndarray  # product of sensel × row × col × smooth gains (clipped)
    sensel_gain: np.ndarray
    row_gain: np.ndarray  # (rows,)
    col_gain: np.ndarray  # (cols,)
    smooth_gain: np.ndarray
    tile_gain: np.ndarray  # front-end gain per sensel's tile
    offset_counts: np.ndarray  # front-end offset at the reference temperature, t = 0
    leak: np.ndarray  # normalised conductance of an unloaded sensel
    line_factor: np.ndarray  # 1 normal, 0 no current (dead, mux bank, outside), factor (half-dead)
    stuck_counts: np.ndarray  # float: the code a stuck sensel reads, NaN where not stuck
    extra_noise_counts: np.ndarray  # σ of extra noise (noisy lines), counts
    masks: dict[str, np.ndarray] = field(default_factory=dict)  # fault kind → (rows, cols) bool
    u_ref: float = 0.0  # u(P_sat)
    k_counts: float = 0.0  # counts per unit normalised conductance at tile gain 1

    @property
    def shape(self) -> tuple[int, int]:
        return self.film_gain.shape

    @property
    def full_scale(self) -> int:
        return self.config.frontend.full_scale

    @property
    def sign(self) -> int:
        return self.config.frontend.sign

    @property
    def rail_counts(self) -> int:
        """The code that pressure drives readings toward."""
        return self.full_scale if self.sign > 0 else 0

    @property
    def measurable(self) -> np.ndarray:
        """Sensels whose reading carries information about their pressure."""
        m = self.masks
        return ~(m["dead"] | m["stuck"] | m["short"] | m["mux_bank"] | m["outside"]) & (self.line_factor > 0)


@dataclass
class SessionParams:
    """Per-session truth."""

    config: SessionConfig
    index: int
    drift_counts_per_h: np.ndarray  # (rows, cols): board + tile drift
    offset_tempco_counts_per_c: float


@dataclass
class SensorParams:
    """Everything :func:`sim.sensor.inverse.true_pressure_estimate` needs."""

    carpet: CarpetParams
    session: SessionParams

    @property
    def config(self) -> SensorConfig:
        return self.carpet.config


def _tri(rng: np.random.Generator, name: str) -> float:
    lo, mode, hi = RANGES[name]
    return float(rng.triangular(lo, mode, hi)) if hi > lo else float(mode)


def _line_mask(shape: tuple[int, int], axis: str, index: int, start: int = 0, stop: int | None = None) -> np.ndarray:
    m = np.zeros(shape, bool)
    if axis == "row":
        if not 0 <= index < shape[0]:
            raise ValueError(f"row {index} outside a grid of {shape[0]} rows")
        m[index, start:stop] = True
    else:
        if not 0 <= index < shape[1]:
            raise ValueError(f"column {index} outside a grid of {shape[1]} columns")
        m[start:stop, index] = True
    return m


def draw_carpet(config: SensorConfig, rng: np.random.Generator) -> CarpetParams:
    """Realise the per-carpet arrays of ``config``."""
    g, gc, fe, rc = config.grid, config.gains, config.frontend, config.response
    shape = g.shape
    rows, cols = shape

    # tiles
    tile_index = np.zeros(shape, int)
    rb, cb = tile_bounds(rows, g.tiles[0]), tile_bounds(cols, g.tiles[1])
    n_tiles = len(rb) * len(cb)
    for i, (r0, r1) in enumerate(rb):
        for j, (c0, c1) in enumerate(cb):
            tile_index[r0:r1, c0:c1] = i * len(cb) + j

    # gains (median 1)
    sensel_gain = np.exp(gc.sensel_sigma * rng.standard_normal(shape))
    row_gain = np.exp(gc.row_sigma * rng.standard_normal(rows))
    col_gain = np.exp(gc.col_sigma * rng.standard_normal(cols))
    sigma_px = max(gc.smooth_length_mm / g.pitch_mm, 0.5)
    field_ = ndimage.gaussian_filter(rng.standard_normal(shape), sigma_px, mode="reflect")
    field_ -= field_.mean()
    peak = np.abs(field_).max()
    smooth_gain = 1.0 + gc.smooth_amplitude * (field_ / peak if peak > 0 else field_)
    film_gain = np.clip(sensel_gain * row_gain[:, None] * col_gain[None, :] * smooth_gain, *gc.clip)
    tile_gain = np.exp(gc.tile_sigma * rng.standard_normal(n_tiles))[tile_index]

    # front end
    fs = fe.full_scale
    mid = fe.mid_fraction * fs
    tile_off = rng.normal(0.0, lsb10_to_counts(fe.tile_offset_sigma_lsb10, fe.adc_bits), n_tiles)[tile_index]
    sensel_off = rng.normal(0.0, lsb10_to_counts(fe.sensel_offset_sigma_lsb10, fe.adc_bits), shape)
    offset_counts = mid + lsb10_to_counts(fe.global_offset_lsb10, fe.adc_bits) + tile_off + sensel_off
    span = (fs - mid) if fe.sign > 0 else mid
    u_ref = float(hill(rc.p_sat_kpa, rc.half_scale_kpa, rc.exponent))
    k_counts = span / u_ref
    # leakage: a fraction of full scale, expressed as normalised conductance
    leak = rc.leakage_fraction * fs / k_counts * rng.uniform(1 - rc.leakage_spread, 1 + rc.leakage_spread, shape)

    # faults
    fc = config.faults
    masks = {k: np.zeros(shape, bool) for k in FAULT_KINDS}
    line_factor = np.ones(shape)
    stuck_counts = np.full(shape, np.nan)
    extra_noise = np.zeros(shape)
    if fc.mask is not None:
        mask = np.asarray(fc.mask, bool)
        if mask.shape != shape:
            raise ValueError(f"faults.mask has shape {mask.shape}, grid is {shape}")
        masks["outside"] = ~mask
    for lf in fc.lines:
        m = _line_mask(shape, lf.axis, lf.index, lf.start, lf.stop)
        masks[lf.kind] |= m
        if lf.kind == "dead":
            line_factor[m] = 0.0
        elif lf.kind == "half_dead":
            line_factor[m] *= lf.factor
        elif lf.kind == "stuck":
            stuck_counts[m] = (fs if fe.sign > 0 else 0) if lf.level == "rail" else (0 if fe.sign > 0 else fs)
        elif lf.kind == "noisy":
            extra_noise[m] = np.hypot(extra_noise[m], lsb10_to_counts(lf.noise_lsb10, fe.adc_bits))
    for mb in fc.mux_banks:
        n = rows if mb.axis == "row" else cols
        if not (0 <= mb.start and mb.start + mb.size <= n):
            raise ValueError(f"mux bank {mb} outside a grid of {n} lines")
        for i in range(mb.start, mb.start + mb.size):
            masks["mux_bank"] |= _line_mask(shape, mb.axis, i)
    for sh in fc.shorts:
        if not (0 <= sh.row < rows and 0 <= sh.col < cols):
            raise ValueError(f"short {sh} outside the grid")
        masks["short"][sh.row, sh.col] = True
        masks["short_lines"][sh.row, :] = True
        masks["short_lines"][:, sh.col] = True
    line_factor[masks["mux_bank"] | masks["outside"]] = 0.0

    return CarpetParams(
        config=config, tile_index=tile_index, film_gain=film_gain, sensel_gain=sensel_gain,
        row_gain=row_gain, col_gain=col_gain, smooth_gain=smooth_gain, tile_gain=tile_gain,
        offset_counts=offset_counts, leak=leak, line_factor=line_factor, stuck_counts=stuck_counts,
        extra_noise_counts=extra_noise, masks=masks, u_ref=u_ref, k_counts=k_counts,
    )


def draw_session(config: SensorConfig, session: SessionConfig, index: int, tile_index: np.ndarray,
                 rng: np.random.Generator) -> SessionParams:
    """Realise a session: per-tile baseline drift rates."""
    bits = config.frontend.adc_bits
    n_tiles = int(tile_index.max()) + 1
    tile_drift = rng.normal(0.0, 1.0, n_tiles) * session.tile_drift_sigma_lsb10_per_h
    drift = lsb10_to_counts(1.0, bits) * (session.drift_lsb10_per_h + tile_drift[tile_index])
    return SessionParams(config=session, index=index, drift_counts_per_h=drift,
                         offset_tempco_counts_per_c=lsb10_to_counts(session.offset_tempco_lsb10_per_c, bits))


def random_session_config(rng: np.random.Generator, rug: bool = False) -> SessionConfig:
    """A session drawn from the note's ranges (temperature, slope, drift; rug if asked)."""
    return SessionConfig(
        temperature_c=_tri(rng, "temperature_c"),
        temperature_slope_c_per_h=float(rng.normal(0.0, 1.5)),
        drift_lsb10_per_h=float(rng.normal(0.0, 2.0)),
        tile_drift_sigma_lsb10_per_h=float(rng.uniform(0.0, 1.0)),
        offset_tempco_lsb10_per_c=float(rng.uniform(0.1, 0.5)),
        rug_sigma_mm=_tri(rng, "rug_sigma_mm") if rug else 0.0,
    )


def random_faults(rng: np.random.Generator, shape: tuple[int, int], rates: dict[str, float]) -> FaultConfig:
    """Each fault kind present with probability ``rates[kind]`` (one instance)."""
    rows, cols = shape
    lines: list[LineFault] = []
    shorts: list[ShortFault] = []
    banks: list[MuxBankFault] = []
    mask = None

    def pick_line() -> tuple[str, int]:
        axis = "row" if rng.random() < 0.5 else "col"
        return axis, int(rng.integers(rows if axis == "row" else cols))

    for kind in ("dead", "half_dead", "stuck", "noisy"):
        if rng.random() < rates.get(kind, 0.0):
            axis, idx = pick_line()
            n = cols if axis == "row" else rows
            start = int(rng.integers(n // 2)) if (kind == "dead" and rng.random() < 0.3) else 0  # broken part-way
            lines.append(LineFault(kind, axis, idx, factor=float(rng.uniform(0.1, 0.5)),
                                   noise_lsb10=float(rng.uniform(6, 25)), start=start))
    if rng.random() < rates.get("short", 0.0):
        shorts.append(ShortFault(int(rng.integers(rows)), int(rng.integers(cols))))
    if rng.random() < rates.get("mux_bank", 0.0):
        axis = "row" if rng.random() < 0.5 else "col"
        n = rows if axis == "row" else cols
        size = int(rng.choice([8, 16])) if n >= 16 else 8
        banks.append(MuxBankFault(axis, size * int(rng.integers(n // size)), size))
    if rng.random() < rates.get("mask", 0.0):  # a corner cut away: an L-shaped carpet
        mask = np.ones(shape, bool)
        h, w = rows // 3, cols // 3
        r0 = 0 if rng.random() < 0.5 else rows - h
        c0 = 0 if rng.random() < 0.5 else cols - w
        mask[r0:r0 + h, c0:c0 + w] = False
    return FaultConfig(lines=tuple(lines), shorts=tuple(shorts), mux_banks=tuple(banks), mask=mask)


def random_config(rng: np.random.Generator, grid: GridConfig, *, adc_bits: int | None = None,
                  sign: int | None = None, faults: bool | FaultConfig = True,
                  fault_rates: dict[str, float] | None = None, readout: str = "zero_potential") -> SensorConfig:
    """A carpet configuration drawn from the note's ranges (triangular around the defaults)."""
    t = lambda name: _tri(rng, name)  # noqa: E731
    response = ResponseConfig(half_scale_kpa=t("half_scale_kpa"), exponent=t("exponent"),
                              p_sat_kpa=t("p_sat_kpa"), leakage_fraction=t("leakage_fraction"))
    gains = GainConfig(sensel_sigma=t("sensel_sigma"), row_sigma=t("row_sigma"), col_sigma=t("col_sigma"),
                       smooth_amplitude=t("smooth_amplitude"), smooth_length_mm=t("smooth_length_mm"),
                       tile_sigma=t("tile_sigma"))
    frontend = FrontEndConfig(
        adc_bits=int(rng.choice([10, 12])) if adc_bits is None else adc_bits,
        sign=int(rng.choice([1, -1])) if sign is None else sign,
        global_offset_lsb10=t("global_offset_lsb10"),
    )
    dynamics = DynamicsConfig(hysteresis=t("hysteresis"), creep_per_decade=t("creep_per_decade"),
                              temp_gain_per_c=t("temp_gain_per_c"))
    crosstalk = CrosstalkConfig(line_resistance_ohm=t("line_resistance_ohm"), readout=readout)
    noise = NoiseConfig(white_lsb10=t("white_lsb10"), row_lsb10=t("row_lsb10"), smear_fraction=t("smear_fraction"))
    if isinstance(faults, FaultConfig):
        fault_cfg = faults
    elif faults:
        fault_cfg = random_faults(rng, grid.shape, {**FAULT_RATES, **(fault_rates or {})})
    else:
        fault_cfg = FaultConfig()
    return SensorConfig(grid=grid, response=response, gains=gains, frontend=frontend, dynamics=dynamics,
                        crosstalk=crosstalk, noise=noise, faults=fault_cfg)


__all__ = [
    "CarpetParams", "SessionParams", "SensorParams", "FAULT_KINDS", "hill", "hill_inverse", "tile_bounds",
    "draw_carpet", "draw_session", "random_config", "random_faults", "random_session_config",
]

"""Configuration of the carpet sensor model: every parameter, in physical units.

Each field documents its unit, its default and the range the randomiser draws from.
Sources: ``shared/notes/sensor-and-calibration.md`` (called "the note" below) unless
marked (est.) — an estimate of ours that nobody has checked on hardware.

Unit conventions:
- pressure in kPa, lengths in mm, time in s, temperature in °C, resistance in Ω,
  conductance in S;
- noise and offsets in ``lsb10``: counts referred to a 10-bit ADC (the note quotes its
  numbers at 10 bit). At ``adc_bits`` b they scale by ``2**(b-10)``, so a parameter
  means the same analogue voltage at every bit depth.

The configuration is split into the three randomisation levels of the note:
per carpet (:class:`GridConfig`, :class:`ResponseConfig`, :class:`GainConfig`,
:class:`FrontEndConfig`, :class:`DynamicsConfig`, :class:`CrosstalkConfig`,
:class:`NoiseConfig`, and :class:`FaultConfig` from ``fault_config``), per session
(:class:`SessionConfig`) and per frame (noise draws, and :class:`StreamConfig` for the
frame stream). The ranges a random carpet is drawn from live in ``ranges``.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from typing import Literal

from .fault_config import FaultConfig

ADC_BITS = (8, 10, 12, 16)


def lsb10_to_counts(value_lsb10: float, adc_bits: int) -> float:
    """Convert a level given in 10-bit counts to counts at ``adc_bits``."""
    return float(value_lsb10) * 2.0 ** (adc_bits - 10)


@dataclass(frozen=True)
class GridConfig:
    """Geometry of the carpet."""

    rows: int = 96
    """sensel rows (y). 96 default; 48 and 32 also supported."""
    cols: int = 96
    """sensel columns (x)."""
    pitch_mm: float = 19.05
    """thread spacing in mm (design.md: 96 × 19.05 mm = 1.83 m)."""
    tiles: tuple[int, int] = (3, 3)
    """tiles (rows, cols); each has its own readout (offset, gain). 3×3 of 32×32 at
    96×96; at other grids the same 3×3 layout with boundaries from ``np.array_split``
    (48×48 → 16×16 tiles; 32×32 → 11/11/10)."""
    rate_hz: float = 14.0
    """frame rate (design.md)."""

    def __post_init__(self) -> None:
        if self.rows < 2 or self.cols < 2:
            raise ValueError(f"grid must be at least 2×2, got {self.rows}×{self.cols}")
        if self.pitch_mm <= 0:
            raise ValueError(f"pitch_mm must be > 0, got {self.pitch_mm}")
        tr, tc = self.tiles
        if not (1 <= tr <= self.rows and 1 <= tc <= self.cols):
            raise ValueError(f"tiles {self.tiles} do not fit a {self.rows}×{self.cols} grid")

    @property
    def shape(self) -> tuple[int, int]:
        return (self.rows, self.cols)


@dataclass(frozen=True)
class ResponseConfig:
    """Per-sensel response: normalised conductance u(P) = x/(1+x), x = (P/P½)^n (Hill)."""

    half_scale_kpa: float = 8.0
    """P½, pressure at half of the film's conductance range. Note: 8 kPa (5–15)."""
    exponent: float = 1.2
    """Hill exponent n. Note: 1.2 (0.9–1.5)."""
    p_sat_kpa: float = 14.0
    """Pressure that drives a nominal-gain sensel exactly to the rail: the front-end
    gain is set so that u(P_sat) spans baseline → rail. Note: the carpet's ~14 kPa
    ceiling; (est.) range 10–20."""
    leakage_fraction: float = 0.002
    """reading of an unloaded sensel's own conductance, as a fraction of the ADC full
    scale (≈ 2 counts at 10 bit, so an empty 10-bit sensel reads ≈ 513). Note: ≈ 0.2 %
    of full scale; (est.) range 0–0.005."""
    leakage_spread: float = 0.5
    """(est.) relative per-sensel spread of the leakage (uniform ±)."""

    def __post_init__(self) -> None:
        if self.half_scale_kpa <= 0 or self.exponent <= 0 or self.p_sat_kpa <= 0:
            raise ValueError("half_scale_kpa, exponent and p_sat_kpa must be > 0")
        if not 0 <= self.leakage_spread < 1:
            raise ValueError("leakage_spread must be in [0, 1)")


@dataclass(frozen=True)
class GainConfig:
    """Multiplicative gain of each sensel's conductance (median 1)."""

    sensel_sigma: float = 0.15
    """per-sensel lognormal σ. Note: 0.15 (0.05–0.30)."""
    row_sigma: float = 0.05
    """per-row lognormal σ. Note: 0.05 (est. range 0–0.10)."""
    col_sigma: float = 0.05
    """per-column lognormal σ. Note: 0.05 (est. range 0–0.10)."""
    smooth_amplitude: float = 0.15
    """peak relative amplitude of a smooth gain field. Note: ±10–20 %."""
    smooth_length_mm: float = 450.0
    """(est.) correlation length of the smooth field (Gaussian σ), 200–800 mm."""
    tile_sigma: float = 0.05
    """(est.) lognormal σ of each tile's front-end gain, 0–0.10."""
    clip: tuple[float, float] = (0.3, 3.0)
    """(est.) the product of the film gains is clipped to this range."""


@dataclass(frozen=True)
class FrontEndConfig:
    """Transimpedance front end and ADC."""

    adc_bits: int = 10
    """ADC resolution, one of 8/10/12/16 (device INFO)."""
    sign: int = 1
    """+1: pressure drives readings up toward full scale; −1: toward 0 (device INFO)."""
    mid_fraction: float = 0.5
    """front-end offset (unloaded reading, before leakage) as a fraction of full scale.
    Note: unloaded sensels read near mid-scale."""
    global_offset_lsb10: float = 0.0
    """offset of the whole board from mid-scale. Note: baselines 500–560 at 10 bit →
    randomised in −12…+48."""
    tile_offset_sigma_lsb10: float = 6.0
    """(est.) σ of each tile's offset."""
    sensel_offset_sigma_lsb10: float = 2.0
    """(est.) σ of each sensel's offset (channel mismatch)."""
    amp_headroom_fraction: float = 0.02
    """(est.) how far beyond the ADC range the amplifier can swing before it clips, as a
    fraction of full scale: a saturated sensel reads exactly the rail code despite noise
    and smear."""

    def __post_init__(self) -> None:
        if self.adc_bits not in ADC_BITS:
            raise ValueError(f"adc_bits must be one of {ADC_BITS}, got {self.adc_bits}")
        if self.sign not in (1, -1):
            raise ValueError(f"sign must be +1 or -1, got {self.sign}")
        if not 0.2 <= self.mid_fraction <= 0.8:
            raise ValueError(f"mid_fraction must be in [0.2, 0.8], got {self.mid_fraction}")

    @property
    def full_scale(self) -> int:
        return (1 << self.adc_bits) - 1


@dataclass(frozen=True)
class DynamicsConfig:
    """Time-dependent behaviour of the film (stateful)."""

    hysteresis: float = 0.05
    """largest gap between the unloading and loading branches, as a fraction of the
    response at the recent peak. Note: ≤ 10 %."""
    hysteresis_tau_s: float = 10.0
    """(est.) relaxation time of the remembered peak."""
    creep_per_decade: float = 0.03
    """relative rise of conductance per decade of time under load. Note: < 5 %/decade."""
    creep_tau0_s: float = 1.0
    """(est.) time origin of the log law: factor = 1 + c·log10(1 + age/τ0)."""
    creep_threshold_kpa: float = 0.5
    """(est.) a sensel above this pressure counts as loaded for creep."""
    creep_recovery_tau_s: float = 10.0
    """(est.) unloaded, the load age decays with this time constant."""
    temp_gain_per_c: float = 0.0025
    """relative conductance change per °C. Note: ≈ +0.25 %/°C."""
    reference_temperature_c: float = 22.0
    """(est.) temperature at which the gains above hold."""

    def __post_init__(self) -> None:
        if not 0 <= self.hysteresis < 0.25:
            raise ValueError(f"hysteresis must be in [0, 0.25), got {self.hysteresis}")
        if self.creep_per_decade < 0:
            raise ValueError("creep_per_decade must be >= 0")


@dataclass(frozen=True)
class CrosstalkConfig:
    """Passive-matrix crosstalk.

    ``zero_potential`` readout: line loading G_app = G / ((1 + R·ΣG_col)(1 + R·ΣG_row)).
    ``floating`` readout: additionally ghosts through three-sensel paths (fourth
    corner of a rectangle of presses), then line loading.
    """

    line_resistance_ohm: float = 100.0
    """R, switch + thread resistance per line. Note: 20–500 Ω (~100 Ω typical)."""
    g_full_s: float = 1e-4
    """(est.) conductance of a nominal sensel at u = 1 (10 kΩ). With R = 100 Ω a line
    carrying ~20 loaded sensels reads ~20 % low (note: 10–30 % on heavily loaded lines)."""
    readout: Literal["zero_potential", "floating"] = "zero_potential"
    ghost_strength: float = 1.0
    """floating readout only: scale of the ghost conductance (1 = the series conductance
    of the lumped three-stage path network, see ``model.ghosts``). Three single equal
    presses give a ghost of 1/3 of a press; blocks of presses (feet) give ghosts as
    strong as real presses or stronger (the note: 76 % in a 16×16 simulation)."""

    def __post_init__(self) -> None:
        if self.line_resistance_ohm < 0 or self.g_full_s <= 0:
            raise ValueError("line_resistance_ohm must be >= 0 and g_full_s > 0")
        if self.readout not in ("zero_potential", "floating"):
            raise ValueError(f"readout must be 'zero_potential' or 'floating', got {self.readout!r}")


@dataclass(frozen=True)
class NoiseConfig:
    """Per-frame noise and multiplexer smear."""

    white_lsb10: float = 1.5
    """σ of per-sample white noise. Note: ≈ 1.5 counts at 10 bit."""
    row_lsb10: float = 0.7
    """σ of a per-row, per-frame common offset. Note: ≈ 0.7 counts at 10 bit."""
    smear_fraction: float = 0.02
    """fraction of the previous sample (scan order: row-major, columns fastest) left on
    the sampling capacitor: out_i = (1−s)·v_i + s·v_{i−1}. Note: ≈ 2 %."""

    def __post_init__(self) -> None:
        if not 0 <= self.smear_fraction < 0.5:
            raise ValueError("smear_fraction must be in [0, 0.5)")


@dataclass(frozen=True)
class SessionConfig:
    """What changes from one session (one laying of the carpet / one recording) to the next."""

    temperature_c: float = 22.0
    """temperature at t = 0. (est.) randomised 15–30 °C."""
    temperature_slope_c_per_h: float = 0.0
    """linear temperature change. (est.) randomised N(0, 1.5 °C/h)."""
    drift_lsb10_per_h: float = 0.0
    """board-wide baseline drift. (est.) randomised N(0, 2)."""
    tile_drift_sigma_lsb10_per_h: float = 0.0
    """(est.) per-tile spread of the drift; randomised 0–1."""
    offset_tempco_lsb10_per_c: float = 0.3
    """(est.) baseline change per °C away from the reference temperature (toward +counts)."""
    rug_sigma_mm: float = 0.0
    """Gaussian blur of the input pressure by the rug. Note: σ ≈ 5 mm (0–15). Off by
    default: the contact-physics stage already spreads pressure by the rug."""


@dataclass(frozen=True)
class StreamConfig:
    """Frame-stream faults (per frame, random). Rates are per produced frame."""

    drop_rate: float = 0.0
    """(est.) probability a frame is lost; randomised 0–1 %."""
    duplicate_rate: float = 0.0
    """(est.) probability a frame is sent twice (same counts, same timestamp)."""
    tear_rate: float = 0.0
    """(est.) probability a frame is torn: rows shifted or rows from the previous frame."""
    tear_shift_fraction: float = 0.5
    """of torn frames, the fraction that are row-shifted (the rest are partly old)."""
    corrupt_rate: float = 0.0
    """(est.) probability a frame is garbage: constant, or (below 16 bit) out of range."""
    jitter_s: float = 0.002
    """σ of timestamp jitter, clipped to ±0.45 frame periods so time stays monotonic."""

    def __post_init__(self) -> None:
        for name in ("drop_rate", "duplicate_rate", "tear_rate", "corrupt_rate", "tear_shift_fraction"):
            v = getattr(self, name)
            if not 0 <= v <= 1:
                raise ValueError(f"{name} must be in [0, 1], got {v}")
        if self.drop_rate + self.duplicate_rate + self.tear_rate + self.corrupt_rate > 1:
            raise ValueError("stream fault rates sum to more than 1")
        if self.jitter_s < 0:
            raise ValueError("jitter_s must be >= 0")


@dataclass(frozen=True)
class SensorConfig:
    """Everything the sensor model needs, per carpet, plus the default session."""

    grid: GridConfig = GridConfig()
    response: ResponseConfig = ResponseConfig()
    gains: GainConfig = GainConfig()
    frontend: FrontEndConfig = FrontEndConfig()
    dynamics: DynamicsConfig = DynamicsConfig()
    crosstalk: CrosstalkConfig = CrosstalkConfig()
    noise: NoiseConfig = NoiseConfig()
    faults: FaultConfig = FaultConfig()
    session: SessionConfig = SessionConfig()

    @classmethod
    def for_grid(cls, rows: int = 96, cols: int | None = None, **grid_kw) -> "SensorConfig":
        """Default configuration on another grid (pitch and tiles from ``grid_kw``)."""
        return cls(grid=GridConfig(rows=rows, cols=rows if cols is None else cols, **grid_kw))

    def ideal(self) -> "SensorConfig":
        """The same carpet with noise, smear, hysteresis, creep and drift switched off
        (gains, curve, crosstalk and faults kept): the deterministic core of the model."""
        return replace(
            self,
            noise=replace(self.noise, white_lsb10=0.0, row_lsb10=0.0, smear_fraction=0.0),
            dynamics=replace(self.dynamics, hysteresis=0.0, creep_per_decade=0.0),
            session=replace(self.session, temperature_slope_c_per_h=0.0, drift_lsb10_per_h=0.0,
                            tile_drift_sigma_lsb10_per_h=0.0),
        )

"""The carpet's hardware faults, as configuration: broken or noisy lines, shorted
crossings, dead multiplexer banks and the mask of sensels that exist (:class:`FaultConfig`,
part of :class:`~sim.sensor.config.SensorConfig`). ``params.draw_carpet`` turns them into
per-sensel arrays; ``params.random_faults`` draws them at ``ranges.FAULT_RATES``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Literal

import numpy as np

LineAxis = Literal["row", "col"]


@dataclass(frozen=True)
class LineFault:
    """A fault on one row or column line.

    kind:
      - ``dead``: open thread; the affected sensels carry no current (read the bare
        offset, invisible on an empty carpet).
      - ``half_dead``: a high-resistance thread; conductance × ``factor``.
      - ``stuck``: the line's channel reads the pressure rail (``level='rail'``) or the
        opposite rail (``level='low'``) whatever the load.
      - ``noisy``: extra white noise of σ ``noise_lsb10``.
    ``start``/``stop`` (inclusive/exclusive, along the line) limit the fault to part of
    the line, e.g. a thread broken at ``start`` is ``dead`` from ``start`` to the end.
    """

    kind: Literal["dead", "half_dead", "stuck", "noisy"]
    axis: LineAxis
    index: int
    factor: float = 0.25
    noise_lsb10: float = 12.0
    level: Literal["rail", "low"] = "rail"
    start: int = 0
    stop: int | None = None

    def __post_init__(self) -> None:
        if self.kind not in ("dead", "half_dead", "stuck", "noisy"):
            raise ValueError(f"unknown line fault kind {self.kind!r}")
        if self.axis not in ("row", "col"):
            raise ValueError(f"axis must be 'row' or 'col', got {self.axis!r}")
        if not 0 <= self.factor <= 1:
            raise ValueError("factor must be in [0, 1]")


@dataclass(frozen=True)
class ShortFault:
    """Row ``row`` and column ``col`` shorted at their crossing.

    The crossing reads the pressure rail; the two lines become one electrical node, so
    their line loads are shared (pressure anywhere on one depresses readings on the
    other); the short itself adds a load of ``g_short_s``.
    """

    row: int
    col: int
    g_short_s: float = 2e-4


@dataclass(frozen=True)
class MuxBankFault:
    """A dead multiplexer bank: ``size`` adjacent lines from ``start`` (8 or 16) carry no
    current (columns are read through the column mux, rows driven through the row mux)."""

    axis: LineAxis
    start: int
    size: int = 16

    def __post_init__(self) -> None:
        if self.size < 1:
            raise ValueError("size must be >= 1")


@dataclass(frozen=True)
class FaultConfig:
    """The carpet's hardware faults, explicit. ``mask`` (rows, cols) bool marks the
    sensels that exist (a non-rectangular carpet); ``None`` = all."""

    lines: tuple[LineFault, ...] = ()
    shorts: tuple[ShortFault, ...] = ()
    mux_banks: tuple[MuxBankFault, ...] = ()
    mask: np.ndarray | None = field(default=None, compare=False)

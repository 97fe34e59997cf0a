"""Wiring maps: where each sample of the wire's (row, col) grid lies on the carpet.

Boards differ in how their threads are wired: rows scanned bottom to top, columns
mirrored, odd and even lines swapped (some MIT readouts do this), or 3×3 tiles of
32×32 sent one tile after another. A :class:`WiringMap` is one integer array,
``source_index`` (H, W): carpet sensel (r, c) takes the wire sample with flat index
``source_index[r, c]``. Applying it is a single ``take``.

Configuration keys (all optional; unknown keys are a ValueError listing these):

- ``flip_rows`` / ``flip_cols`` (bool): mirror the wire grid.
- ``transpose`` (bool): wire rows are carpet columns.
- ``swap_odd_even_rows`` / ``swap_odd_even_cols`` (bool): exchange lines 2k and 2k+1.
- ``tiles``: a list of tiles, each ``{wire = [r0, c0], carpet = [r0, c0], size = [h, w],
  rot90 = k, flip_cols = bool}``: the h×w block at wire (r0, c0), rotated k quarter turns
  counter-clockwise then mirrored if asked, lands at carpet (r0, c0). Tiles must use
  every wire sample once and leave no hole; the carpet's shape is their extent.

The line operations apply in the order listed, after the tiles.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

KEYS = ("flip_rows", "flip_cols", "transpose", "swap_odd_even_rows", "swap_odd_even_cols", "tiles")
TILE_KEYS = ("wire", "carpet", "size", "rot90", "flip_cols")


def _swap_pairs(n: int) -> np.ndarray:
    idx = np.arange(n)
    even = np.arange(0, n - n % 2, 2)
    idx[even], idx[even + 1] = even + 1, even
    return idx


@dataclass(frozen=True)
class WiringMap:
    """``source_index`` (H, W) int: carpet sensel → flat wire index. Wire grid is (wire_rows, wire_cols)."""

    source_index: np.ndarray
    wire_rows: int
    wire_cols: int

    @property
    def shape(self) -> tuple[int, int]:
        return self.source_index.shape

    @classmethod
    def identity(cls, rows: int, cols: int) -> "WiringMap":
        return cls(np.arange(rows * cols).reshape(rows, cols), rows, cols)

    @classmethod
    def from_config(cls, config: dict[str, Any] | None, wire_rows: int, wire_cols: int) -> "WiringMap":
        config = dict(config or {})
        unknown = sorted(set(config) - set(KEYS))
        if unknown:
            raise ValueError(f"wiring: unknown key(s) {unknown}; accepted: {list(KEYS)}")
        grid = np.arange(wire_rows * wire_cols).reshape(wire_rows, wire_cols)
        if config.get("tiles"):
            grid = _place_tiles(grid, config["tiles"])
        if config.get("flip_rows"):
            grid = grid[::-1]
        if config.get("flip_cols"):
            grid = grid[:, ::-1]
        if config.get("transpose"):
            grid = grid.T
        if config.get("swap_odd_even_rows"):
            grid = grid[_swap_pairs(grid.shape[0])]
        if config.get("swap_odd_even_cols"):
            grid = grid[:, _swap_pairs(grid.shape[1])]
        return cls(np.ascontiguousarray(grid), wire_rows, wire_cols)

    def apply(self, wire: np.ndarray) -> np.ndarray:
        """(wire_rows, wire_cols) → (H, W) carpet orientation."""
        if wire.shape != (self.wire_rows, self.wire_cols):
            raise ValueError(f"wiring map expects a {self.wire_rows}×{self.wire_cols} frame, got {wire.shape}")
        return wire.reshape(-1).take(self.source_index)


def _place_tiles(grid: np.ndarray, tiles: list[dict[str, Any]]) -> np.ndarray:
    placed = []
    for i, tile in enumerate(tiles):
        unknown = sorted(set(tile) - set(TILE_KEYS))
        if unknown:
            raise ValueError(f"wiring.tiles[{i}]: unknown key(s) {unknown}; accepted: {list(TILE_KEYS)}")
        try:
            (wr, wc), (cr, cc), (h, w) = tile["wire"], tile["carpet"], tile["size"]
        except (KeyError, TypeError, ValueError):
            raise ValueError(f"wiring.tiles[{i}] needs wire = [r, c], carpet = [r, c], size = [h, w]") from None
        block = grid[wr : wr + h, wc : wc + w] if wr >= 0 and wc >= 0 else grid[:0, :0]
        if block.shape != (h, w):
            raise ValueError(f"wiring.tiles[{i}]: wire block at {[wr, wc]} of size {[h, w]} leaves the {grid.shape} wire grid")
        if cr < 0 or cc < 0:
            raise ValueError(f"wiring.tiles[{i}]: carpet position {[cr, cc]} is negative")
        block = np.rot90(block, int(tile.get("rot90", 0)))
        if tile.get("flip_cols"):
            block = block[:, ::-1]
        placed.append((i, cr, cc, block))
    height = max(cr + b.shape[0] for _, cr, _, b in placed)
    width = max(cc + b.shape[1] for _, _, cc, b in placed)
    out = np.full((height, width), -1, dtype=np.int64)
    for i, cr, cc, block in placed:
        bh, bw = block.shape
        if (out[cr : cr + bh, cc : cc + bw] >= 0).any():
            raise ValueError(f"wiring.tiles[{i}] overlaps another tile on the carpet")
        out[cr : cr + bh, cc : cc + bw] = block
    if (out < 0).any():
        raise ValueError(f"wiring.tiles leave {(out < 0).sum()} of the {height}×{width} carpet sensels uncovered")
    if out.size != grid.size:
        raise ValueError(f"wiring.tiles use {out.size} of the {grid.size} wire samples; every sample must land once")
    return out

"""Loaders for the Intelligent Carpet release (Luo et al., CVPR 2021).

A recording folder holds, per 32×32 tile, ``touch<k>.hdf5`` with datasets
``frame_count`` (frames actually written; the arrays may be pre-allocated longer),
``ts`` (n,) seconds and ``pressure`` (n, 32, 32) raw ADC readings; and
``touch_aligned.p``, a pickle of the 96×96 frames already assembled (an array
(n, 96, 96), optionally with timestamps as a tuple ``(ts, frames)`` or a dict with
``ts`` and ``pressure``). Readings are raw counts, not kPa.

Tiles are recorded by separate readers with their own clocks: :func:`load_tiles`
puts them on one time base (the first tile's timestamps, or a regular clock at
``rate_hz``) by nearest timestamp, and reports how far apart the matched frames were.
The 3×3 placement of the tiles is a :class:`TileLayout` (default row-major, no
rotation); the release's ``tile_pos.p`` may be turned into one.

Needs ``h5py`` (``pip install -e '.[data]'``).
"""

from __future__ import annotations

import pickle
import re
from dataclasses import dataclass
from pathlib import Path

import numpy as np


class RecordingError(Exception):
    """A recording that is missing files or holds something unexpected."""


@dataclass(frozen=True)
class TileLayout:
    """Where tile k lands: ``cells[k] = (tile_row, tile_col, rot90)`` on a grid of tiles."""

    cells: tuple[tuple[int, int, int], ...]
    tile_rows: int = 32
    tile_cols: int = 32

    @classmethod
    def row_major(cls, n_rows: int = 3, n_cols: int = 3, tile: int = 32) -> "TileLayout":
        return cls(tuple((k // n_cols, k % n_cols, 0) for k in range(n_rows * n_cols)), tile, tile)

    @property
    def shape(self) -> tuple[int, int]:
        return (1 + max(r for r, _, _ in self.cells)) * self.tile_rows, (1 + max(c for _, c, _ in self.cells)) * self.tile_cols

    def assemble(self, tiles: list[np.ndarray]) -> np.ndarray:
        """(n, 32, 32) per tile → (n, H, W)."""
        if len(tiles) != len(self.cells):
            raise RecordingError(f"the layout has {len(self.cells)} tiles, the recording {len(tiles)}")
        n = len(tiles[0])
        for k, tile in enumerate(tiles):
            if tile.shape[1:] != (self.tile_rows, self.tile_cols):
                raise RecordingError(f"tile {k} is {tile.shape[1:]}, the layout expects {(self.tile_rows, self.tile_cols)}")
        out = np.zeros((n, *self.shape), dtype=tiles[0].dtype)
        for (r, c, rot), tile in zip(self.cells, tiles):
            rows = slice(r * self.tile_rows, (r + 1) * self.tile_rows)
            cols = slice(c * self.tile_cols, (c + 1) * self.tile_cols)
            out[:, rows, cols] = np.rot90(tile, rot, axes=(1, 2))
        return out


@dataclass
class TactileRecording:
    """Frames of raw counts on one time base."""

    frames: np.ndarray  # (n, H, W) raw counts
    t_s: np.ndarray  # (n,) seconds, as recorded
    max_skew_s: float = 0.0  # largest time gap between tiles matched into one frame


def _tile_index(path: Path) -> int:
    m = re.fullmatch(r"touch(\d+)\.hdf5", path.name)
    return int(m.group(1)) if m else -1


def read_tile(path: str | Path) -> tuple[np.ndarray, np.ndarray]:
    """One ``touch<k>.hdf5``: (ts (n,), pressure (n, h, w)) trimmed to ``frame_count``."""
    import h5py

    path = Path(path)
    try:
        with h5py.File(path, "r") as f:
            missing = [k for k in ("frame_count", "ts", "pressure") if k not in f]
            if missing:
                raise RecordingError(f"{path}: no dataset {missing} (expected frame_count, ts, pressure)")
            n = int(np.asarray(f["frame_count"]).reshape(-1)[0])
            ts = np.asarray(f["ts"][:n], dtype=np.float64).reshape(-1)
            pressure = np.asarray(f["pressure"][:n])
    except OSError as exc:
        raise RecordingError(f"{path}: not a readable HDF5 file ({exc})") from None
    if pressure.ndim != 3 or len(ts) != len(pressure) or len(ts) != n:
        raise RecordingError(f"{path}: frame_count {n}, ts {ts.shape}, pressure {pressure.shape} do not agree")
    if n and np.any(np.diff(ts) < 0):
        raise RecordingError(f"{path}: timestamps go backwards")
    return ts, pressure


def load_tiles(folder: str | Path, layout: TileLayout | None = None, rate_hz: float | None = None,
               max_skew_s: float = 0.05) -> TactileRecording:
    """Assemble the per-tile files of a recording folder into whole frames.

    Each output time takes every tile's nearest frame; output times where some tile's
    nearest frame is further than ``max_skew_s`` away are left out.
    """
    folder = Path(folder)
    paths = sorted((p for p in folder.glob("touch*.hdf5") if _tile_index(p) >= 0), key=_tile_index)
    if not paths:
        raise RecordingError(f"{folder}: no touch<k>.hdf5 tile files")
    tiles = [read_tile(p) for p in paths]
    if layout is None:  # the release's 3×3 carpet, row-major, tile size from the files
        n_rows = 3 if len(paths) == 9 else 1
        h, w = tiles[0][1].shape[1:]
        layout = TileLayout(TileLayout.row_major(n_rows, len(paths) // n_rows).cells, h, w)
    start = max(ts[0] for ts, _ in tiles if len(ts))
    stop = min(ts[-1] for ts, _ in tiles if len(ts))
    if not stop > start:
        raise RecordingError(f"{folder}: the tiles' recordings do not overlap in time")
    ref = tiles[0][0]
    t = np.arange(start, stop, 1.0 / rate_hz) if rate_hz else ref[(ref >= start) & (ref <= stop)]
    picked, skew = [], np.zeros(len(t))
    for ts, pressure in tiles:
        j = np.clip(np.searchsorted(ts, t), 1, len(ts) - 1)
        j -= (t - ts[j - 1]) < (ts[j] - t)  # nearest neighbour
        skew = np.maximum(skew, np.abs(ts[j] - t))
        picked.append(pressure[j])
    keep = skew <= max_skew_s
    frames = layout.assemble([p[keep] for p in picked])
    return TactileRecording(frames, t[keep], float(skew[keep].max()) if keep.any() else 0.0)


def load_aligned(path: str | Path, rate_hz: float = 14.0) -> TactileRecording:
    """``touch_aligned.p``: the assembled frames (timestamps made up at ``rate_hz`` if absent)."""
    path = Path(path)
    try:
        with open(path, "rb") as fh:
            obj = pickle.load(fh, encoding="latin1")
    except (OSError, pickle.UnpicklingError, EOFError) as exc:
        raise RecordingError(f"{path}: not a readable pickle ({exc})") from None
    ts = None
    if isinstance(obj, dict):
        key = next((k for k in ("pressure", "touch", "frames", "data") if k in obj), None)
        if key is None:
            raise RecordingError(f"{path}: a dict without pressure/touch/frames/data; keys: {sorted(obj)}")
        frames, ts = obj[key], obj.get("ts")
    elif isinstance(obj, (tuple, list)) and len(obj) == 2:
        ts, frames = obj
    else:
        frames = obj
    frames = np.asarray(frames)
    if frames.ndim != 3:
        raise RecordingError(f"{path}: expected frames (n, H, W), got shape {frames.shape}")
    ts = np.arange(len(frames)) / rate_hz if ts is None else np.asarray(ts, np.float64).reshape(-1)
    if len(ts) != len(frames):
        raise RecordingError(f"{path}: {len(ts)} timestamps for {len(frames)} frames")
    return TactileRecording(frames, ts)

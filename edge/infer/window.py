"""A per-track ring buffer of encoder features, giving the head its causal window.

    win = FeatureWindow(bundle.window, bundle.features)
    win.push(bundle.encode(x)[0])            # once per new frame of this track
    out = bundle.head(win.window(), origin)  # (1,T,F): the last T features, oldest first

A new track's history is its first frame's features repeated (what training does for windows
that start before a track's first frame), so the head can run from the first frame on.
"""

from __future__ import annotations

import numpy as np


class FeatureWindow:
    def __init__(self, window: int, features: int):
        self.t, self.f = int(window), int(features)
        self._buf = np.zeros((2 * self.t, self.f), np.float32)  # doubled: every window is one contiguous slice
        self._end = 0
        self.frames = 0

    def push(self, features: np.ndarray) -> None:
        """Append one frame's (F,) features; NaN/∞ raise ValueError (they would sit in every window for T frames)."""
        v = np.asarray(features, np.float32).reshape(self.f)
        if not np.isfinite(v).all():
            raise ValueError(f"features hold {int((~np.isfinite(v)).sum())} NaN/∞ value(s) of {self.f}; "
                             "refuse the frame before pushing it (ModelBundle.encode checks its input)")
        if self.frames == 0:
            self._buf[:] = v
            self._end = self.t
        elif self._end == 2 * self.t:
            self._buf[: self.t - 1] = self._buf[self._end - self.t + 1:self._end]
            self._end = self.t - 1
            self._buf[self._end] = v
            self._end += 1
        else:
            self._buf[self._end] = v
            self._end += 1
        self.frames += 1

    def window(self) -> np.ndarray:
        """(1,T,F) the last T frames' features, oldest first; raises before the first push."""
        if self.frames == 0:
            raise ValueError("no frame pushed yet")
        return self._buf[self._end - self.t:self._end][None]

    def reset(self) -> None:
        self.frames, self._end = 0, 0

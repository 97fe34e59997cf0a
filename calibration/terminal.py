"""A carpet map in the terminal: Unicode blocks, one character per block of sensels.

``render_map(values)`` takes (H, W) bool or float (0..1 after scaling by the max) and
draws at most ``width`` characters across; characters are twice as tall as wide, so
a character covers s × 2s sensels. Legend: ' ' never, '░' little, '▒', '▓', '█' fully.
``faults`` (H, W) bool draws 'x' where a block is mostly faulty.
"""

from __future__ import annotations

import numpy as np

SHADES = " ░▒▓█"


def render_map(values: np.ndarray, title: str = "", width: int = 48, faults: np.ndarray | None = None) -> str:
    v = np.asarray(values, float)
    h, w = v.shape
    sx = max(1, int(np.ceil(w / width)))
    sy = 2 * sx
    hh, ww = int(np.ceil(h / sy)), int(np.ceil(w / sx))
    pad = np.zeros((hh * sy, ww * sx))
    pad[:h, :w] = v / (v.max() if v.max() > 0 else 1.0)
    blocks = pad.reshape(hh, sy, ww, sx).mean(axis=(1, 3))
    fb = None
    if faults is not None:
        fpad = np.zeros((hh * sy, ww * sx))
        fpad[:h, :w] = faults
        fb = fpad.reshape(hh, sy, ww, sx).mean(axis=(1, 3)) > 0.5
    lines = [title] if title else []
    lines.append("┌" + "─" * ww + "┐")
    for r in range(hh):
        row = "".join("x" if fb is not None and fb[r, c] else SHADES[min(4, int(np.ceil(blocks[r, c] * 4)))]
                      for c in range(ww))
        lines.append("│" + row + "│")
    lines.append("└" + "─" * ww + "┘")
    covered = float((v > 0).mean())
    lines.append(f"{covered:.0%} of sensels touched   (row 0 at the top, column 0 at the left)")
    return "\n".join(lines)

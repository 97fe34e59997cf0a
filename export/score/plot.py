"""The score's PNG: per scene, the true and the published people count over time (needs matplotlib, the viz extra)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np


def _runs(mask: np.ndarray) -> list[tuple[int, int]]:
    """[(start, stop)) of every run of True in a 1-D boolean array."""
    edges = np.diff(np.concatenate([[0], mask.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1).tolist(), np.flatnonzero(edges == -1).tolist()))


def timeline_png(result: dict[str, Any], out_png: Path) -> Path:
    """One row per scored scene: true count (black) and published count (red) per frame; extra frames shaded."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    names = list(result["timeline"])
    if not names:
        raise ValueError("no scene was scored: nothing to draw")
    rate = result["rate_hz"]
    top = max(max(max(v["true"], default=0), max(v["published"], default=0)) for v in result["timeline"].values())
    fig = Figure(figsize=(11, 1.35 * len(names) + 0.9), dpi=100)
    FigureCanvasAgg(fig)
    axes = fig.subplots(len(names), 1, squeeze=False, sharex=True)[:, 0]
    scenes = {s["name"]: s for s in result["scenes"]}
    for ax, name in zip(axes, names):
        true = np.asarray(result["timeline"][name]["true"])
        pub = np.asarray(result["timeline"][name]["published"])
        t = np.arange(len(true)) / rate
        for mask, colour in ((pub > true, "tab:red"), (pub < true, "tab:blue")):
            for a, b in _runs(mask):  # frame a up to (not including) frame b
                ax.axvspan(a / rate, b / rate, color=colour, alpha=0.15, lw=0)
        te = np.append(t, len(t) / rate)  # each frame drawn over its whole interval
        ax.step(te, np.append(true, true[-1:]), where="post", color="black", lw=2.2, label="true")
        ax.step(te, np.append(pub, pub[-1:]), where="post", color="tab:red", lw=1.1, label="published")
        starts = result["timeline"][name].get("chunk_starts_s", [])
        ends = starts[1:] + [len(t) / rate]
        for x in starts[1:]:
            ax.axvline(x, color="0.6", lw=0.6, ls=":")
        for a, b, acts in zip(starts, ends, result["timeline"][name].get("chunk_activities", [])):
            x = (a + b) / 2
            ax.text(x, top + 0.9, ", ".join(a.replace("_", "-") for a in acts), ha="center", va="top", fontsize=7,
                    color="0.25")
        s = scenes[name].get("summary") or {}
        ax.set_ylim(-0.2, top + 1.0)
        ax.set_yticks(range(top + 1))
        ax.set_ylabel(name, rotation=0, ha="right", va="center", fontsize=9)
        ax.text(1.005, 0.5, f"right {s.get('count_right_pct')} %\nextra {s.get('extra_frames_pct')} %",
                transform=ax.transAxes, fontsize=7.5, va="center")
    handles, labels = axes[0].get_legend_handles_labels()
    fig.legend(handles, labels, loc="upper right", fontsize=8, ncol=2, frameon=False)
    axes[-1].set_xlabel("time in the scene, s (dotted: a new simulated scene; red shade: more published than true, "
                        "blue: fewer)")
    fig.suptitle(f"People count per frame, true vs published ({result['set']} set; "
                 f"{', '.join(result['model']) or 'model ?'})", fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.97))
    fig.savefig(out_png)
    return out_png

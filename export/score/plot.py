"""The score's PNG: per scene, the true and the published people count over time (needs matplotlib, the viz extra)."""

from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np


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
        ax.fill_between(t, 0, top + 0.6, where=pub > true, step="post", color="tab:red", alpha=0.15, lw=0)
        ax.fill_between(t, 0, top + 0.6, where=pub < true, step="post", color="tab:blue", alpha=0.15, lw=0)
        ax.step(t, true, where="post", color="black", lw=2.2, label="true")
        ax.step(t, pub, where="post", color="tab:red", lw=1.1, label="published")
        chunk = scenes[name]["scene_s"]
        for x in np.arange(chunk, t[-1] if len(t) else 0, chunk):
            ax.axvline(x, color="0.6", lw=0.6, ls=":")
        s = scenes[name].get("summary") or {}
        ax.set_ylim(-0.2, top + 0.6)
        ax.set_yticks(range(top + 1))
        ax.set_ylabel(name, rotation=0, ha="right", va="center", fontsize=9)
        ax.text(1.005, 0.5, f"right {s.get('count_right_pct')} %\nextra {s.get('extra_frames_pct')} %",
                transform=ax.transAxes, fontsize=7.5, va="center")
    axes[0].legend(loc="upper left", fontsize=8, ncol=2, framealpha=0.8)
    axes[-1].set_xlabel("time in the scene, s (dotted: a new simulated scene; red shade: more published than true, "
                        "blue: fewer)")
    fig.suptitle(f"People count per frame, true vs published ({result['set']} set; "
                 f"{', '.join(result['model']) or 'model ?'})", fontsize=10)
    fig.tight_layout()
    fig.savefig(out_png)
    return out_png

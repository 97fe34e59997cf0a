"""Draw one dataset frame: raw counts, true pressure, and the bodies (top and side), side by side."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def draw_frame(frame: dict[str, np.ndarray], manifest: dict, path: str | Path, body: str = "lite", title: str = "") -> Path:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from edge.body import SMPL_PARENTS, BodyModel
    from edge.body.render import draw_view

    pitch, rows, cols = manifest["pitch_m"], manifest["rows"], manifest["cols"]
    extent = (0, cols * pitch, rows * pitch, 0)  # x along columns, y along rows (row 0 at the top)
    fig = Figure(figsize=(17, 4.4), dpi=90)
    FigureCanvasAgg(fig)
    ax = fig.add_subplot(1, 4, 1)
    im = ax.imshow(frame["counts"], cmap="viridis", extent=extent)
    fig.colorbar(im, ax=ax, shrink=0.8, label="raw counts")
    ax.set_title("raw counts (what the board sends)", fontsize=9)
    ax = fig.add_subplot(1, 4, 2)
    p = frame["pressure_kpa"].astype(np.float32)
    im = ax.imshow(p, cmap="magma", extent=extent, vmin=0, vmax=max(1.0, float(np.nanpercentile(p, 99.5))))
    fig.colorbar(im, ax=ax, shrink=0.8, label="kPa")
    ax.set_title(f"true pressure, total {np.nansum(p) * pitch**2 * 1e3:.0f} N", fontsize=9)
    present = np.flatnonzero(frame["present"])
    names = manifest["activities"]
    people = ", ".join(f"{manifest['subjects'][frame['subject'][k]]['subject_id']}: {names[frame['activity'][k]]}" for k in present)
    if len(present) and np.isfinite(frame["transl_m"][present]).all():
        model = BodyModel.load(body)
        out = model.forward(frame["pose_aa"][present], frame["betas"][present], frame["transl_m"][present], vertices=True)
        for k, view in enumerate(("top", "side")):
            a = fig.add_subplot(1, 4, 3 + k)
            draw_view(a, list(out["vertices"]), model.faces, view, joints=list(out["joints"]), parents=SMPL_PARENTS)
            if view == "top":
                a.set_xlim(0, cols * pitch)
                a.set_ylim(rows * pitch, 0)
                a.set_title("bodies from above (carpet frame)", fontsize=9)
    fig.suptitle(f"{title}  t = {frame['t_s']:.2f} s  {people or 'empty carpet'}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    return Path(path)

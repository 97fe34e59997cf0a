"""Pressure maps next to the body: ``python -m sim.contact.render --out docs/sim/contact``.

Per pose: the body from the side and from above (COM ✚, COP ○), the fine pressure field
(the compliant layer, before the rug) and the sensel pressure (after rug blur and
crossing sampling), with the numbers that the tests check. matplotlib only here.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np


def _pressure_panel(ax, img, extent, title, vmax, com, cop):
    from matplotlib.colors import PowerNorm

    im = ax.imshow(np.ma.masked_less(img, 0.05), origin="lower", extent=extent, cmap="magma_r",
                   norm=PowerNorm(0.5, vmin=0, vmax=vmax if vmax else float(img.max())), interpolation="nearest")
    ax.plot(com[0], com[1], "+", color="tab:green", ms=14, mew=2, label="COM")
    if np.isfinite(cop).all():
        ax.plot(cop[0], cop[1], "o", mfc="none", color="tab:blue", ms=10, mew=1.5, label="COP")
    ax.set_title(title, fontsize=9)
    ax.set_aspect("equal")
    ax.tick_params(labelsize=7)
    ax.set_facecolor("0.93")
    return im


def render_pose(path, model, pose_name, carpet, mass, tissue, xy_m=(0.9, 0.9), yaw_deg=0.0, title_extra=""):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from edge.body.render import draw_view
    from sim.contact.scenes import grounded_vertices, scene_pose

    v = grounded_vertices(model, scene_pose(model, pose_name), xy_m=xy_m, yaw_deg=yaw_deg)
    res = carpet.pressure_kpa(v, model.faces, mass, tissue_kpa_per_mm=tissue, keep_fine=True)
    fine = res.fine_pressure_kpa
    j0, i0 = res.fine_origin
    c = res.fine_cell_m
    fine_ext = [i0 * c, (i0 + fine.shape[1]) * c, j0 * c, (j0 + fine.shape[0]) * c]
    nz = np.argwhere(fine > 0)
    lo, hi = nz.min(0), nz.max(0)
    pad = 0.06
    box = [(i0 + lo[1]) * c - pad, (i0 + hi[1] + 1) * c + pad, (j0 + lo[0]) * c - pad, (j0 + hi[0] + 1) * c + pad]
    p = carpet.pitch_m
    sens_ext = [0, carpet.cols * p, 0, carpet.rows * p]
    area_f = (fine > 0).sum() * c * c
    sens_area = res.contact_mask.sum() * p * p
    vmax = float(fine.max())

    fig = Figure(figsize=(18, 4.8), dpi=90)
    FigureCanvasAgg(fig)
    ax = [fig.add_subplot(1, 4, k + 1) for k in range(4)]
    draw_view(ax[0], [v], model.faces, "side")
    ax[0].plot(res.com_m[1], res.com_m[2], "+", color="tab:green", ms=14, mew=2)
    draw_view(ax[1], [v], model.faces, "top", floor_z=None)
    ax[1].plot(res.com_m[0], res.com_m[1], "+", color="tab:green", ms=14, mew=2)
    ax[1].plot(res.cop_total_m[0], res.cop_total_m[1], "o", mfc="none", color="tab:blue", ms=10, mew=1.5)
    im = _pressure_panel(ax[2], fine, fine_ext, f"fine field ({c * 1000:.2f} mm cells): {area_f * 1e4:.0f} cm²,\n"
                         f"mean {res.force_total_n / area_f / 1000:.1f} kPa, max {fine.max():.0f}", vmax, res.com_m, res.cop_total_m)
    fig.colorbar(im, ax=ax[2], fraction=0.046, label="kPa")
    im = _pressure_panel(ax[3], res.pressure_kpa, sens_ext,
                         f"sensels {carpet.rows}×{carpet.cols} @ {p * 1000:.2f} mm: >{carpet.contact_kpa:g} kPa on "
                         f"{sens_area * 1e4:.0f} cm²,\nmean {res.pressure_kpa[res.contact_mask].mean():.1f} kPa, "
                         f"max {res.pressure_kpa.max():.0f}, Σ {res.sensel_force_n:.0f} N", vmax, res.com_m, res.cop_m)
    fig.colorbar(im, ax=ax[3], fraction=0.046, label="kPa")
    for a in ax[2:]:
        a.set_xlim(box[0], box[1])
        a.set_ylim(box[2], box[3])
    ax[3].legend(fontsize=7, loc="upper right")
    fig.suptitle(f"{pose_name} ({model.num_vertices} vertices, {mass:.1f} kg): force {res.force_total_n:.1f} N = "
                 f"m·g {res.target_force_n:.1f} N, COP−COM {res.cop_error_m * 1000:.1f} mm, balanced {res.balanced}, "
                 f"indentation {res.indentation_mm:.0f} mm, tilt ({res.slope[0]:+.3f}, {res.slope[1]:+.3f}){title_extra}", fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    return res


def render_grids(path, model, mass, tissue, pose_name="t_pose"):
    """One stance on 96×96, 48×48 and 32×32 carpets of the same size."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from sim.contact.model import ContactModel
    from sim.contact.scenes import grounded_vertices, scene_pose

    v = grounded_vertices(model, scene_pose(model, pose_name), xy_m=(0.9, 0.9), yaw_deg=30.0)
    fig = Figure(figsize=(14, 4.6), dpi=90)
    FigureCanvasAgg(fig)
    for k, n in enumerate((96, 48, 32)):
        cm = ContactModel(n, n, 0.01905 * 96 / n)
        res = cm.pressure_kpa(v, model.faces, mass, tissue_kpa_per_mm=tissue)
        ax = fig.add_subplot(1, 3, k + 1)
        im = _pressure_panel(ax, res.pressure_kpa, [0, n * cm.pitch_m, 0, n * cm.pitch_m],
                             f"{n}×{n} @ {cm.pitch_m * 1000:.1f} mm: force {res.force_n:.0f} N,\nΣ sensels "
                             f"{res.sensel_force_n:.0f} N, max {res.pressure_kpa.max():.0f} kPa", None, res.com_m, res.cop_m)
        ax.set_xlim(0.55, 1.25)
        ax.set_ylim(0.55, 1.25)
        fig.colorbar(im, ax=ax, fraction=0.046, label="kPa")
    fig.suptitle(f"{pose_name} turned 30°, same body on three grids (crossing width 0.5 pitch, rug σ 5 mm)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path)


def main(argv=None) -> int:
    from edge.body import BodyModel
    from sim.contact.mesh import subject_mass_kg, tissue_stiffness
    from sim.contact.model import ContactModel
    from sim.contact.scenes import SCENE_POSES

    parser = argparse.ArgumentParser(prog="python -m sim.contact.render", description="draw contact pressure maps")
    parser.add_argument("--out", type=Path, default=Path("docs/sim/contact"))
    parser.add_argument("--model", default="full")
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    model = BodyModel.load(args.model)
    mass, tissue = subject_mass_kg(model), tissue_stiffness(model)
    carpet = ContactModel(96, 96, 0.01905)
    for name in SCENE_POSES:
        path = args.out / f"{name}.png"
        render_pose(path, model, name, carpet, mass, tissue)
        print(path)
    path = args.out / "edge_of_carpet.png"
    res = render_pose(path, model, "t_pose", carpet, mass, tissue, xy_m=(96 * 0.01905 - 0.02, 0.9))
    print(path, f"off carpet {res.force_off_carpet_n:.0f} N")
    path = args.out / "grids_96_48_32.png"
    render_grids(path, model, mass, tissue)
    print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Contact sheets: for each activity, several moments of the body beside its true pressure.

    python -m sim.sheets docs/sim/activities        (needs matplotlib)

One PNG per activity: the top row draws the body from the side, the row below the true
pressure at the sensels (kPa, cropped to the person), with the total force against
the body weight. These are the pictures to look at when judging the simulator.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

from sim.dataset.generate import PAPER_ACTIVITIES

MOMENTS = 5


def sheet(activity: str, out: Path, seed: int = 2, seconds: float = 6.0) -> Path:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from edge.body import BodyModel
    from edge.body.render import draw_view
    from sim.contact import ContactModel, mesh_centroid_m, regional_tissue, subject_mass_kg
    from sim.motion import Subject, person_track

    body = BodyModel.load("lite")
    carpet = ContactModel(96, 96, pitch_m=0.01905)
    tissue = regional_tissue(body)
    subject = Subject.random(seed, seed)
    track = person_track(subject, [activity], seconds, 14.0, rng=seed, model=body, start_xy=(0.9, 0.9))
    n = len(track)
    out_fw = body.forward(track.pose_aa, np.broadcast_to(track.betas, (n, 10)), track.transl_m, vertices=True)
    mass = subject_mass_kg(body, track.betas)
    com = np.stack([mesh_centroid_m(v, body.faces) for v in out_fw["vertices"]])
    acc = np.gradient(np.gradient(com, 1 / 14, axis=0), 1 / 14, axis=0)
    # moments that show the range of the motion: quantiles of the head's height, in time order
    head_z = out_fw["joints"][:, 15, 2]
    order = np.argsort(head_z[1:-1]) + 1
    moments = np.unique(order[np.linspace(0, len(order) - 1, MOMENTS).astype(int)])
    fig = Figure(figsize=(3.2 * MOMENTS, 6.6), dpi=80)
    FigureCanvasAgg(fig)
    pitch = carpet.pitch_m
    for k, t in enumerate(moments):
        res = carpet.pressure_kpa(out_fw["vertices"][t], body.faces, mass, acc_z_m_s2=float(acc[t, 2]), com_m=com[t],
                                  acc_xy_m_s2=acc[t, :2], tissue_kpa_per_mm=tissue)
        ax = fig.add_subplot(2, MOMENTS, k + 1)
        draw_view(ax, [out_fw["vertices"][t]], body.faces, "side")
        ax.set_title(f"t = {t / 14:.1f} s", fontsize=9)
        ax = fig.add_subplot(2, MOMENTS, MOMENTS + k + 1)
        p = res.pressure_kpa
        rows, cols = np.nonzero(p > 0.05)
        if len(rows):
            r0, r1 = max(rows.min() - 4, 0), min(rows.max() + 5, p.shape[0])
            c0, c1 = max(cols.min() - 4, 0), min(cols.max() + 5, p.shape[1])
        else:
            r0, r1, c0, c1 = 0, p.shape[0], 0, p.shape[1]
        im = ax.imshow(p[r0:r1, c0:c1], cmap="magma", vmin=0, extent=(c0 * pitch, c1 * pitch, r1 * pitch, r0 * pitch))
        fig.colorbar(im, ax=ax, shrink=0.7, label="kPa")
        ax.set_title(f"{res.sensel_force_n:.0f} N on sensels / {mass * 9.81:.0f} N weight, peak {p.max():.0f} kPa", fontsize=7)
        ax.tick_params(labelsize=6)
    fig.suptitle(f"{activity}: subject {subject.subject_id}, {mass:.0f} kg", fontsize=11)
    fig.tight_layout()
    path = out / f"{activity}.png"
    fig.savefig(path)
    return path


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    out = Path(argv[0] if argv else "docs/sim/activities")
    out.mkdir(parents=True, exist_ok=True)
    for activity in PAPER_ACTIVITIES + ("walking",):
        print(sheet(activity, out))
    return 0


if __name__ == "__main__":
    sys.exit(main())

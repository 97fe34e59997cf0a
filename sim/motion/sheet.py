"""Contact sheets: a few moments of each activity, front and side, to look at.

``python -m sim.motion.sheet --out docs/sim/motion`` writes ``<activity>.png`` for every
activity (full mesh, subject 3, seed 1). matplotlib is needed (the ``viz`` extra).
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from edge.body import BodyModel
from sim.motion.activities import ACTIVITIES
from sim.motion.generate import Subject, person_track


def draw_activity(path, activity: str, subject_id: int = 3, seed: int = 1, moments: int = 6,
                  seconds: float = 10.0, model_name: str = "full") -> Path:
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from edge.body.render import draw_view

    lite = BodyModel.load("lite")
    track = person_track(Subject.random(subject_id), [activity], seconds, 14.0, rng=seed, model=lite, extend=True)
    model = lite if model_name == "lite" else BodyModel.load(model_name)
    inside = np.flatnonzero(np.asarray(track.activity) == ACTIVITIES.index(activity))
    if len(inside) < moments:
        inside = np.arange(len(track))
    # One moment per equal slice of the activity: the frame that differs most from standing
    # (pose and pelvis height), so the sheet shows the activity rather than its pauses.
    change = np.abs(track.pose_aa[:, 3:] - track.pose_aa[:1, 3:]).sum(1) + 5.0 * np.abs(track.transl_m[:, 2] - track.transl_m[0, 2])
    frames = np.array([sl[np.argmax(change[sl])] for sl in np.array_split(inside, moments)])
    out = model.forward(track.pose_aa[frames], track.betas, track.transl_m[frames], vertices=True)
    fig = Figure(figsize=(2.6 * moments, 6.4), dpi=90)
    FigureCanvasAgg(fig)
    names = ("left_foot", "right_foot", "left_hand", "right_hand", "buttocks", "back")
    for k, f in enumerate(frames):
        for row, view in enumerate(("front", "side")):
            ax = fig.add_subplot(2, moments, row * moments + k + 1)
            draw_view(ax, [out["vertices"][k]], model.faces, view, [out["joints"][k]], model.parents, 0.0)
            on = [n for n, c in zip(names, track.contact[f]) if c]
            ax.set_title(f"{view} t={f / track.rate_hz:.1f}s" + ("\n" + ",".join(on) if row == 0 else ""), fontsize=7)
    fig.suptitle(f"{activity} (subject 3, seed {seed}; contacts = generator's schedule)", fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    return Path(path)


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m sim.motion.sheet", description="draw a contact sheet per activity")
    parser.add_argument("--out", type=Path, default=Path("docs/sim/motion"))
    parser.add_argument("--model", default="full")
    parser.add_argument("activities", nargs="*", default=[a for a in ACTIVITIES if a != "standing"])
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    for a in args.activities:
        print(draw_activity(args.out / f"{a}.png", a, model_name=args.model))
    return 0


if __name__ == "__main__":
    sys.exit(main())

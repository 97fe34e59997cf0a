"""Draw posed bodies to PNG with matplotlib only (no GPU, no OpenGL).

Orthographic views of the carpet frame (Z up), flat-shaded triangles drawn far to
near (painter's algorithm) as one 2D PolyCollection per view:

* ``front``: seen from −y (screen right = +x): an upright body with global
  orientation +90° about x faces the viewer;
* ``side``: seen from +x (screen right = +y);
* ``top``: seen from above (screen right = +x, up = +y), as the carpet sees it.

matplotlib is imported here only (the ``viz`` extra), never by the runtime.
``python -m edge.body.render --out docs/body`` redraws the committed renders.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

# view → (screen right, screen up, direction the camera looks along)
VIEWS = {
    "front": (np.array([1.0, 0, 0]), np.array([0, 0, 1.0]), np.array([0, 1.0, 0])),
    "side": (np.array([0, 1.0, 0]), np.array([0, 0, 1.0]), np.array([-1.0, 0, 0])),
    "top": (np.array([1.0, 0, 0]), np.array([0, 1.0, 0]), np.array([0, 0, -1.0])),
}
_COLOURS = [(0.78, 0.62, 0.52), (0.45, 0.60, 0.80), (0.55, 0.75, 0.50), (0.85, 0.70, 0.35)]


def draw_view(ax, bodies, faces, view: str, joints=None, parents=None, floor_z: float | None = 0.0):
    from matplotlib.collections import LineCollection, PolyCollection

    right, up, look = VIEWS[view]
    light = -look + 0.6 * up + 0.3 * right
    light /= np.linalg.norm(light)
    polys, shades, depths = [], [], []
    for i, verts in enumerate(bodies):
        tri = verts[faces]  # (F,3,3)
        normal = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
        normal /= np.maximum(np.linalg.norm(normal, axis=1, keepdims=True), 1e-12)
        lit = 0.3 + 0.7 * np.abs(normal @ light)  # two-sided
        base = np.array(_COLOURS[i % len(_COLOURS)])
        polys.append(np.stack([tri @ right, tri @ up], axis=-1))
        shades.append(np.clip(lit[:, None] * base, 0, 1))
        depths.append(tri.mean(1) @ look)
    xy = np.concatenate(polys)  # (F,3,2)
    rgb = np.concatenate(shades)
    order = np.argsort(np.concatenate(depths))[::-1]  # far first
    # matplotlib's stubs ask for a sequence; an (F,3,2) array is its documented fast path
    ax.add_collection(PolyCollection(xy[order], facecolors=rgb[order], edgecolors=rgb[order],  # type: ignore[arg-type]
                                     linewidths=0.15))
    pts = xy.reshape(-1, 2)
    lo, hi = pts.min(0), pts.max(0)
    if floor_z is not None and view != "top":
        ax.axhline(floor_z, color="0.5", linewidth=0.8, zorder=0)
        lo[1] = min(lo[1], floor_z)
    if joints is not None:
        for body_joints in joints:
            p2 = np.stack([body_joints @ right, body_joints @ up], axis=-1)
            segs = [p2[[parents[j], j]] for j in range(1, len(p2))]
            ax.add_collection(LineCollection(segs, colors="k", linewidths=0.8, zorder=3))
            ax.scatter(p2[:, 0], p2[:, 1], s=4, c="crimson", zorder=4)
    pad = 0.05 * max(hi - lo) + 0.02
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_aspect("equal")
    ax.set_title(view, fontsize=9)
    ax.tick_params(labelsize=7)


def render_png(path, bodies, faces, views=("front", "side"), title: str | None = None, joints=None, parents=None,
               floor_z=0.0, size_in=4.0, dpi=100):
    """Draw bodies (list of (V,3) arrays in metres, carpet frame) to a PNG.

    faces: (F,3) shared by all bodies; joints: optional list of (J,3) drawn as a
    skeleton with ``parents``; floor_z: a floor line (None: none).
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    unknown = [v for v in views if v not in VIEWS]
    if unknown:
        raise ValueError(f"unknown view(s) {unknown}; choose from {sorted(VIEWS)}")
    bodies = [np.asarray(b, dtype=np.float64) for b in bodies]
    if not bodies:
        raise ValueError("nothing to draw: no bodies")
    fig = Figure(figsize=(size_in * len(views), size_in * 1.1), dpi=dpi)
    FigureCanvasAgg(fig)
    for k, view in enumerate(views):
        ax = fig.add_subplot(1, len(views), k + 1)
        draw_view(ax, bodies, np.asarray(faces), view, joints, parents, floor_z)
    if title:
        fig.suptitle(title, fontsize=10)
    fig.tight_layout()
    fig.savefig(path)
    return Path(path)


def grounded(model, pose_aa, betas=None, xy_m=(0.0, 0.0)):
    """transl_m that puts the lowest vertex of the posed body on the floor (z = 0) at xy."""
    out = model.forward(pose_aa, betas, np.zeros(3), vertices=True)
    lowest = float(out["vertices"][0][:, 2].min())
    return np.array([xy_m[0], xy_m[1], -lowest])


def render_docs(out_dir: Path, model_name: str = "full") -> list[Path]:
    """The committed renders: each named pose, front and side, plus the lite mesh."""
    from edge.body.model import BodyModel
    from edge.body.poses import POSES, pose_aa

    written = []
    for name in (model_name, "lite"):
        model = BodyModel.load(name)
        poses = POSES if name == model_name else ["t_pose", "deep_squat"]
        for pose_name in poses:
            pose = pose_aa(pose_name)
            transl = grounded(model, pose)
            out = model.forward(pose, None, transl, vertices=True)
            suffix = "" if name == model_name else f"_{name}"
            path = out_dir / f"{pose_name}{suffix}.png"
            render_png(
                path, [out["vertices"][0]], model.faces, title=f"{pose_name} ({name}: {model.num_vertices} vertices, betas 0)",
                joints=[out["joints"][0]], parents=model.parents,
            )
            written.append(path)
    # Shape: beta 0 (stature) at −2, 0, +2 side by side.
    model = BodyModel.load(model_name)
    bodies = []
    for k, b0 in enumerate((-2.0, 0.0, 2.0)):
        betas = np.zeros(model.num_betas)
        betas[0] = b0
        transl = grounded(model, pose_aa("t_pose"), betas, xy_m=(1.9 * (k - 1), 0.0))
        bodies.append(model.forward(pose_aa("t_pose"), betas, transl, vertices=True)["vertices"][0])
    path = out_dir / "betas0_-2_0_+2.png"
    render_png(path, bodies, model.faces, views=("front",), title="beta 0 = -2, 0, +2", size_in=6.0)
    written.append(path)
    return written


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m edge.body.render", description="redraw the body-model renders of docs/body")
    parser.add_argument("--out", type=Path, default=Path("docs/body"))
    args = parser.parse_args(argv)
    args.out.mkdir(parents=True, exist_ok=True)
    for path in render_docs(args.out):
        print(path)
    return 0


if __name__ == "__main__":
    sys.exit(main())

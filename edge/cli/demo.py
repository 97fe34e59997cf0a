"""`make run`: the runtime on the virtual carpet, then reconstructed bodies beside the simulator's truth.

    python -m edge.cli.demo --out out/run --seconds 20 --people 2 --seed 7

1. runs ``cavatar run``'s own loop (:func:`edge.cli.run.serve`, the one-line summary each
   second) on ``sim://?people=2&seed=7&scene_s=…`` for ``--seconds`` into ``<out>/bodies.jsonl``
   (status ``<out>/status.json``; the virtual carpet's calibration is made, or reused, at
   ``<out>/calibration-sim-<seed>-96.npz``);
2. writes ``<out>/frames.json``: the simulator frame of every published seq (records carry
   no frame index: ``seq`` counts records, heartbeats included; the pipeline reports
   which board frame each record came from, and the virtual board's frame_seq is the
   simulator's frame index);
3. draws ``<out>/bodies.png``: for a few records spread over the run, the true bodies (the
   ``sim://`` plug-in's carpet made again with the same seed, its ``truth(k)``) above the
   reconstructed ones, front view, each column one frame time.

Drawing needs matplotlib (the ``viz`` extra, which `make run` installs); the runtime does not.
"""

from __future__ import annotations

import argparse
import json
import sys
import warnings
from pathlib import Path
from typing import Any

import numpy as np

from edge.runtime.config import RuntimeConfig


def demo_scene_s(seconds: float) -> float:
    """The virtual carpet's scene length for a run of ``seconds``: whole scenes of about 10 s, the last one
    cut at its middle. At a scene change everyone moves elsewhere at once (no real carpet does that) and
    a new track needs a few frames, so a run that ended just after one would draw its last column there."""
    scenes = max(1, int(seconds / 10.0 + 0.5))
    return round(seconds / (scenes - 0.5), 3)


def demo_url(people: int, seed: int, seconds: float) -> str:
    """The demo's source: the virtual carpet with ``people`` and ``seed``, scenes as ``demo_scene_s`` says."""
    return f"sim://?people={people}&seed={seed}&scene_s={demo_scene_s(seconds)}"


def demo_config(out_dir: Path, seconds: float, people: int, seed: int) -> RuntimeConfig:
    return RuntimeConfig().with_overrides(
        source=demo_url(people, seed, seconds), sinks=[f"jsonl://{out_dir}/bodies.jsonl"],
        status_file=str(out_dir / "status.json"), seconds=seconds, device="sim-demo")


def run(out_dir: Path, seconds: float = 20.0, people: int = 2, seed: int = 7) -> tuple[int, dict, dict[int, int]]:
    """Run the runtime; returns (exit code, final status, seq → simulator frame)."""
    from edge.cli.run import serve
    from edge.runtime.loop import Runtime

    out_dir.mkdir(parents=True, exist_ok=True)
    for old in [*out_dir.glob("bodies*.jsonl"), out_dir / "bodies.info.json", out_dir / "status.json",
                out_dir / "frames.json", out_dir / "bodies.png"]:
        old.unlink(missing_ok=True)  # a fresh run (the calibration is kept: it is this carpet's)
    cfg = demo_config(out_dir, seconds, people, seed)
    rt = Runtime(cfg)
    frame_of_seq: dict[int, int] = {}

    def note(outcome: Any) -> None:
        if outcome.record is not None:
            frame_of_seq[outcome.record["seq"]] = int(outcome.frame.frame_seq)

    rt.on_outcome.append(note)
    code, final = serve(cfg, runtime=rt)
    (out_dir / "frames.json").write_text(json.dumps({"rate_hz": final["source"]["board"].get("rate_hz", 14.0),
                                                     "frame_of_seq": {str(k): v for k, v in frame_of_seq.items()}}))
    return code, final, frame_of_seq


def pick_records(jsonl: Path, frame_of_seq: dict[int, int], count: int) -> list[dict]:
    """``count`` records with people, evenly spread over the run (only those whose frame is known)."""
    records = []
    for line in jsonl.read_text().splitlines():
        rec = json.loads(line)
        if rec["people"] and rec["seq"] in frame_of_seq:
            records.append(rec)
    if not records:
        return []
    idx = np.unique(np.linspace(0, len(records) - 1, min(count, len(records))).round().astype(int))
    return [records[i] for i in idx]


def match_people(truth_xyz: list, published_xyz: list) -> list[int]:
    """Order of the published people so that the i-th is the one nearest (on the carpet) the i-th true one; extras last."""
    left = list(range(len(published_xyz)))
    order = []
    for t in truth_xyz:
        if not left:
            break
        best = min(left, key=lambda i: float(np.hypot(*(np.asarray(published_xyz[i])[:2] - np.asarray(t)[:2]))))
        order.append(best)
        left.remove(best)
    return order + left


def render_strip(out_png: Path, records: list[dict], frame_of_seq: dict[int, int], people: int, seed: int,
                 rate_hz: float = 14.0, model_label: str = "", seconds: float = 20.0) -> Path:
    """Truth (top row) and reconstruction (bottom row), front view, one column per record."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    from edge.body import BodyModelWarning
    from edge.body.render import draw_view
    from edge.sources import source_options, source_plugin

    if not records:
        raise ValueError("no record with people to draw")
    url = demo_url(people, seed, seconds) + "&speed=0"  # the run's carpet, made again for its truth
    plugin = source_plugin(url)
    if plugin is None:
        raise ValueError("sim:// is served by no source plug-in here")
    carpet, _ = plugin.module.open_carpet(source_options(url))
    model = carpet.body  # the body model the simulator and the shipped bundle use
    fig = Figure(figsize=(2.6 * len(records), 6.4), dpi=110)
    FigureCanvasAgg(fig)
    axes = fig.subplots(2, len(records), squeeze=False)
    clamped = 0
    for col, rec in enumerate(records):
        k = frame_of_seq[rec["seq"]]
        truth = carpet.truth(k)
        tv = model.forward(np.stack([t["pose_aa"] for t in truth]), np.stack([t["betas"] for t in truth]),
                           np.stack([t["transl_m"] for t in truth]), vertices=True)["vertices"]
        ppl = rec["people"]
        with warnings.catch_warnings(record=True) as caught:  # an untrained bundle's betas go beyond ±5: clamped
            warnings.simplefilter("always", BodyModelWarning)
            rv = model.forward(np.array([p["pose_aa"] for p in ppl]), np.array([p["betas"] for p in ppl]),
                               np.array([p["transl_m"] for p in ppl]), vertices=True)["vertices"]
        clamped += len(caught)
        order = match_people([t["transl_m"] for t in truth], [p["transl_m"] for p in ppl])
        rv, ppl = [rv[i] for i in order], [ppl[i] for i in order]  # same colour above and below = same person
        ax_t, ax_r = axes[0, col], axes[1, col]
        draw_view(ax_t, list(tv), model.faces, "front")
        draw_view(ax_r, rv, model.faces, "front")
        pts = np.concatenate([*tv, *rv])
        pad = 0.1
        for ax in (ax_t, ax_r):  # the same box above and below, so truth and reconstruction compare
            ax.set_xlim(pts[:, 0].min() - pad, pts[:, 0].max() + pad)
            ax.set_ylim(min(0.0, pts[:, 2].min()) - pad, pts[:, 2].max() + pad)
        acts_t = ", ".join(t["activity"] for t in truth)
        acts_r = ", ".join(p["activity"] for p in ppl)
        ax_t.set_title(f"t = {k / rate_hz:.1f} s (frame {k})\n{acts_t}", fontsize=8)
        ax_r.set_title(f"seq {rec['seq']}: tracks {', '.join(str(p['track_id']) for p in ppl)}\n{acts_r}", fontsize=8)
    axes[0, 0].set_ylabel("TRUTH (simulator)\nz, m", fontsize=9)
    axes[1, 0].set_ylabel(f"RECONSTRUCTED\n{model_label}\nz, m", fontsize=9)
    fig.suptitle(f"{demo_url(people, seed, seconds)}: front view (x right, z up, metres); top: the simulator's "
                 "true bodies, bottom: what the runtime published", fontsize=10)
    fig.tight_layout()
    fig.savefig(out_png)
    if clamped:
        print(f"note: {clamped} reconstructed bodies had betas beyond ±5, drawn clamped (an untrained or poor bundle)")
    return out_png


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="python -m edge.cli.demo", description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", type=Path, default=Path("out/run"), help="output folder (default out/run)")
    ap.add_argument("--seconds", type=float, default=20.0, help="how long the runtime runs (default 20)")
    ap.add_argument("--people", type=int, default=2, help="people on the virtual carpet (default 2)")
    ap.add_argument("--seed", type=int, default=7, help="seed of the virtual carpet (default 7)")
    ap.add_argument("--columns", type=int, default=6, help="frames drawn (default 6)")
    args = ap.parse_args(argv)
    from cavatar_common.errors import CliError

    try:
        code, final, frame_of_seq = run(args.out, args.seconds, args.people, args.seed)
    except CliError as exc:
        print(f"demo: error: {exc}", file=sys.stderr)
        return 2
    if code != 0:
        return code
    jsonl = args.out / "bodies.jsonl"
    records = pick_records(jsonl, frame_of_seq, args.columns)
    png = args.out / "bodies.png"
    render_strip(png, records, frame_of_seq, args.people, args.seed, final["source"]["board"].get("rate_hz", 14.0),
                 final["model"].get("version", ""), args.seconds)
    q = final["source"]["queue"].get("dropped_slow_consumer", 0)
    print(f"\nrecords: {jsonl} ({final['publish']['published']} published, {final['publish']['heartbeats']} heartbeats)")
    print(f"status:  {args.out / 'status.json'} (`cavatar status --file {args.out / 'status.json'}`)")
    print(f"frames:  {args.out / 'frames.json'} (seq → simulator frame)")
    print(f"picture: {png} (truth above, reconstruction below; {len(records)} frames)")
    print(f"frames dropped for a slow pipeline: {q}; ms/frame median {final['stages_ms']['frame']['median_ms']}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

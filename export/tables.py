"""The paper-shaped evaluation: per-frame errors of a model and of the mean-pose baseline, grouped into tables.

    errs = frame_errors(tracks, encode, head, window=40, pitch_m=0.01905)
    base = baseline_errors(mean_pose(train_tracks), tracks, pitch_m=0.01905)
    result = summarise(errs, base)          # overall, per activity, subject, people, joint
    print(markdown(result, title="lean-96 on unseen subjects"))

Metrics (cm and degrees, on every ``frame_stride``-th frame of every track; the functions are
export/metrics.py's):
  MPJPE        mean over the 24 joints of the pelvis-aligned joint error (the lite body's skeleton);
  PA-MPJPE     the same after the best similarity transform of the prediction onto the truth;
  root-aligned the predicted local pose and shape re-posed with the TRUE global orientation,
               pelvis-aligned: what is left when the heading and tilt are right;
  heading      |rotation about the vertical| between predicted and true global orientation:
               median, and the share of frames beyond 45° and beyond 90°;
  PVE          mean over the FULL mesh's 13,348 vertices of the pelvis-aligned vertex error, predicted
               pose and shape against the true pose and shape through the same full body model;
  transl       the pelvis position error in the carpet frame.
With a heading resolver (as the board runs, edge/infer/heading.py) the tables score what it
publishes and add the model's own heading (``model_heading_*``, ``model_mpjpe_cm``) beside it.
The baseline is the mean training pose (per-joint rotation mean, mean betas) placed with its
pelvis over the person's centre of pressure at the mean training pelvis height.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import numpy as np

from edge.body import SMPL_JOINT_NAMES, BodyModel
from export.data import Track
from export.evaluate import predict_track, scored_frames, track_inputs

GROUPS = ("activity", "subject", "people")


def _bodies() -> tuple[BodyModel, BodyModel]:
    return BodyModel.load("lite"), BodyModel.load("full")


def _errors(pose_aa: np.ndarray, betas: np.ndarray, transl_m: np.ndarray, tr: Track, frames: np.ndarray,
            lite: BodyModel, full: BodyModel, model_pose_aa: np.ndarray | None = None) -> dict[str, np.ndarray]:
    from export import metrics

    pj = lite.forward(pose_aa, betas)["joints"]
    gj = tr.joints_m[frames]
    true_pose = tr.pose_aa[frames]
    joint = metrics.joint_errors(pj, gj) * 100
    pm = full.forward(pose_aa, betas, vertices=True)
    gm = full.forward(true_pose, tr.betas[frames], vertices=True)
    n = len(frames)
    out = {"joint_cm": joint, "mpjpe_cm": joint.mean(-1), "pa_mpjpe_cm": metrics.pa_mpjpe(pj, gj) * 100,
           "local_mpjpe_cm": metrics.local_mpjpe(lite, pose_aa, betas, gj, true_pose) * 100,
           "heading_deg": np.degrees(np.abs(metrics.heading_error_rad(pose_aa[:, :3], true_pose[:, :3]))),
           "pve_cm": metrics.pve(pm["vertices"], gm["vertices"], pm["joints"][:, 0], gm["joints"][:, 0]) * 100,
           "transl_cm": np.linalg.norm(transl_m - tr.transl_m[frames], axis=-1) * 100,
           "activity": tr.activity[frames], "subject": np.full(n, tr.subject), "people": np.full(n, tr.people)}
    if model_pose_aa is not None:  # the model's own answer, before the heading resolver
        out["model_mpjpe_cm"] = metrics.mpjpe(lite.forward(model_pose_aa, betas)["joints"], gj) * 100
        out["model_heading_deg"] = np.degrees(np.abs(metrics.heading_error_rad(model_pose_aa[:, :3], true_pose[:, :3])))
    return out


def _concat(parts: list[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}


def frame_errors(tracks: list[Track], encode: Callable, head: Callable, window: int, pitch_m: float,
                 frame_stride: int = 2, seed: int = 0, bodies=None, heading: tuple | None = None,
                 score_from: float = 0.0) -> dict[str, np.ndarray]:
    """Per-frame errors of a model (any encode/head: torch, ONNX, the bundle as the board runs it);
    ``heading``: (params, activity weights) of edge.infer.heading.load to resolve the heading as the board does;
    ``score_from``: score only frames from this fraction of every track on (the time-split protocol)."""
    lite, full = bodies or _bodies()
    parts = []
    for i, tr in enumerate(tracks):
        frames, out = predict_track(tr, encode, head, window, pitch_m, seed + i, frame_stride, heading=heading,
                                    score_from=score_from)
        e = _errors(out["pose_aa"], out["betas"], out["transl_m"], tr, frames, lite, full, out.get("pose_aa_model"))
        e["activity_pred"] = np.argmax(out["activity_logits"], -1)
        e["confidence"] = np.asarray(out["confidence"], float)
        parts.append(e)
    return _concat(parts)


def mean_pose(train_tracks: list[Track]) -> tuple[np.ndarray, np.ndarray, float]:
    """(72,) axis-angle of the per-joint chordal mean rotation, (10,) mean betas, mean pelvis height (m)."""
    from scipy.spatial.transform import Rotation

    pose = np.concatenate([t.pose_aa for t in train_tracks]).reshape(-1, 24, 3)
    mean = np.stack([Rotation.from_rotvec(pose[:, j]).mean().as_rotvec() for j in range(24)])
    betas = np.concatenate([t.betas for t in train_tracks]).mean(0)
    height = float(np.concatenate([t.transl_m[:, 2] for t in train_tracks]).mean())
    return mean.reshape(72), betas, height


def baseline_errors(baseline: tuple[np.ndarray, np.ndarray, float], tracks: list[Track], pitch_m: float, frame_stride: int = 2,
                    seed: int = 0, bodies=None, score_from: float = 0.0) -> dict[str, np.ndarray]:
    """Per-frame errors of the mean training pose at the centre of pressure (same inputs as frame_errors);
    ``baseline`` is :func:`mean_pose` of the training tracks (or a bundle manifest's "baseline")."""
    lite, full = bodies or _bodies()
    pose, betas, height = baseline
    parts = []
    for i, tr in enumerate(tracks):
        _, cop = track_inputs(tr, pitch_m, seed + i)
        frames = scored_frames(len(tr), frame_stride, score_from)
        n = len(frames)
        transl = np.concatenate([cop[frames], np.full((n, 1), height)], -1)
        parts.append(_errors(np.tile(pose, (n, 1)), np.tile(betas, (n, 1)), transl, tr, frames, lite, full))
    return _concat(parts)


def _heading(deg: np.ndarray, prefix: str = "heading") -> dict[str, float]:
    return {f"{prefix}_median_deg": float(np.median(deg)), f"{prefix}_over45_pct": float(100 * (deg > 45).mean()),
            f"{prefix}_over90_pct": float(100 * (deg > 90).mean())}


def _stats(e: dict[str, np.ndarray], sel: np.ndarray) -> dict[str, float]:
    out = {"frames": int(sel.sum()), **{k: float(e[k][sel].mean()) for k in ("mpjpe_cm", "pa_mpjpe_cm", "local_mpjpe_cm")},
           **_heading(e["heading_deg"][sel]), "pve_cm": float(e["pve_cm"][sel].mean()), "transl_cm": float(e["transl_cm"][sel].mean())}
    if "model_heading_deg" in e:
        out["model_mpjpe_cm"] = float(e["model_mpjpe_cm"][sel].mean())
        out.update(_heading(e["model_heading_deg"][sel], "model_heading"))
    return out


def summarise(model: dict[str, np.ndarray], baseline: dict[str, np.ndarray] | None = None) -> dict[str, Any]:
    """Overall and grouped means (model, and the baseline on the same frames), per-joint errors."""
    from sim.motion import ACTIVITIES

    every = np.ones(len(model["mpjpe_cm"]), bool)
    out: dict[str, Any] = {"overall": _stats(model, every)}
    if "activity_pred" in model:
        out["overall"]["activity_accuracy"] = float((model["activity_pred"] == model["activity"]).mean())
    if baseline is not None:
        out["baseline"] = _stats(baseline, every)
        out["overall"]["mpjpe_vs_baseline"] = out["overall"]["mpjpe_cm"] / out["baseline"]["mpjpe_cm"]
    name = {"activity": lambda v: ACTIVITIES[int(v)], "subject": lambda v: f"s{int(v):02d}",
            "people": lambda v: "1 person" if int(v) == 1 else f"{int(v)} people"}
    for g in GROUPS:
        rows = {}
        for v in np.unique(model[g]):
            sel = model[g] == v
            rows[name[g](v)] = {**_stats(model, sel), **({"baseline_mpjpe_cm": float(baseline["mpjpe_cm"][sel].mean()),
                                                          "baseline_pve_cm": float(baseline["pve_cm"][sel].mean())}
                                                         if baseline is not None else {})}
        out[f"by_{g}"] = rows
    out["by_joint_cm"] = {n: float(v) for n, v in zip(SMPL_JOINT_NAMES, model["joint_cm"].mean(0))}
    if baseline is not None:
        out["baseline_by_joint_cm"] = {n: float(v) for n, v in zip(SMPL_JOINT_NAMES, baseline["joint_cm"].mean(0))}
    return out


def _row(cells: list[Any]) -> str:
    return "| " + " | ".join(f"{c:.2f}" if isinstance(c, float) else str(c) for c in cells) + " |"


METRIC_HEADER = "| frames | MPJPE | PA-MPJPE | root-aligned | heading median ° | >45° % | >90° % | PVE | translation |"


def metric_cells(r: dict[str, Any], prefix: str = "") -> list[Any]:
    """The cells of METRIC_HEADER for one row of :func:`summarise` (``prefix="model_"``: the model's own heading)."""
    if prefix:
        return [r["frames"], r["model_mpjpe_cm"], r["pa_mpjpe_cm"], r["local_mpjpe_cm"], r["model_heading_median_deg"],
                r["model_heading_over45_pct"], r["model_heading_over90_pct"], "–", r["transl_cm"]]
    return [r["frames"], r["mpjpe_cm"], r["pa_mpjpe_cm"], r["local_mpjpe_cm"], r["heading_median_deg"],
            r["heading_over45_pct"], r["heading_over90_pct"], r["pve_cm"], r["transl_cm"]]


def markdown(result: dict[str, Any], title: str) -> str:
    """The tables of :func:`summarise` in Markdown (cm, degrees, % of frames)."""
    lines = [f"## {title}", ""]
    o = result["overall"]
    model = "model" + (" (heading resolved)" if "model_mpjpe_cm" in o else "")
    lines += ["| " + METRIC_HEADER, "|---" * 10 + "|", _row([model] + metric_cells(o))]
    if "model_mpjpe_cm" in o:
        lines.append(_row(["model alone (heading not resolved)"] + metric_cells(o, "model_")))
    if "baseline" in result:
        b = result["baseline"]
        lines.append(_row(["mean pose at CoP (baseline)"] + metric_cells(b)))
        lines += ["", f"Model MPJPE is {100 * (1 - o['mpjpe_vs_baseline']):.0f} % below the baseline's."]
    if "activity_accuracy" in o:
        lines.append(f"Activity accuracy {100 * o['activity_accuracy']:.1f} %.")
    for g in GROUPS:
        rows = result[f"by_{g}"]
        with_base = rows and "baseline_mpjpe_cm" in next(iter(rows.values()))
        lines += ["", f"### per {g}", "", "| " + g + " " + METRIC_HEADER + (" baseline MPJPE | baseline PVE |" if with_base else ""),
                  "|---" * 10 + "|" + ("---|---|" if with_base else "")]
        for k, r in rows.items():
            lines.append(_row([k] + metric_cells(r) + ([r["baseline_mpjpe_cm"], r["baseline_pve_cm"]] if with_base else [])))
    lines += ["", "### per joint (cm)", "", "| joint | error |" + (" baseline |" if "baseline_by_joint_cm" in result else ""),
              "|---|---|" + ("---|" if "baseline_by_joint_cm" in result else "")]
    for k, v in result["by_joint_cm"].items():
        lines.append(_row([k, v] + ([result["baseline_by_joint_cm"][k]] if "baseline_by_joint_cm" in result else [])))
    return "\n".join(lines) + "\n"


def evaluate_bundle(bundle: str | Path, tracks: list[Track], pitch_m: float, frame_stride: int = 2,
                    baseline: tuple[np.ndarray, np.ndarray, float] | None = None, resolve_heading: bool = True,
                    heading_params: str | Path | None = None, score_from: float = 0.0) -> dict[str, Any]:
    """The bundle as the board loads it (onnxruntime, this machine's kernels; the heading resolved as the
    board does unless ``resolve_heading`` is False) beside the baseline: summarise()."""
    from edge.infer import heading as heading_cue
    from edge.infer import verify
    from export.evaluate import bundle_callables

    encode, head, window = bundle_callables(bundle)
    heading = heading_cue.load(heading_params, verify(bundle)["activities"]) if resolve_heading else None
    bodies = _bodies()
    model = frame_errors(tracks, encode, head, window, pitch_m, frame_stride=frame_stride, bodies=bodies, heading=heading,
                         score_from=score_from)
    base = (baseline_errors(baseline, tracks, pitch_m, frame_stride=frame_stride, bodies=bodies, score_from=score_from)
            if baseline is not None else None)
    return summarise(model, base)


README_BEGIN, README_END = "<!-- model-table:begin -->", "<!-- model-table:end -->"


def protocols_markdown(results: dict[str, dict[str, Any]]) -> str:
    """One overall row per protocol (name → a ``cavatar eval`` JSON), the model's own heading beside the
    resolved one when the result has it, and the mean-pose baseline: the README's model table."""
    lines = ["| protocol | heading " + METRIC_HEADER, "|---" * 11 + "|"]
    for name, r in results.items():
        o = r["overall"]
        if "model_mpjpe_cm" in o:
            lines.append(_row([name, "model alone"] + metric_cells(o, "model_")))
        lines.append(_row([name, "resolved from the feet" if "model_mpjpe_cm" in o else "model alone"] + metric_cells(o)))
        if "baseline" in r:
            lines.append(_row([name, "mean pose at CoP (baseline)"] + metric_cells(r["baseline"])))
    return "\n".join(lines) + "\n"


def replace_block(text: str, block: str, begin: str = README_BEGIN, end: str = README_END) -> str:
    """``text`` with what lies between the ``begin`` and ``end`` markers replaced by ``block``; ValueError without them."""
    i, j = text.find(begin), text.find(end)
    if i < 0 or j < i:
        raise ValueError(f"no {begin} … {end} block to replace")
    return text[:i + len(begin)] + "\n" + block + text[j:]


def main(argv: list[str] | None = None) -> int:
    """python -m export.tables --readme README.md NAME=EVAL.json …: regenerate the README's model table."""
    import argparse
    import json
    import sys

    ap = argparse.ArgumentParser(prog="python -m export.tables", description=main.__doc__)
    ap.add_argument("--readme", required=True, help="file holding the model-table block")
    ap.add_argument("results", nargs="+", metavar="NAME=EVAL.json", help="a protocol's name and its `cavatar eval` JSON")
    args = ap.parse_args(argv)
    results, sources = {}, []
    for item in args.results:
        name, sep, path = item.partition("=")
        if not sep:
            print(f"error: expected NAME=EVAL.json, got {item!r}", file=sys.stderr)
            return 2
        try:
            results[name] = json.loads(Path(path).read_text())
        except (OSError, ValueError) as exc:
            print(f"error: {path}: {exc}", file=sys.stderr)
            return 2
        s = results[name].get("setup", {})
        subjects = s.get("subjects", [])
        who = ", ".join(subjects) if len(subjects) <= 6 else f"{len(subjects)} subjects"
        sources.append(f"{name}: {s.get('bundle', '?')}, {s.get('protocol', '?')}; {who}; frame stride "
                       f"{s.get('frame_stride', '?')}; `{path}`")
    readme = Path(args.readme)
    try:
        if not readme.is_file():
            raise ValueError("no such file")
        text = replace_block(readme.read_text(), protocols_markdown(results) + "\n" + "\n".join(f"- {x}" for x in sources) + "\n")
    except ValueError as exc:
        print(f"error: {readme}: {exc}", file=sys.stderr)
        return 2
    readme.write_text(text)
    print(f"wrote the model table of {readme}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

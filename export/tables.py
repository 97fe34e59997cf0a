"""The paper-shaped evaluation: per-frame errors of a model and of the mean-pose baseline, grouped into tables.

    errs = frame_errors(tracks, encode, head, window=40, pitch_m=0.01905)
    base = baseline_errors(mean_pose(train_tracks), tracks, pitch_m=0.01905)
    result = summarise(errs, base)          # overall, per activity, subject, people, joint
    print(markdown(result, title="lean-96 on unseen subjects"))

Metrics (cm, on every ``frame_stride``-th frame of every track):
  MPJPE  mean over the 24 joints of the pelvis-aligned joint error (the lite body's skeleton);
  PVE    mean over the FULL mesh's 13,348 vertices of the pelvis-aligned vertex error, predicted
         pose and shape against the true pose and shape through the same full body model;
  transl the pelvis position error in the carpet frame.
The baseline is the mean training pose (per-joint rotation mean, mean betas) placed with its
pelvis over the person's centre of pressure at the mean training pelvis height.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any, Callable

import numpy as np

from edge.body import SMPL_JOINT_NAMES, BodyModel
from export.data import Track
from export.evaluate import predict_track, track_inputs

GROUPS = ("activity", "subject", "people")


def _bodies() -> tuple[BodyModel, BodyModel]:
    return BodyModel.load("lite"), BodyModel.load("full")


def _errors(pose_aa: np.ndarray, betas: np.ndarray, transl_m: np.ndarray, tr: Track, frames: np.ndarray,
            lite: BodyModel, full: BodyModel) -> dict[str, np.ndarray]:
    pj = lite.forward(pose_aa, betas)["joints"]
    gj = tr.joints_m[frames]
    joint = np.linalg.norm((pj - pj[:, :1]) - (gj - gj[:, :1]), axis=-1) * 100
    pm = full.forward(pose_aa, betas, vertices=True)
    gm = full.forward(tr.pose_aa[frames], tr.betas[frames], vertices=True)
    pv = pm["vertices"] - pm["joints"][:, :1]
    gv = gm["vertices"] - gm["joints"][:, :1]
    pve = np.linalg.norm(pv - gv, axis=-1).mean(-1) * 100
    transl = np.linalg.norm(transl_m - tr.transl_m[frames], axis=-1) * 100
    n = len(frames)
    return {"joint_cm": joint, "mpjpe_cm": joint.mean(-1), "pve_cm": pve, "transl_cm": transl,
            "activity": tr.activity[frames], "subject": np.full(n, tr.subject), "people": np.full(n, tr.people)}


def _concat(parts: list[dict[str, np.ndarray]]) -> dict[str, np.ndarray]:
    return {k: np.concatenate([p[k] for p in parts]) for k in parts[0]}


def frame_errors(tracks: list[Track], encode: Callable, head: Callable, window: int, pitch_m: float,
                 frame_stride: int = 2, seed: int = 0, bodies=None) -> dict[str, np.ndarray]:
    """Per-frame errors of a model (any encode/head: torch, ONNX, the bundle as the board runs it)."""
    lite, full = bodies or _bodies()
    parts = []
    for i, tr in enumerate(tracks):
        frames, out = predict_track(tr, encode, head, window, pitch_m, seed + i, frame_stride)
        e = _errors(out["pose_aa"], out["betas"], out["transl_m"], tr, frames, lite, full)
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
                    seed: int = 0, bodies=None) -> dict[str, np.ndarray]:
    """Per-frame errors of the mean training pose at the centre of pressure (same inputs as frame_errors);
    ``baseline`` is :func:`mean_pose` of the training tracks (or a bundle manifest's "baseline")."""
    lite, full = bodies or _bodies()
    pose, betas, height = baseline
    parts = []
    for i, tr in enumerate(tracks):
        _, cop = track_inputs(tr, pitch_m, seed + i)
        frames = np.arange(0, len(tr), frame_stride)
        n = len(frames)
        transl = np.concatenate([cop[frames], np.full((n, 1), height)], -1)
        parts.append(_errors(np.tile(pose, (n, 1)), np.tile(betas, (n, 1)), transl, tr, frames, lite, full))
    return _concat(parts)


def _stats(e: dict[str, np.ndarray], sel: np.ndarray) -> dict[str, float]:
    return {"frames": int(sel.sum()), "mpjpe_cm": float(e["mpjpe_cm"][sel].mean()), "pve_cm": float(e["pve_cm"][sel].mean()),
            "transl_cm": float(e["transl_cm"][sel].mean())}


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
    name = {"activity": lambda v: ACTIVITIES[int(v)], "subject": lambda v: f"s{int(v):02d}", "people": lambda v: "1 person" if int(v) == 1 else f"{int(v)} people"}
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


def markdown(result: dict[str, Any], title: str) -> str:
    """The tables of :func:`summarise` in Markdown (cm)."""
    lines = [f"## {title}", ""]
    o = result["overall"]
    lines += ["| | frames | MPJPE | PVE | translation |", "|---|---|---|---|---|", _row(["model", o["frames"], o["mpjpe_cm"], o["pve_cm"], o["transl_cm"]])]
    if "baseline" in result:
        b = result["baseline"]
        lines.append(_row(["mean pose at CoP (baseline)", b["frames"], b["mpjpe_cm"], b["pve_cm"], b["transl_cm"]]))
        lines += ["", f"Model MPJPE is {100 * (1 - o['mpjpe_vs_baseline']):.0f} % below the baseline's."]
    if "activity_accuracy" in o:
        lines.append(f"Activity accuracy {100 * o['activity_accuracy']:.1f} %.")
    for g in GROUPS:
        rows = result[f"by_{g}"]
        with_base = rows and "baseline_mpjpe_cm" in next(iter(rows.values()))
        lines += ["", f"### per {g}", "", "| " + g + " | frames | MPJPE | PVE | translation |" + (" baseline MPJPE | baseline PVE |" if with_base else ""),
                  "|---|---|---|---|---|" + ("---|---|" if with_base else "")]
        for k, r in rows.items():
            cells = [k, r["frames"], r["mpjpe_cm"], r["pve_cm"], r["transl_cm"]]
            lines.append(_row(cells + ([r["baseline_mpjpe_cm"], r["baseline_pve_cm"]] if with_base else [])))
    lines += ["", "### per joint (cm)", "", "| joint | error |" + (" baseline |" if "baseline_by_joint_cm" in result else ""),
              "|---|---|" + ("---|" if "baseline_by_joint_cm" in result else "")]
    for k, v in result["by_joint_cm"].items():
        lines.append(_row([k, v] + ([result["baseline_by_joint_cm"][k]] if "baseline_by_joint_cm" in result else [])))
    return "\n".join(lines) + "\n"


def evaluate_bundle(bundle: str | Path, tracks: list[Track], pitch_m: float, frame_stride: int = 2,
                    baseline: tuple[np.ndarray, np.ndarray, float] | None = None) -> dict[str, Any]:
    """The bundle as the board loads it (onnxruntime, this machine's kernels) beside the baseline: summarise()."""
    from export.bundle import bundle_callables

    encode, head, window = bundle_callables(bundle)
    bodies = _bodies()
    model = frame_errors(tracks, encode, head, window, pitch_m, frame_stride=frame_stride, bodies=bodies)
    base = baseline_errors(baseline, tracks, pitch_m, frame_stride=frame_stride, bodies=bodies) if baseline is not None else None
    return summarise(model, base)

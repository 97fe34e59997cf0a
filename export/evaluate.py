"""End-to-end metrics over person tracks with any encoder/head (torch, ONNX fp32, int8).

    m = track_metrics(tracks, encode, head, window=40, pitch_m=0.01905, body=BodyModel.load("lite"))

``encode`` maps (B,1,H,W) float32 → (B,F); ``head`` maps (B,T,F) → dict with rot6d, betas,
transl_rel_m, activity_logits, confidence (numpy). Inputs are each track's pressure through the
training corruption with a fixed seed per track, so every variant sees the same frames.
MPJPE is pelvis-aligned over the 24 joints, in cm; the translation error is of the pelvis.
:func:`bundle_callables` gives the (encode, head, window) of a bundle loaded as the board loads it.
"""

from __future__ import annotations

from pathlib import Path
from typing import Callable

import numpy as np

from edge.infer.heading import resolve_sequence, sequence_cues
from edge.infer.normalise import center_of_pressure_m, normalise_kpa
from edge.infer.rotations import rot6d_to_axis_angle
from export import metrics
from export.data import Track, corrupt

Encode = Callable[[np.ndarray], np.ndarray]
Head = Callable[[np.ndarray], dict]


def track_pressure(track: Track, seed: int) -> np.ndarray:
    """(L,H,W) float32 kPa: the track's pressure through the training corruption, deterministic for a seed;
    a board's-path track (``track.board``) only floored and clipped, as the runtime does (edge.infer.model_input)."""
    if track.board:
        from edge.infer.model_input import FLOOR_KPA, SATURATION_KPA

        kpa = track.pressure_kpa.astype(np.float32)
        kpa[kpa < FLOOR_KPA] = 0.0
        return np.minimum(kpa, np.float32(SATURATION_KPA))
    return corrupt(track.pressure_kpa.astype(np.float32), np.random.default_rng(seed)).numpy()


def track_inputs(track: Track, pitch_m: float, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """(L,1,H,W) normalised inputs and (L,2) CoP in metres, deterministic for a seed."""
    p = track_pressure(track, seed)
    return normalise_kpa(p)[:, None], center_of_pressure_m(p, pitch_m)


def predict(inputs: np.ndarray, encode: Encode, head: Head, window: int, batch: int = 64,
            frames: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Outputs for ``frames`` (default all) of one track; history before frame 0 = frame 0's features."""
    feats = np.concatenate([encode(inputs[i:i + batch]) for i in range(0, len(inputs), batch)])
    padded = np.concatenate([np.repeat(feats[:1], window - 1, 0), feats])
    frames = np.arange(len(inputs)) if frames is None else np.asarray(frames)
    outs: dict[str, list] = {}
    for i in range(0, len(frames), batch):
        idx = frames[i:i + batch]
        windows = np.stack([padded[f:f + window] for f in idx]).astype(np.float32)
        for k, v in head(windows).items():
            outs.setdefault(k, []).append(np.asarray(v))
    return {k: np.concatenate(v) for k, v in outs.items()}


def scored_frames(length: int, frame_stride: int = 1, score_from: float = 0.0) -> np.ndarray:
    """Every ``frame_stride``-th frame index from ``score_from`` × ``length`` on."""
    return np.arange(int(np.ceil(score_from * length)), length, frame_stride)


def predict_track(tr: Track, encode: Encode, head: Head, window: int, pitch_m: float, seed: int,
                  frame_stride: int = 1, heading: tuple | None = None,
                  score_from: float = 0.0) -> tuple[np.ndarray, dict[str, np.ndarray]]:
    """(frames, outputs) for every ``frame_stride``-th frame of one track from ``score_from`` (a fraction of
    its length: the model still sees the frames before, as a live stream would); outputs add ``pose_aa``,
    ``betas`` clipped to ±5 and ``transl_m`` (the relative translation put back over the CoP).

    ``heading``: (params, activity weights) of :func:`edge.infer.heading.load`: every frame of the track
    goes through a heading resolver as on the board, ``pose_aa`` is what it publishes and
    ``pose_aa_model`` the model's own answer."""
    kpa = track_pressure(tr, seed)
    inputs, cop = normalise_kpa(kpa)[:, None], center_of_pressure_m(kpa, pitch_m)
    frames = scored_frames(len(tr), frame_stride, score_from)
    out = predict(inputs, encode, head, window, frames=np.arange(len(tr)) if heading is not None else frames)
    out["pose_aa"] = rot6d_to_axis_angle(out["rot6d"])
    if heading is not None:
        params, weights = heading
        logits = out["activity_logits"].astype(np.float64)
        probs = np.exp(logits - logits.max(-1, keepdims=True))
        probs /= probs.sum(-1, keepdims=True)
        cues = sequence_cues(kpa, pitch_m, params)
        out["pose_aa_model"] = out["pose_aa"]
        out["pose_aa"] = resolve_sequence(out["pose_aa"], cues, probs, params, weights)
        out = {k: v[frames] for k, v in out.items()}
    out["betas"] = np.clip(out["betas"], -5, 5)
    out["transl_m"] = out["transl_rel_m"] + np.concatenate([cop[frames], np.zeros((len(frames), 1))], -1)
    return frames, out


def track_metrics(tracks: list[Track], encode: Encode, head: Head, window: int, pitch_m: float, body,
                  frame_stride: int = 1, seed: int = 0) -> dict[str, float]:
    """Mean MPJPE (cm, pelvis-aligned), pelvis translation error (cm), activity accuracy over tracks."""
    err, terr, acc = [], [], []
    for i, tr in enumerate(tracks):
        frames, out = predict_track(tr, encode, head, window, pitch_m, seed + i, frame_stride)
        joints = body.forward(out["pose_aa"], out["betas"])["joints"]
        gt = tr.joints_m[frames]
        err.append(metrics.mpjpe(joints, gt))
        terr.append(np.linalg.norm(out["transl_m"] - tr.transl_m[frames], axis=-1))
        acc.append(np.argmax(out["activity_logits"], -1) == tr.activity[frames])
    err, terr, acc = np.concatenate(err), np.concatenate(terr), np.concatenate(acc)
    return {"mpjpe_cm": float(err.mean() * 100), "transl_cm": float(terr.mean() * 100),
            "activity_acc": float(acc.mean()), "frames": int(len(err))}


def torch_callables(net, frame_head=None) -> tuple[Encode, Head]:
    """encode/head callables over a torch CAvatarNet (eval mode, no grad); with ``frame_head``
    (the `frames` training stage's) the head sees only each window's last frame."""
    import torch

    from export.model.heads import OUTPUTS

    net.eval()
    if frame_head is not None:
        frame_head.eval()

    def encode(x: np.ndarray) -> np.ndarray:
        with torch.no_grad():
            return net.encoder(torch.from_numpy(np.ascontiguousarray(x, np.float32))).numpy()

    def head(w: np.ndarray) -> dict:
        with torch.no_grad():
            w = torch.from_numpy(w)
            outs = frame_head(w[:, -1]) if frame_head is not None else net.head(w)
            return {k: v.numpy() for k, v in zip(OUTPUTS, outs)}

    return encode, head


def bundle_callables(folder: str | Path):
    """(encode, head, window) of a bundle loaded as the board loads it; head returns the raw graph outputs."""
    from edge.infer import ModelBundle
    from export.model.heads import OUTPUTS

    b = ModelBundle.load(folder)

    def head(w):
        out = b.head_outputs(w)
        return {k: out[k] for k in OUTPUTS}

    return b.encode, head, b.window

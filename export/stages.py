"""Training stages that make CPU training work: i.i.d. frames for the encoder, cached features for the head.

The end-to-end stage (`windows`, train.py) encodes B+T-1 consecutive frames of ONE track per
chunk: every gradient step then sees one person doing one activity, and on a CPU that can
afford one or two chunks per step the gradient swings from activity to activity (measured
here: 3,000 steps of lean at lr 1e-3 stayed at chance activity accuracy and above the
mean-pose baseline's MPJPE). Two cheaper stages come first:

``frames``  the per-frame encoder with an auxiliary one-frame head (heads.FrameHead), on B frames
            drawn independently from all tracks: every step sees every activity and subject.
``head``    the encoder frozen; every training frame is encoded once per corruption copy into a
            feature cache (:class:`FeatureCache`), and the temporal head trains on B windows drawn
            independently from the cache: a step costs only the head.

Then ``windows`` may fine-tune both end to end from the ``head`` stage's weights (``--init``).
"""

from __future__ import annotations

import numpy as np
import torch

from edge.infer.normalise import center_of_pressure_m
from export.data import Track, chunk_indices, corrupt

STAGES = ("windows", "frames", "head")


def _targets(tr: Track, idx: np.ndarray, cop_m: np.ndarray, device) -> dict[str, torch.Tensor]:
    """Targets of frames ``idx`` of one track; ``cop_m`` (len(idx),2) of the inputs the model saw."""
    transl_rel = tr.transl_m[idx] - np.concatenate([cop_m, np.zeros((len(idx), 1))], -1)
    joints = tr.joints_m[idx]
    return {"pose_aa": tr.pose_aa[idx], "betas": tr.betas[idx], "transl_rel_m": transl_rel,
            "activity": tr.activity[idx], "joints_m": joints - joints[:, :1]}


def _stack(parts: list[dict[str, np.ndarray]], device) -> dict[str, torch.Tensor]:
    out = {}
    for k in parts[0]:
        a = np.concatenate([p[k] for p in parts])
        out[k] = torch.as_tensor(np.ascontiguousarray(a), dtype=torch.long if k == "activity" else torch.float32, device=device)
    return out


def pick(rng: np.random.Generator, weights: np.ndarray, n: int) -> np.ndarray:
    """``n`` track indices drawn with probability proportional to track length."""
    return rng.choice(len(weights), size=n, p=weights)


def sample_frames(tracks: list[Track], weights: np.ndarray, n: int, pitch_m: float, rng: np.random.Generator,
                  device) -> dict[str, torch.Tensor]:
    """``n`` frames drawn independently (track by length, then frame uniformly), each corrupted on its own."""
    xs, parts = [], []
    for ti in pick(rng, weights, n):
        tr = tracks[int(ti)]
        f = np.array([int(rng.integers(len(tr)))])
        p = corrupt(tr.pressure_kpa[f].astype(np.float32), rng)
        xs.append(torch.log1p(p))                                               # NORMALISATION (log1p, 1 kPa)
        parts.append(_targets(tr, f, center_of_pressure_m(p.numpy(), pitch_m), device))
    return {"x": torch.cat(xs)[:, None].to(device), **_stack(parts, device)}


class FeatureCache:
    """Encoder features of every frame of every track, ``copies`` corruptions each, and the CoP of each input.

    feats[c][i]: (len(track i), F) float32; cop[c][i]: (len(track i), 2). Deterministic for a seed.
    """

    def __init__(self, encoder: torch.nn.Module, tracks: list[Track], pitch_m: float, copies: int = 2, seed: int = 0,
                 batch: int = 256, device="cpu", progress=None):
        self.feats: list[list[np.ndarray]] = []
        self.cop: list[list[np.ndarray]] = []
        encoder.eval()
        total = copies * sum(len(t) for t in tracks)
        done = 0
        with torch.no_grad():
            for c in range(copies):
                fc, cc = [], []
                for i, tr in enumerate(tracks):
                    rng = np.random.default_rng([seed, c, i])
                    p = corrupt(tr.pressure_kpa.astype(np.float32), rng)
                    x = torch.log1p(p)[:, None]
                    fc.append(np.concatenate([encoder(x[s:s + batch].to(device)).cpu().numpy() for s in range(0, len(x), batch)]))
                    cc.append(center_of_pressure_m(p.numpy(), pitch_m))
                    done += len(tr)
                    if progress:
                        progress(done, total)
                self.feats.append(fc)
                self.cop.append(cc)
        self.copies = copies

    def sample(self, tracks: list[Track], weights: np.ndarray, n: int, window: int, rng: np.random.Generator,
               device) -> dict[str, torch.Tensor]:
        """``n`` causal windows drawn independently: (n,T,F) features and the targets of their last frames.
        A window reaching before a track's first frame repeats that frame (as the runtime does)."""
        ws, parts = [], []
        for ti in pick(rng, weights, n):
            ti = int(ti)
            tr = tracks[ti]
            c = int(rng.integers(self.copies))
            end = int(rng.integers(len(tr)))
            idx = chunk_indices(len(tr), end - window + 1, window)
            ws.append(self.feats[c][ti][idx])
            parts.append(_targets(tr, idx[-1:], self.cop[c][ti][idx[-1:]], device))
        return {"windows": torch.as_tensor(np.stack(ws), device=device), **_stack(parts, device)}

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

Both stages turn the whole carpet by a multiple of 90° about its centre (:func:`turn`: the frame by
``np.rot90``, exact; the global orientation, pelvis and joints by the same rotation about z). Measured
without it: every subject's sequences face a few headings, so the encoder learned "this person at this
spot faces there" — 7° global-orientation error on training subjects, a median 139° (most frames turned
round) on unseen ones. Turned copies leave the footprint itself as the only heading cue.
"""

from __future__ import annotations

import numpy as np
import torch

from edge.infer.normalise import center_of_pressure_m
from export.data import Track, chunk_indices, training_input

STAGES = ("windows", "frames", "head")


def turn_frames(pressure: np.ndarray, k: int) -> np.ndarray:
    """(…,N,N) frames of a square carpet turned by k·90° about its centre (counter-clockwise seen from
    above, x along columns, y along rows): sensel (r, c) → (c, N−1−r) per quarter turn."""
    if pressure.shape[-1] != pressure.shape[-2]:
        raise ValueError("quarter turns need a square carpet")
    return np.ascontiguousarray(np.rot90(pressure, -(k % 4), axes=(-2, -1)))


def turn_labels(pose_aa: np.ndarray, transl_m: np.ndarray, joints_m: np.ndarray, k: int, side_m: float):
    """The labels of :func:`turn_frames`: the global orientation pre-multiplied by Rz(k·90°), the joint
    rotations unchanged, pelvis (…,3) and joints (…,24,3) rotated about the carpet centre (x' − cx = −(y − cy),
    y' − cy = x − cx per quarter turn)."""
    from scipy.spatial.transform import Rotation

    k %= 4
    if k == 0:
        return pose_aa, transl_m, joints_m
    c, s = [(1, 0), (0, 1), (-1, 0), (0, -1)][k]
    q = np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]], np.float64)
    centre = np.array([side_m / 2, side_m / 2, 0.0])
    pose = np.array(pose_aa, np.float32, copy=True)
    glob = Rotation.from_matrix(q) * Rotation.from_rotvec(pose[..., :3].reshape(-1, 3).astype(np.float64))
    pose[..., :3] = glob.as_rotvec().reshape(pose[..., :3].shape)
    return pose, ((transl_m - centre) @ q.T + centre).astype(np.float32), ((joints_m - centre) @ q.T + centre).astype(np.float32)


def _targets(tr: Track, idx: np.ndarray, cop_m: np.ndarray, k: int = 0, side_m: float = 0.0) -> dict[str, np.ndarray]:
    """Targets of frames ``idx`` of one track turned by k quarter turns; ``cop_m`` (len(idx),2) of the
    (turned) inputs the model saw."""
    pose, transl, joints = turn_labels(tr.pose_aa[idx], tr.transl_m[idx], tr.joints_m[idx], k, side_m)
    transl_rel = transl - np.concatenate([cop_m, np.zeros((len(idx), 1))], -1)
    return {"pose_aa": pose, "betas": tr.betas[idx], "transl_rel_m": transl_rel,
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
                  device, turns: bool = True) -> dict[str, torch.Tensor]:
    """``n`` frames drawn independently (track by length, then frame uniformly), each turned by a random
    quarter turn (``turns``) and corrupted on its own."""
    xs, parts = [], []
    side_m = tracks[0].pressure_kpa.shape[-1] * pitch_m
    for ti in pick(rng, weights, n):
        tr = tracks[int(ti)]
        f = np.array([int(rng.integers(len(tr)))])
        k = int(rng.integers(4)) if turns else 0
        p = training_input(turn_frames(tr.pressure_kpa[f].astype(np.float32), k), rng, tr.board)
        xs.append(torch.log1p(p))                                               # NORMALISATION (log1p, 1 kPa)
        parts.append(_targets(tr, f, center_of_pressure_m(p.numpy(), pitch_m), k, side_m))
    return {"x": torch.cat(xs)[:, None].to(device), **_stack(parts, device)}


class FeatureCache:
    """Encoder features of every frame of every track, ``copies`` corruptions each, and the CoP of each input.

    Copy c is turned by c quarter turns (when ``turns``: with 4 copies every heading of the scene is seen).
    feats[c][i]: (len(track i), F) float32; cop[c][i]: (len(track i), 2). Deterministic for a seed.
    """

    def __init__(self, encoder: torch.nn.Module, tracks: list[Track], pitch_m: float, copies: int = 2, seed: int = 0,
                 batch: int = 256, device="cpu", progress=None, turns: bool = True):
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
                    p = training_input(turn_frames(tr.pressure_kpa.astype(np.float32), c if turns else 0), rng, tr.board)
                    x = torch.log1p(p)[:, None]
                    fc.append(np.concatenate([encoder(x[s:s + batch].to(device)).cpu().numpy() for s in range(0, len(x), batch)]))
                    cc.append(center_of_pressure_m(p.numpy(), pitch_m))
                    done += len(tr)
                    if progress:
                        progress(done, total)
                self.feats.append(fc)
                self.cop.append(cc)
        self.copies = copies
        self.turns = turns
        self.side_m = tracks[0].pressure_kpa.shape[-1] * pitch_m if tracks else 0.0

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
            parts.append(_targets(tr, idx[-1:], self.cop[c][ti][idx[-1:]], c if self.turns else 0, self.side_m))
        return {"windows": torch.as_tensor(np.stack(ws), device=device), **_stack(parts, device)}

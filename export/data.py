"""Training data from a simulated dataset: one track per person, sensor-realistic inputs.

Choice (documented in every bundle manifest, TRAINING_INPUT): the input is the simulator's
TRUE pressure_kpa passed through a cheap sensor corruption at training time (per-chunk gain
×U(0.85, 1.15), per-sensel gain jitter 5 %, additive noise σ 0.1 kPa, a 0.2 kPa floor below
which a calibrated board reads 0, saturation censoring at 14 kPa), not the raw counts through
a calibration: it is fast, and it spans more carpets than the generator's few.
``load_tracks(..., board=True)`` reads the board's path instead (TRAINING_INPUT_BOARD): the raw
counts through each carpet's calibration, for datasets generated with ``--calibration``.

Several people: the generator's pressure is the sum over people. Each person gets their own
input: a loaded sensel belongs to the person whose nearest joint ground projection is
closest, dilated by 2 sensels and limited to that person (a runtime gets the same from
edge.scene's per-person masks). A single person's input is the whole frame of true pressure;
on the board's path every person, alone or not, is masked to the true load's footprint grown by
2 sensels (the runtime's mask: contacts grown by mask_margin_mm, 40 mm), so what a faulty line or a
drifting tile reads far from anyone never reaches the model, as at runtime.
"""

from __future__ import annotations

from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np
from scipy import ndimage

SATURATION_KPA = 14.0
TRAINING_INPUT = ("true pressure_kpa with sensor corruption: gain ×U(0.85,1.15) per chunk, per-sensel gain σ 5 %, "
                  "noise σ 0.1 kPa, floor 0.2 kPa → 0, saturation at 14 kPa; other people masked out by nearest-joint "
                  "assignment of loaded sensels (dilated 2 sensels)")
TRAINING_INPUT_BOARD = ("the board's path: raw sensor-model counts (per-carpet gains, curve, crosstalk, hysteresis, "
                        "saturation, faults, noise) through each carpet's calibration (calibration.apply), floored at "
                        "0.2 kPa and clipped at 14 kPa as the runtime does, gain ×U(0.92,1.08); each person masked to "
                        "the true load's footprint grown by 2 sensels (nearest-joint assignment between people)")


@dataclass
class Track:
    """One person in one sequence: frames (N,H,W) of their own true pressure and their ground truth."""

    pressure_kpa: np.ndarray   # (N,H,W) float16
    pose_aa: np.ndarray        # (N,72) float32
    betas: np.ndarray          # (N,10)
    transl_m: np.ndarray       # (N,3)
    joints_m: np.ndarray       # (N,24,3)
    activity: np.ndarray       # (N,) int64
    subject: int
    people: int                # number of people in the scene
    board: bool = False        # pressure_kpa is the board's path (load_tracks(board=True)), not the truth

    def __len__(self) -> int:
        return len(self.pose_aa)

    def slice(self, start: int, stop: int) -> "Track":
        """Frames start:stop of this track (views, no copy)."""
        s = slice(start, stop)
        return replace(self, pressure_kpa=self.pressure_kpa[s], pose_aa=self.pose_aa[s], betas=self.betas[s],
                       transl_m=self.transl_m[s], joints_m=self.joints_m[s], activity=self.activity[s])


def person_masks(pressure_kpa: np.ndarray, joints_m: np.ndarray, present: np.ndarray, pitch_m: float,
                 floor_kpa: float = 0.2, dilate: int = 2) -> np.ndarray:
    """(H,W) pressure, (P,24,3) joints, (P,) present → (P,H,W) bool masks, nearest-joint assignment."""
    h, w = pressure_kpa.shape
    masks = np.zeros((len(present), h, w), bool)
    people = np.flatnonzero(present)
    loaded = pressure_kpa > floor_kpa
    if len(people) == 1:
        masks[people[0]] = True
        return masks
    rr, cc = np.nonzero(loaded)
    centres = np.stack([(cc + 0.5) * pitch_m, (rr + 0.5) * pitch_m], -1)                    # (K,2)
    dist = np.stack([np.linalg.norm(centres[:, None] - joints_m[p, None, :, :2], axis=-1).min(1) for p in people], 0)
    owner = people[np.argmin(dist, 0)] if len(rr) else np.zeros(0, int)
    for p in people:
        own = np.zeros((h, w), bool)
        own[rr[owner == p], cc[owner == p]] = True
        grown = ndimage.binary_dilation(own, iterations=dilate) if dilate else own
        others = loaded & ~own
        masks[p] = grown & ~others
    return masks


def footprint_masks(true_kpa: np.ndarray, joints_m: np.ndarray, present: np.ndarray, pitch_m: float,
                    floor_kpa: float = 0.2, dilate: int = 2) -> np.ndarray:
    """(H,W) true pressure, (P,24,3) joints, (P,) present → (P,H,W) bool: each person's loaded sensels
    (nearest-joint assignment between several) grown by ``dilate`` sensels — alone too, unlike person_masks."""
    people = np.flatnonzero(present)
    if len(people) > 1:
        return person_masks(true_kpa, joints_m, present, pitch_m, floor_kpa, dilate)
    masks = np.zeros((len(present),) + true_kpa.shape, bool)
    if len(people):
        masks[people[0]] = ndimage.binary_dilation(true_kpa > floor_kpa, iterations=dilate)
    return masks


def load_tracks(dataset, split: str, max_tracks: int | None = None, board: bool = False) -> list[Track]:
    """All person tracks of a split (a ``sim.dataset.Dataset`` or its path); contiguous present runs.

    board: the input is what a board reads (TRAINING_INPUT_BOARD) — the raw counts through each
    carpet's calibration (``cavatar sim generate --calibration installer|truth``) — instead of
    the true pressure; the ground truth is the same. Train on it without ``corrupt``.
    """
    from sim.dataset import Dataset

    ds = dataset if hasattr(dataset, "shards") else Dataset(dataset)
    pitch = float(ds.manifest["pitch_m"])
    appliers = _board_appliers(ds) if board else None
    tracks: list[Track] = []
    for info, shard in ds.shards_with_info(split=split):
        source = board_pressure(shard["counts"], appliers.get(str(info.get("carpet"))), info) if board else shard["pressure_kpa"]
        for seq in np.unique(shard["sequence"]):
            rows = np.flatnonzero(shard["sequence"] == seq)
            present = shard["present"][rows]
            pressure = source[rows].astype(np.float32)
            own = np.repeat(pressure[:, None], present.shape[1], 1)
            if board:  # masked to where the truth loads, as the runtime's scene masks a person
                truth = shard["pressure_kpa"][rows].astype(np.float32)
                for i in range(len(rows)):
                    own[i] = pressure[i] * footprint_masks(truth[i], shard["joints_m"][rows[i]], present[i], pitch)
            else:
                for i in np.flatnonzero(present.sum(1) > 1):
                    m = person_masks(pressure[i], shard["joints_m"][rows[i]], present[i], pitch)
                    own[i] = pressure[i] * m
            for p in range(present.shape[1]):
                for start, stop in _runs(present[:, p]):
                    r = rows[start:stop]
                    tracks.append(Track(own[start:stop, p].astype(np.float16), shard["pose_aa"][r, p], shard["betas"][r, p],
                                        shard["transl_m"][r, p], shard["joints_m"][r, p],
                                        shard["activity"][r, p].astype(np.int64), int(shard["subject"][r[0], p]),
                                        int(present[start:stop].sum(1).max()), board))
                    if max_tracks and len(tracks) >= max_tracks:
                        return tracks
    return tracks


def _board_appliers(ds) -> dict:
    """carpet → calibration.apply.Applier for every calibration the dataset lists."""
    from calibration.apply import Applier
    from calibration.file import Calibration

    cals = ds.manifest.get("calibrations")
    if not cals:
        raise ValueError(f"{ds.dir} has no calibrations; generate it with `cavatar sim generate --calibration installer` "
                         "(or truth) to read the board's path")
    return {carpet: Applier(Calibration.load(Path(ds.dir) / c["file"])) for carpet, c in cals.items()}


def board_pressure(counts: np.ndarray, applier, info: dict | None = None) -> np.ndarray:
    """(N,H,W) raw counts → (N,H,W) float16 kPa through the carpet's calibration, frame by frame."""
    if applier is None:
        raise ValueError(f"shard {(info or {}).get('file')} names no carpet with a calibration")
    return np.stack([applier.apply(c).pressure_kpa for c in counts]).astype(np.float16)


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    d = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)))


def corrupt(pressure_kpa, rng: np.random.Generator):
    """Sensor-realistic corruption of true pressure (numpy or torch (N,H,W)); same op set as TRAINING_INPUT."""
    import torch

    p = torch.as_tensor(pressure_kpa, dtype=torch.float32)
    h, w = p.shape[-2:]
    gain = float(rng.uniform(0.85, 1.15))
    sensel = torch.from_numpy(rng.normal(1.0, 0.05, (h, w)).astype(np.float32))
    noise = torch.from_numpy(rng.normal(0.0, 0.1, p.shape).astype(np.float32))
    loaded = p > 0  # only the person's own region carries noise: elsewhere the person mask zeroes it
    q = torch.where(loaded, p * gain * sensel + noise, torch.zeros_like(p))
    q = torch.where(q < 0.2, torch.zeros_like(q), q)
    return q.clamp(max=SATURATION_KPA)


def training_input(pressure_kpa, rng: np.random.Generator, board: bool = False):
    """(N,H,W) kPa of one track → the model's training input (torch, kPa) for that track's kind.

    A true-pressure track goes through ``corrupt`` (TRAINING_INPUT). A board's-path track (already the
    sensor model's counts through a calibration) is floored and clipped as the runtime does
    (edge.infer.model_input) after one global gain ×U(0.92, 1.08), which spans more calibrations than a
    dataset's few carpets while keeping every label exact."""
    import torch

    if not board:
        return corrupt(pressure_kpa, rng)
    from edge.infer.model_input import FLOOR_KPA

    p = torch.as_tensor(pressure_kpa, dtype=torch.float32) * float(rng.uniform(0.92, 1.08))
    p = torch.where(p < FLOOR_KPA, torch.zeros_like(p), p)
    return p.clamp(max=SATURATION_KPA)


def chunk_indices(length: int, start: int, frames: int) -> np.ndarray:
    """Frame indices of a chunk starting at ``start`` (may be negative: the runtime pads a new
    track's history with its first frame, and so do we)."""
    return np.clip(np.arange(start, start + frames), 0, length - 1)


def without_activities(tracks: list[Track], names: list[str]) -> list[Track]:
    """The tracks cut around every frame of the named activities (leave-one-activity-out training)."""
    from sim.motion import ACTIVITIES

    unknown = [n for n in names if n not in ACTIVITIES]
    if unknown:
        raise ValueError(f"unknown activities {unknown}; known: {list(ACTIVITIES)}")
    drop = [ACTIVITIES.index(n) for n in names]
    out = []
    for t in tracks:
        out += [t.slice(a, b) for a, b in _runs(~np.isin(t.activity, drop))]
    return out

"""The dataset format: sharded frames with exact ground truth, and a manifest.

A dataset is a folder::

    manifest.json          schema, grid, pitch, rate, subjects and their split, shards with
                           frame counts and SHA-256 (and the carpet they were rendered on),
                           generator settings, seed, git revision; "calibrations" when made
    calibration-<carpet>.npz  each carpet's calibration (``generate(calibration=…)``, optional)
    shard-00000.npz        one shard: whole sequences, never split across shards
    ...

Arrays in a shard (N frames, P = manifest["max_people"] person slots):

    counts          (N, H, W) uint16   raw sensor counts (what the board sends)
    pressure_kpa    (N, H, W) float16  true pressure at the sensels
    fault_mask      (H, W)    uint8    bit flags of configured sensor faults, FAULT_BITS (0 = healthy)
    t_s             (N,)      float64  time of each frame, seconds since the sequence began
    sequence        (N,)      int32    sequence index within the shard (frames of one sequence are consecutive)
    frame_flags     (N,)      uint8    FRAME_FLAGS: 1 frames were dropped just before, 2 torn, 4 duplicate, 8 corrupt
    present         (N, P)    bool     person slot p is on the carpet
    subject         (N, P)    int16    index into manifest["subjects"], -1 when absent
    activity        (N, P)    int8     index into manifest["activities"], -1 when absent
    pose_aa         (N, P, 72) float32 SMPL axis-angle, global orientation in the carpet frame
    betas           (N, P, 10) float32
    transl_m        (N, P, 3) float32  pelvis joint in the carpet frame
    joints_m        (N, P, 24, 3) float32

Splits are by subject: every subject is in exactly one of train/val/test, so test
subjects are never seen in training. Writing is atomic per shard (``.part`` then
rename) and the manifest is written last, so an interrupted run never leaves a
dataset that looks complete.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Iterator

import numpy as np

from cavatar_common.atomic import atomic_path, write_atomic
from cavatar_common.provenance import git_revision, sha256_file

SCHEMA = "cavatar.dataset/1"
SPLITS = ("train", "val", "test")
FRAME_FLAGS = {"after_drop": 1, "torn": 2, "duplicate": 4, "corrupt": 8}
# fault_mask bits: the simulator's configured sensor faults (ground truth for calibration)
FAULT_BITS = {"dead": 1, "half_dead": 2, "stuck": 4, "noisy": 8, "short": 16, "mux_bank": 32, "outside": 64}

FRAME_ARRAYS = {"counts": np.uint16, "pressure_kpa": np.float16, "t_s": np.float64, "sequence": np.int32, "frame_flags": np.uint8}
PERSON_ARRAYS = {
    "present": np.bool_, "subject": np.int16, "activity": np.int8, "pose_aa": np.float32,
    "betas": np.float32, "transl_m": np.float32, "joints_m": np.float32,
}


class DatasetError(Exception):
    """A dataset folder that is missing, incomplete, or fails its hashes."""


@dataclass
class Subject:
    subject_id: str
    split: str
    betas: list[float] = field(default_factory=list)
    mass_kg: float | None = None


class DatasetWriter:
    """Write shards, then :meth:`close` writes the manifest. Use as a context manager."""

    def __init__(self, out_dir: str | Path, *, rows: int, cols: int, pitch_m: float, rate_hz: float,
                 activities: list[str], subjects: list[Subject], max_people: int = 3,
                 source: str = "sim", settings: dict[str, Any] | None = None, overwrite: bool = False) -> None:
        self.dir = Path(out_dir)
        if (self.dir / "manifest.json").exists() and not overwrite:
            raise DatasetError(f"{self.dir} already holds a dataset; choose another --out or remove it")
        for s in subjects:
            if s.split not in SPLITS:
                raise ValueError(f"subject {s.subject_id}: split must be one of {SPLITS}, got {s.split!r}")
        self.dir.mkdir(parents=True, exist_ok=True)
        self.rows, self.cols, self.max_people = rows, cols, max_people
        self.manifest: dict[str, Any] = {
            "schema": SCHEMA, "source": source, "rows": rows, "cols": cols, "pitch_m": pitch_m,
            "rate_hz": rate_hz, "max_people": max_people, "activities": list(activities),
            "subjects": [s.__dict__ for s in subjects], "settings": settings or {},
            "git_revision": git_revision(), "shards": [],
        }

    def __enter__(self) -> "DatasetWriter":
        return self

    def __exit__(self, exc_type, *_: Any) -> None:
        if exc_type is None:
            self.close()

    def write_shard(self, arrays: dict[str, np.ndarray], info: dict[str, Any] | None = None) -> Path:
        """Validate and write one shard; ``info`` (e.g. sequences, split) goes into the manifest."""
        n = len(arrays["counts"])
        checked = {}
        for name, dtype in FRAME_ARRAYS.items():
            a = np.asarray(arrays[name])
            if a.shape[0] != n:
                raise ValueError(f"shard array {name} has {a.shape[0]} frames, counts has {n}")
            checked[name] = a.astype(dtype, copy=False)
        if checked["counts"].shape[1:] != (self.rows, self.cols):
            raise ValueError(f"counts are {checked['counts'].shape[1:]}, the dataset is {self.rows}×{self.cols}")
        for name, dtype in PERSON_ARRAYS.items():
            a = np.asarray(arrays[name])
            if a.shape[:2] != (n, self.max_people):
                raise ValueError(f"shard array {name} must start with (frames, {self.max_people}), got {a.shape}")
            checked[name] = a.astype(dtype, copy=False)
        checked["fault_mask"] = np.asarray(arrays.get("fault_mask", np.zeros((self.rows, self.cols))), np.uint8)
        index = len(self.manifest["shards"])
        path = self.dir / f"shard-{index:05d}.npz"
        with atomic_path(path, durable=False) as part, open(part, "wb") as fh:  # regenerable: no fsync per shard
            np.savez_compressed(fh, **checked)
        self.manifest["shards"].append({"file": path.name, "frames": n, "sha256": sha256_file(path), **(info or {})})
        return path

    def close(self) -> None:
        self.manifest["frames"] = sum(s["frames"] for s in self.manifest["shards"])
        write_atomic(self.dir / "manifest.json", json.dumps(self.manifest, indent=1))


class Dataset:
    """Read a dataset folder: ``Dataset(path).shards(split="test")`` yields shard dicts."""

    def __init__(self, path: str | Path, verify: bool = False) -> None:
        self.dir = Path(path)
        mpath = self.dir / "manifest.json"
        if not mpath.exists():
            raise DatasetError(f"{self.dir} has no manifest.json: not a dataset, or its generation did not finish")
        self.manifest = json.loads(mpath.read_text())
        if self.manifest.get("schema") != SCHEMA:
            raise DatasetError(f"{mpath}: schema {self.manifest.get('schema')!r}, this reader reads {SCHEMA!r}")
        for shard in self.manifest["shards"]:
            if not (self.dir / shard["file"]).exists():
                raise DatasetError(f"{self.dir}: shard {shard['file']} listed in the manifest is missing")
            if verify and sha256_file(self.dir / shard["file"]) != shard["sha256"]:
                raise DatasetError(f"{self.dir}: shard {shard['file']} does not match its SHA-256 in the manifest")

    @property
    def subjects(self) -> list[dict[str, Any]]:
        return self.manifest["subjects"]

    @property
    def activities(self) -> list[str]:
        return self.manifest["activities"]

    def subject_split(self) -> np.ndarray:
        """(S,) array of split names by subject index."""
        return np.array([s["split"] for s in self.subjects])

    def __len__(self) -> int:
        return int(self.manifest.get("frames", sum(s["frames"] for s in self.manifest["shards"])))

    def load_shard(self, index: int) -> dict[str, np.ndarray]:
        with np.load(self.dir / self.manifest["shards"][index]["file"]) as z:
            return {k: z[k] for k in z.files}

    def shards(self, split: str | None = None) -> Iterator[dict[str, np.ndarray]]:
        """Shards in order; with ``split``, only the sequences whose subjects all belong to it.

        Sequences are kept whole (training windows span consecutive frames); a generator
        puts only subjects of one split in a sequence, and a mixed one is left out here.
        """
        for _, shard in self.shards_with_info(split):
            yield shard

    def shards_with_info(self, split: str | None = None) -> Iterator[tuple[dict[str, Any], dict[str, np.ndarray]]]:
        """As :meth:`shards`, each with its manifest entry (file, frames, split, carpet, …)."""
        if split is not None and split not in SPLITS:
            raise ValueError(f"split must be one of {SPLITS}")
        splits = self.subject_split()
        for i, info in enumerate(self.manifest["shards"]):
            shard = self.load_shard(i)
            if split is None:
                yield info, shard
                continue
            keep = np.zeros(len(shard["sequence"]), bool)
            for seq in np.unique(shard["sequence"]):
                rows = shard["sequence"] == seq
                subjects = np.unique(shard["subject"][rows])
                subjects = subjects[subjects >= 0]
                if len(subjects) and (splits[subjects] == split).all():
                    keep |= rows
            if keep.any():
                yield info, {k: (v if k == "fault_mask" else v[keep]) for k, v in shard.items()}

    def frame(self, index: int) -> dict[str, np.ndarray]:
        """One frame by global index (for `cavatar sim show`)."""
        if not 0 <= index < len(self):
            raise IndexError(f"frame {index} is outside 0..{len(self) - 1}")
        for i, s in enumerate(self.manifest["shards"]):
            if index < s["frames"]:
                shard = self.load_shard(i)
                return {k: (v if k == "fault_mask" else v[index]) for k, v in shard.items()}
            index -= s["frames"]
        raise IndexError(index)

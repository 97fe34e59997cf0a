"""Turn an Intelligent Carpet recording (and optional VIBE labels) into our dataset format.

The result reads like a simulated dataset (:class:`sim.dataset.Dataset`), with what a
real recording cannot know left out honestly: ``pressure_kpa`` is NaN (the release has
raw readings only), and so are ``transl_m``/``joints_m`` (VIBE gives no metric
translation nor our body model's joints); the manifest says so under ``"unknown"``.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sim.dataset import DatasetWriter, Subject
from sim.real.intelligent_carpet import RecordingError, TactileRecording, load_aligned, load_tiles
from sim.real.vibe import load_vibe, match_to_carpet, read_video_times


def load_recording(folder: str | Path, rate_hz: float | None = None) -> TactileRecording:
    """Per-tile HDF5 files when present, else ``touch_aligned.p``."""
    folder = Path(folder)
    if any(folder.glob("touch*.hdf5")):
        return load_tiles(folder, rate_hz=rate_hz)
    if (folder / "touch_aligned.p").exists():
        return load_aligned(folder / "touch_aligned.p", rate_hz=rate_hz or 14.0)
    raise RecordingError(f"{folder}: neither touch<k>.hdf5 tiles nor touch_aligned.p")


def convert(folder: str | Path, out_dir: str | Path, *, subject_id: str, split: str = "test",
            vibe: str | Path | None = None, video_times: str | Path | None = None,
            cam_to_carpet: np.ndarray | None = None, pitch_m: float = 0.01905, activity: str | None = None,
            max_gap_s: float = 0.05) -> Path:
    rec = load_recording(folder)
    n, rows, cols = rec.frames.shape
    if rec.frames.min() < 0 or rec.frames.max() > 65535:
        raise RecordingError(f"{folder}: readings outside 0..65535 cannot be raw counts")
    people = {"present": np.zeros((n, 3), bool)}
    if vibe is not None:
        if video_times is None:
            raise ValueError("VIBE labels need the video's timestamp file (webcam<k>.txt) to align with the carpet")
        people = match_to_carpet(load_vibe(vibe), read_video_times(video_times), rec.t_s, max_gap_s=max_gap_s,
                                 cam_to_carpet=cam_to_carpet)
    present = people["present"]
    activities = [activity or "unknown"]
    dt = np.diff(rec.t_s)
    rate = float(1.0 / np.median(dt)) if len(dt) else 14.0
    arrays = {
        "counts": rec.frames.astype(np.uint16),
        "pressure_kpa": np.full((n, rows, cols), np.nan, np.float16),
        "t_s": rec.t_s - rec.t_s[0],
        "sequence": np.zeros(n, np.int32),
        "frame_flags": np.zeros(n, np.uint8),
        "present": present,
        "subject": np.where(present, 0, -1).astype(np.int16),
        "activity": np.where(present, 0, -1).astype(np.int8),
        "pose_aa": people.get("pose_aa", np.zeros((n, 3, 72))),
        "betas": people.get("betas", np.zeros((n, 3, 10))),
        "transl_m": people.get("transl_m", np.full((n, 3, 3), np.nan)),
        "joints_m": people.get("joints_m", np.full((n, 3, 24, 3), np.nan)),
    }
    settings = {"recording": str(folder), "vibe": str(vibe) if vibe else None, "max_tile_skew_s": rec.max_skew_s,
                "unknown": ["pressure_kpa", "transl_m", "joints_m"] + ([] if vibe else ["pose_aa", "betas"]),
                "betas_are": "official SMPL betas (VIBE), not this project's body model" if vibe else None}
    with DatasetWriter(out_dir, rows=rows, cols=cols, pitch_m=pitch_m, rate_hz=rate, activities=activities,
                       subjects=[Subject(subject_id, split)], source="intelligent_carpet", settings=settings) as w:
        w.write_shard(arrays, {"sequences": 1, "split": split})
    return Path(out_dir)

"""Loader for VIBE outputs, the video labels the CAvatar paper trained on.

VIBE writes ``vibe_output.pkl`` with joblib: a dict ``track_id -> {"pose" (n, 72),
"betas" (n, 10), "pred_cam" (n, 3), "joints3d" (n, 49, 3), "frame_ids" (n,), ...}``
(plus ``verts``, ``orig_cam``, ``bboxes``, ``joints2d``, which we do not need).
Video frames are put on a time base with the camera's timestamp file (one time per
line, seconds), then matched to carpet frames by nearest time.

What VIBE cannot give: metric translation (``pred_cam`` is a weak-perspective camera)
and joints of our body model (its betas are official SMPL betas). Matched frames carry
``pose_aa`` (global orientation turned into the carpet frame when the camera-to-carpet
rotation is given) and ``betas``; ``transl_m`` and ``joints_m`` are NaN unless
the caller supplies them. Needs ``joblib`` (``pip install -e '.[data]'``).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial.transform import Rotation

from sim.real.intelligent_carpet import RecordingError

REQUIRED = ("pose", "betas", "frame_ids")


@dataclass
class VibeTrack:
    track_id: int
    frame_ids: np.ndarray  # (n,) video frame indices
    pose_aa: np.ndarray  # (n, 72), camera frame
    betas: np.ndarray  # (n, 10)
    pred_cam: np.ndarray | None  # (n, 3) weak perspective (s, tx, ty)


def load_vibe(path: str | Path) -> list[VibeTrack]:
    """Tracks of a ``vibe_output.pkl`` (joblib or plain pickle)."""
    import joblib

    path = Path(path)
    try:
        data = joblib.load(path)
    except Exception as exc:  # joblib raises many kinds on a bad file
        raise RecordingError(f"{path}: not a readable VIBE output ({type(exc).__name__}: {exc})") from None
    if not isinstance(data, dict):
        raise RecordingError(f"{path}: expected a dict of tracks, got {type(data).__name__}")
    tracks = []
    for track_id, t in sorted(data.items()):
        missing = [k for k in REQUIRED if k not in t]
        if missing:
            raise RecordingError(f"{path}: track {track_id} lacks {missing}; a VIBE track has {list(REQUIRED)} at least")
        pose, betas, ids = np.asarray(t["pose"], np.float64), np.asarray(t["betas"], np.float64), np.asarray(t["frame_ids"]).astype(int)
        if pose.shape != (len(ids), 72) or betas.shape != (len(ids), 10):
            raise RecordingError(f"{path}: track {track_id}: pose {pose.shape} / betas {betas.shape} do not match {len(ids)} frame ids")
        cam = np.asarray(t["pred_cam"], np.float64) if "pred_cam" in t else None
        tracks.append(VibeTrack(int(track_id), ids, pose, betas, cam))
    return tracks


def read_video_times(path: str | Path) -> np.ndarray:
    """A camera's timestamp file: one time in seconds per line (blank lines ignored)."""
    try:
        lines = [ln.split()[0] for ln in Path(path).read_text().splitlines() if ln.strip()]
        return np.array([float(x) for x in lines])
    except (OSError, ValueError) as exc:
        raise RecordingError(f"{path}: not a timestamp file, one number per line ({exc})") from None


def to_carpet_frame(pose_aa: np.ndarray, cam_to_carpet: np.ndarray) -> np.ndarray:
    """Rotate the global orientation (first three values) by the camera-to-carpet rotation (3×3)."""
    out = pose_aa.copy()
    out[:, :3] = (Rotation.from_matrix(cam_to_carpet) * Rotation.from_rotvec(pose_aa[:, :3])).as_rotvec()
    return out


def match_to_carpet(tracks: list[VibeTrack], video_t_s: np.ndarray, carpet_t_s: np.ndarray, max_gap_s: float = 0.05,
                    max_people: int = 3, cam_to_carpet: np.ndarray | None = None) -> dict[str, np.ndarray]:
    """Person arrays (present, pose_aa, betas, transl_m, joints_m) per carpet frame.

    A track's label goes to a carpet frame when the nearest video frame is within
    ``max_gap_s``; tracks fill person slots in order of first appearance (at most
    ``max_people``; more is a RecordingError).
    """
    if len(tracks) > max_people:
        raise RecordingError(f"{len(tracks)} VIBE tracks, at most {max_people} people per frame are supported")
    n = len(carpet_t_s)
    out = {
        "present": np.zeros((n, max_people), bool),
        "pose_aa": np.zeros((n, max_people, 72), np.float32),
        "betas": np.zeros((n, max_people, 10), np.float32),
        "transl_m": np.full((n, max_people, 3), np.nan, np.float32),
        "joints_m": np.full((n, max_people, 24, 3), np.nan, np.float32),
    }
    for slot, track in enumerate(sorted(tracks, key=lambda t: t.frame_ids.min())):
        if track.frame_ids.max() >= len(video_t_s):
            raise RecordingError(f"track {track.track_id} refers to video frame {track.frame_ids.max()}, "
                                 f"the timestamps have {len(video_t_s)}")
        t_track = video_t_s[track.frame_ids]
        order = np.argsort(t_track)
        t_track = t_track[order]
        j = np.clip(np.searchsorted(t_track, carpet_t_s), 1, max(1, len(t_track) - 1))
        j = np.where(np.abs(t_track[j - 1] - carpet_t_s) <= np.abs(t_track[np.minimum(j, len(t_track) - 1)] - carpet_t_s), j - 1, j)
        j = np.minimum(j, len(t_track) - 1)
        ok = np.abs(t_track[j] - carpet_t_s) <= max_gap_s
        src = order[j[ok]]
        pose = track.pose_aa[src]
        if cam_to_carpet is not None:
            pose = to_carpet_frame(pose, np.asarray(cam_to_carpet, np.float64))
        out["present"][ok, slot] = True
        out["pose_aa"][ok, slot] = pose
        out["betas"][ok, slot] = track.betas[src]
    return out

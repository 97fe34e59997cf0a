"""The error axis of speed_error: each trained variant on the same unseen-subject tracks, as the board loads it,
and the mean-pose baseline on the same frames."""

from __future__ import annotations

from typing import Any

import numpy as np

from bench import BenchmarkError
from bench.variants import Variant


def load_eval_tracks(data: list[str], split: str) -> dict[tuple[int, int], dict[str, Any]]:
    """grid → {"tracks", "pitch_m", "data", "subjects"} from every dataset folder given (one set per grid)."""
    from export.finetune import user_tracks
    from sim.dataset import DatasetError

    groups: dict[tuple[int, int], dict[str, Any]] = {}
    for d in data:
        try:
            tracks, pitch, ds = user_tracks(d, split)
        except (DatasetError, ValueError) as exc:
            raise BenchmarkError(str(exc)) from None
        grid = (int(ds.manifest["rows"]), int(ds.manifest["cols"]))
        g = groups.setdefault(grid, {"tracks": [], "pitch_m": pitch, "data": []})
        if abs(g["pitch_m"] - pitch) > 1e-6:
            raise BenchmarkError(f"{d}: pitch {pitch} m differs from the other {grid[0]}×{grid[1]} datasets' {g['pitch_m']} m")
        g["tracks"] += tracks
        g["data"].append(str(d))
    for g in groups.values():
        g["subjects"] = sorted({f"s{t.subject:02d}" for t in g["tracks"]})
    return groups


ERROR_KEYS = ("mpjpe_cm", "pa_mpjpe_cm", "heading_over90_pct", "pve_cm", "transl_cm")  # export.tables.summarise's


def variant_error(v: Variant, groups: dict, stride: int) -> dict[str, Any]:
    from export.tables import evaluate_bundle

    if v.trained is False:
        return {"status": "not trained"}
    if not groups:
        return {"status": "not evaluated", "reason": "no --data given (speed only)"}
    if v.trained is None:
        return {"status": "not evaluated", "reason": "the bundle has no weights.npz"}
    g = groups.get(v.grid)
    if g is None or v.bundle_dir is None:
        return {"status": "not evaluated", "reason": f"no --data of a {v.grid[0]}×{v.grid[1]} carpet"}
    if abs(g["pitch_m"] - v.pitch_m) > 0.05 * v.pitch_m:
        return {"status": "not evaluated", "reason": f"data pitch {g['pitch_m']} m, bundle pitch {v.pitch_m} m"}
    o = evaluate_bundle(v.bundle_dir, g["tracks"], g["pitch_m"], frame_stride=stride)["overall"]  # heading resolved
    return {"status": "evaluated", **{k: o[k] for k in ERROR_KEYS}, "frames": o["frames"]}


def baseline_error(manifest: dict[str, Any], group: dict[str, Any], stride: int) -> dict[str, Any] | None:
    """The mean-pose baseline of the reference bundle's manifest on the same frames (context for the table)."""
    from export.tables import baseline_errors, summarise

    base = manifest.get("baseline")
    if not base:
        return None
    e = baseline_errors((np.array(base["pose_aa"]), np.array(base["betas"]), float(base["pelvis_height_m"])),
                        group["tracks"], group["pitch_m"], frame_stride=stride)
    o = summarise(e)["overall"]
    return {**{k: o[k] for k in ERROR_KEYS}, "frames": o["frames"]}

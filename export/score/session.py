"""A whole score: every scene captured through the runtime, judged, summarised into one result dict.

    result = score_scenes(SETS["quick"], work=Path("out/score"), threshold_m=0.5)
    result["overall"]["mota_pct"], result["scenes"][0]["status"], result["timeline"]["p1-s3"]

The result (schema ``cavatar.score/1``) holds the machine, git revision, model, the matching
threshold and calibration used, one entry per scene (status, reason when it failed, its own
numbers), the numbers overall / per number of people / per activity (:mod:`.summary`) and each
scene's timeline of true and published people counts (what the PNG draws).
"""

from __future__ import annotations

import os
import platform
import time
from collections import Counter
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Callable, Iterable

from export.score.capture import RATE_HZ, Scene, capture
from export.score.judge import judge
from export.score.summary import summarise

SCHEMA = "cavatar.score/1"


def machine() -> dict[str, Any]:
    """CPU count, platform, Python and the load average now (times on a shared machine move with its load)."""
    return {"platform": platform.platform(), "cpu_count": os.cpu_count(), "python": platform.python_version(),
            "load_average_1_5_15_min": [round(x, 2) for x in os.getloadavg()]}


def chunk_activities(run) -> tuple[list[int], list[list[str]]]:
    """(first frame, each person's activity) per simulated scene (chunk) of ``run``, in order: the most
    frequent activity of a person's frames other than the "standing" a scene starts from (standing only
    when it is all there is). Scenes differ in length: each lasts as long as its activities need."""
    starts: list[int] = []
    per_scene: dict[int, dict[int, Counter]] = {}
    for k, truth in enumerate(run.truth):
        for t in truth:
            if t["scene"] not in per_scene:
                starts.append(k)
            per_scene.setdefault(t["scene"], {}).setdefault(t["subject_id"], Counter())[t["activity"]] += 1
    out = []
    for subjects in per_scene.values():
        labels = []
        for counts in subjects.values():
            moving = Counter({a: n for a, n in counts.items() if a != "standing"})
            labels.append((moving or counts).most_common(1)[0][0])
        out.append(sorted(labels))
    return starts, out


def score_scenes(scenes: Iterable[Scene], work: Path, threshold_m: float = 0.5, calibration: str = "installer",
                 config: Any = None, set_name: str = "custom", command: str = "",
                 say: Callable[[str], None] = print) -> dict[str, Any]:
    """Capture, judge and summarise ``scenes`` (see the module doc); a scene that fails is reported, not fatal."""
    from cavatar_common.provenance import git_revision
    from edge.body import BodyModel

    revision = git_revision()  # of the code that runs, before anything is committed meanwhile
    body = BodyModel.load("lite")  # the body the simulator poses and the shipped bundle is trained on
    judged, entries, timeline, models = [], [], {}, set()
    t_all = time.monotonic()
    for scene in scenes:
        say(f"score: {scene.name} ({scene.people} people, seed {scene.seed}, {scene.seconds:g} s) …")
        run = capture(scene, work, calibration=calibration, config=config, say=say)
        entry = {"name": scene.name, "people": scene.people, "seed": scene.seed, "seconds": scene.seconds,
                 "scene_s": scene.scene_s, "url": scene.url(), "status": run.status, "reason": run.reason,
                 "frames": len(run.truth), "calibration": run.calibration, "runtime_s": round(run.runtime_s, 1)}
        if run.model:
            models.add(run.model)
        if run.truth:
            frames, persons = judge(run, body, threshold_m)
            judged.append((scene, frames, persons))
            entry["activities"] = sorted({a for acts in frames["activities"] for a in acts})
            entry["kinds"] = {k: frames["kind"].count(k) for k in sorted(set(frames["kind"]))}
            entry["summary"] = summarise([(scene, frames, persons)], RATE_HZ)["overall"]
            starts, acts = chunk_activities(run)
            timeline[scene.name] = {"true": frames["true"].tolist(), "published": frames["published"].tolist(),
                                    "chunk_starts_s": [round(k / RATE_HZ, 3) for k in starts], "chunk_activities": acts}
            s = entry["summary"]
            say(f"score: {scene.name} {run.status}: count right {s['count_right_pct']} %, extra-track frames "
                f"{s['extra_frames_pct']} %, MOTA {s['mota_pct']} %, MPJPE {s['mpjpe_cm']} cm ({run.runtime_s:.0f} s)")
        else:
            say(f"score: {scene.name} {run.status}: {run.reason}")
        entries.append(entry)
    summary = summarise(judged, RATE_HZ)
    return {"schema": SCHEMA, "set": set_name, "command": command, "machine": machine(), "git_revision": revision,
            "date": datetime.now(timezone.utc).isoformat(timespec="seconds"), "model": sorted(models),
            "match_threshold_m": threshold_m, "calibration": calibration, "rate_hz": RATE_HZ,
            "score_s": round(time.monotonic() - t_all, 1), "scenes": entries, **summary, "timeline": timeline}

"""The fall score: the runtime's fall detector over simulated falls and a stretch of ordinary activity.

    python -m export.score.falls_clips out/falls/score.jsonl 5 6 7      # simulate (minutes per seed)
    python -m export.score.falls --clips out/falls/score.jsonl --tuned-on out/falls/tune.jsonl \\
        --out docs/falls/score                                         # PREFIX.json, .md, .png

Per fall clip: detected (a ``fall`` raised from the fall's start to 10 s after impact), the delay from
impact, and — where the person lay still long enough — whether ``person_down`` came within
person_down_s + 2 s of impact. Over every other clip (hard negatives and ordinary activity) and the
parts of fall clips outside their fall: false alarms (``fall`` or ``person_down`` raised), per hard-
negative type, and per 24 h of that activity. The detector's cost per frame is timed here on the cached
body features (the per-frame body_features cost is benched in bench/falls_events.py).
"""

from __future__ import annotations

import argparse
import json
import time
from pathlib import Path
from typing import Any

import numpy as np

from edge.scene.falls import FallConfig, FallDetector, Observation

SCHEMA = "cavatar.falls-score/1"
PATHS = {
    "board": "the board's: simulated bodies → contact model → the virtual carpet's sensor model (raw counts: noise, "
             "saturation, crosstalk, hysteresis, faults) → the runtime's calibration step (the scripted installer "
             "session's calibration of that carpet) → the runtime's SceneTracker → edge.scene.falls. Not through the "
             "wire protocol and frame assembly (lossless on the virtual carpet).",
    "clean": "clean pressure: simulated bodies → contact model (no sensor noise, no calibration) → the runtime's "
             "SceneTracker → edge.scene.falls.",
}
DETECT_AFTER_IMPACT_S = 10.0
DOWN_SLACK_S = 2.0


def load_clips(path: str | Path) -> list[dict]:
    clips = []
    for i, line in enumerate(Path(path).read_text().splitlines(), 1):
        if not line.strip():
            continue
        try:
            clips.append(json.loads(line))
        except json.JSONDecodeError:
            raise SystemExit(f"{path}:{i}: not a JSON line; the clip file is damaged — simulate it again") from None
    return clips


def run_clip(clip: dict, config: FallConfig, rate_hz: float = 14.0) -> tuple[list[dict], float]:
    """The detector over one clip's cached frames → (events, seconds spent in step())."""
    det = FallDetector(config)
    events, spent = [], 0.0
    for k, frame in enumerate(clip["frames"]):
        obs = [Observation(tid, f, a, np.asarray(c), np.asarray(m)) for tid, f, a, c, m in frame]
        t0 = time.perf_counter()
        events += det.step_observations(k / rate_hz, obs, {})
        spent += time.perf_counter() - t0
    events += det.reset(len(clip["frames"]) / rate_hz, "clip_end")
    return events, spent


def judge_clip(clip: dict, events: list[dict], config: FallConfig) -> dict[str, Any]:
    raised = [e for e in events if e["state"] == "raised"]
    truth = clip["truth"]
    out: dict[str, Any] = {"name": clip["name"], "kind": clip["kind"], "what": clip["what"], "seconds": clip["seconds"],
                           "raised": [{"type": e["type"], "t_s": e["t_s"], "confidence": e["confidence"]} for e in raised]}
    false = list(raised)
    if truth.get("fall"):
        start, impact = truth["start_s"], truth["impact_s"]
        falls = [e for e in raised if e["type"] == "fall" and start - 0.5 <= e["t_s"] <= impact + DETECT_AFTER_IMPACT_S]
        out["detected"] = bool(falls)
        out["delay_s"] = round(falls[0]["t_s"] - impact, 2) if falls else None
        floor_s = truth["floor_s"][1] - truth["floor_s"][0]
        out["down_due"] = floor_s >= config.person_down_s + DOWN_SLACK_S
        downs = [e for e in raised if e["type"] == "person_down" and impact <= e["t_s"] <= truth["floor_s"][1] + 1.0]
        out["down_delay_s"] = round(downs[0]["t_s"] - impact, 2) if downs else None
        out["down_in_time"] = bool(downs) and downs[0]["t_s"] - impact <= config.person_down_s + DOWN_SLACK_S
        false = [e for e in raised if e not in falls[:1] and e not in downs[:1]]
    out["false_alarms"] = len(false)
    out["false_types"] = [e["type"] for e in false]
    return out


def score(clips: list[dict], config: FallConfig) -> dict[str, Any]:
    per, spent, frames = [], 0.0, 0
    for clip in clips:
        events, s = run_clip(clip, config)
        spent += s
        frames += len(clip["frames"])
        per.append(judge_clip(clip, events, config))
    falls = [p for p in per if p["kind"] == "fall"]
    neg = [p for p in per if p["kind"] != "fall"]
    delays = [p["delay_s"] for p in falls if p["delay_s"] is not None]
    due = [p for p in falls if p["down_due"]]
    neg_s = sum(p["seconds"] for p in neg)
    by_type: dict[str, dict[str, float]] = {}
    for p in neg:
        d = by_type.setdefault(p["what"], {"seconds": 0.0, "false_alarms": 0})
        d["seconds"] += p["seconds"]
        d["false_alarms"] += p["false_alarms"]
    for d in by_type.values():
        d["seconds"] = round(d["seconds"], 1)
        d["per_24h"] = round(d["false_alarms"] * 86400.0 / max(d["seconds"], 1e-9), 1)
    fa_neg = sum(p["false_alarms"] for p in neg)
    fa_in_falls = sum(p["false_alarms"] for p in falls)
    per_scenario: dict[str, dict[str, Any]] = {}
    for p in falls:
        d = per_scenario.setdefault(p["what"], {"clips": 0, "detected": 0, "delays_s": []})
        d["clips"] += 1
        d["detected"] += int(p["detected"])
        if p["delay_s"] is not None:
            d["delays_s"].append(p["delay_s"])
    for d in per_scenario.values():
        d["median_delay_s"] = round(float(np.median(d["delays_s"])), 2) if d["delays_s"] else None
    return {
        "falls": len(falls),
        "detected_pct": round(100.0 * sum(p["detected"] for p in falls) / max(len(falls), 1), 1),
        "median_delay_s": round(float(np.median(delays)), 2) if delays else None,
        "p90_delay_s": round(float(np.percentile(delays, 90)), 2) if delays else None,
        "person_down_due": len(due),
        "person_down_in_time_pct": round(100.0 * sum(p["down_in_time"] for p in due) / max(len(due), 1), 1),
        "ordinary_hours": round(neg_s / 3600.0, 3),
        "false_alarms": fa_neg,
        "false_alarms_per_24h": round(fa_neg * 86400.0 / max(neg_s, 1e-9), 1),
        "false_alarms_per_24h_upper95": round(_poisson_upper95(fa_neg) * 86400.0 / max(neg_s, 1e-9), 1),
        "false_alarms_in_fall_clips": fa_in_falls,
        "by_negative_type": dict(sorted(by_type.items())),
        "by_fall_scenario": dict(sorted(per_scenario.items())),
        "detector_ms_per_frame": round(1e3 * spent / max(frames, 1), 4),
        "frames": frames,
        "clips": per,
    }


def _poisson_upper95(k: int) -> float:
    """One-sided 95 % upper bound of a Poisson mean after observing k events (chi-square, exact)."""
    from scipy.stats import chi2

    return float(chi2.ppf(0.95, 2 * (k + 1)) / 2.0)


def markdown(result: dict[str, Any]) -> str:
    s = result["score"]
    t = result["targets"]
    lines = [
        "# Fall score", "",
        f"Command: `{result['command']}`  ", f"Clips: {result['clips_file']} (tuned on {result['tuned_on'] or '—'}); "
        f"git {result['git_revision']}; {result['date']}  ",
        f"Scored on seeds {result.get('seeds')}; the thresholds were tuned on seeds {result.get('tuning_seeds', '—')} "
        f"(there: {result.get('tuning_set', {}).get('detected_pct', '—')} % of "
        f"{result.get('tuning_set', {}).get('falls', '—')} falls, {result.get('tuning_set', {}).get('false_alarms', '—')} "
        f"false alarms in {result.get('tuning_set', {}).get('ordinary_hours', '—')} h).", "",
        f"Path: {PATHS.get(result.get('path'), result.get('path'))} The model's activity is not used (pressure alone).", "",
        "| target | measured | target met |", "|---|---|---|",
        f"| falls detected ≥ 97 % | {s['detected_pct']} % of {s['falls']} | {'yes' if t['detected'] else 'no'} |",
        f"| median delay from impact ≤ 3 s | {s['median_delay_s']} s (p90 {s['p90_delay_s']} s) | "
        f"{'yes' if t['delay'] else 'no'} |",
        f"| person_down within {result['config']['person_down_s']:g} s + 2 s | {s['person_down_in_time_pct']} % of "
        f"{s['person_down_due']} | {'yes' if t['person_down'] else 'no'} |",
        f"| ≤ 1 false alarm / 24 h | {s['false_alarms']} in {s['ordinary_hours']} h = {s['false_alarms_per_24h']} / 24 h "
        f"(95 % upper bound {s['false_alarms_per_24h_upper95']} / 24 h) | {'yes' if t['false_alarms'] else 'no'} |",
        f"| detector cost | {s['detector_ms_per_frame']} ms / frame (step only) | — |", "",
        "## Falls, per scenario", "", "| scenario | clips | detected | median delay s |", "|---|---|---|---|",
    ]
    for name, d in s["by_fall_scenario"].items():
        lines.append(f"| {name} | {d['clips']} | {d['detected']} | {d['median_delay_s']} |")
    lines += ["", "## False alarms, per hard-negative type", "", "| type | seconds | false alarms | per 24 h |",
              "|---|---|---|---|"]
    for name, d in s["by_negative_type"].items():
        lines.append(f"| {name} | {d['seconds']} | {d['false_alarms']} | {d['per_24h']} |")
    missed = [c["name"] for c in s["clips"] if c["kind"] == "fall" and not c["detected"]]
    alarms = [f"{c['name']} ({', '.join(c['false_types'])})" for c in s["clips"] if c["false_alarms"]]
    lines += ["", f"Missed falls: {', '.join(missed) or 'none'}.  ", f"False alarms: {', '.join(alarms) or 'none'}.", ""]
    return "\n".join(lines)


def timeline_png(clip: dict, events: list[dict], truth: dict, path: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    t = np.arange(len(clip["frames"])) / 14.0
    area = [sum(o[2] for o in f) for f in clip["frames"]]
    force = [sum(o[1] for o in f) for f in clip["frames"]]
    fig, ax = plt.subplots(figsize=(9, 3.2))
    ax.plot(t, area, label="contact area m² (all bodies)")
    ax.set_xlabel("s")
    ax.set_ylabel("m²")
    ax2 = ax.twinx()
    ax2.plot(t, force, color="0.6", lw=0.8, label="load N")
    ax2.set_ylabel("N")
    if truth.get("fall"):
        ax.axvspan(truth["start_s"], truth["impact_s"], color="tab:red", alpha=0.2, label="falling (truth)")
        ax.axvspan(*truth["floor_s"], color="tab:orange", alpha=0.1, label="on the floor (truth)")
    for e in events:
        style = {"fall": "tab:red", "person_down": "tab:purple"}[e["type"]]
        ax.axvline(e["t_s"], color=style, ls="-" if e["state"] == "raised" else ":",
                   label=f"{e['type']} {e['state']}")
    ax.set_title(f"{clip['name']}: contact area, load and events")
    h1, l1 = ax.get_legend_handles_labels()
    ax.legend(h1, l1, fontsize=7, loc="upper right")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    from dataclasses import asdict
    from datetime import datetime, timezone

    from cavatar_common.provenance import git_revision
    from export.score.session import machine

    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--clips", required=True, help="clip features (python -m export.score.falls_clips)")
    ap.add_argument("--tuned-on", help="the clip file the thresholds were tuned on (recorded, and scored too)")
    ap.add_argument("--out", default="out/falls/score", help="PREFIX for PREFIX.json, .md, .png")
    ap.add_argument("--timeline", help="the clip drawn in the PNG (default: the first fall)")
    ap.add_argument("--plots", metavar="DIR", help="also draw every missed fall and every false alarm's clip, one PNG each")
    a = ap.parse_args(argv)
    config = FallConfig()
    clips = load_clips(a.clips)
    if not clips:
        raise SystemExit(f"{a.clips}: no clips")
    s = score(clips, config)
    result = {"schema": SCHEMA, "command": "python -m export.score.falls " + " ".join(argv or __import__("sys").argv[1:]),
              "clips_file": a.clips, "tuned_on": a.tuned_on, "git_revision": git_revision(), "machine": machine(),
              "date": datetime.now(timezone.utc).isoformat(timespec="seconds"),
              "config": asdict(config), "score": s,
              "targets": {"detected": s["detected_pct"] >= 97.0, "delay": (s["median_delay_s"] or 99) <= 3.0,
                          "person_down": s["person_down_in_time_pct"] >= 97.0,
                          "false_alarms": s["false_alarms_per_24h"] <= 1.0}}
    result["seeds"] = sorted({c["seed"] for c in clips})
    paths = sorted({c.get("path", "clean") for c in clips})
    if len(paths) != 1:
        raise SystemExit(f"{a.clips}: clips from several paths {paths}; simulate them again into one file")
    result["path"] = paths[0]
    if a.tuned_on:
        tuning = load_clips(a.tuned_on)
        t = score(tuning, config)
        result["tuning_set"] = {k: v for k, v in t.items() if k not in ("clips",)}
        result["tuning_seeds"] = sorted({c["seed"] for c in tuning})
    prefix = Path(a.out)
    prefix.parent.mkdir(parents=True, exist_ok=True)
    prefix.with_suffix(".json").write_text(json.dumps(result, indent=1) + "\n")
    prefix.with_suffix(".md").write_text(markdown(result))
    pick = next((c for c in clips if (a.timeline and c["name"] == a.timeline) or (not a.timeline and c["kind"] == "fall")), clips[0])
    events, _ = run_clip(pick, config)
    timeline_png(pick, events, pick["truth"], prefix.with_suffix(".png"))
    if a.plots:
        for c in clips:
            judged = next(p for p in s["clips"] if p["name"] == c["name"])
            if judged["false_alarms"] or (c["kind"] == "fall" and not judged["detected"]):
                events, _ = run_clip(c, config)
                timeline_png(c, events, c["truth"], Path(a.plots) / f"{c['name']}.png")
    print(markdown(result))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

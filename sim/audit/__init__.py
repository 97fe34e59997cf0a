"""``cavatar sim audit``: small generated sets of every activity measured against the
literature ranges of issue 13 (balance, force, foot roll, region loads, print areas, variety).

    report = run_audit(subjects=3, seconds=8.0, seed=0)    # {"settings", "checks", "summary"}
    write_report(report, "docs/sim/audit")                 # audit.json + audit.md

The sets are made by the dataset generator's own motion and contact physics
(``sim.contact.track``), so the audit measures what the training data holds.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

AUDIT_ACTIVITIES = ("stepping", "bending", "turning", "squat", "twisting", "raising_arms", "lunge", "sitting", "push_up",
                    "sit_up", "walking")


def run_audit(subjects: int = 3, seconds: float = 8.0, seed: int = 0, activities=AUDIT_ACTIVITIES, spread_subjects: int = 8,
              progress=None) -> dict:
    from edge.body import BodyModel
    from sim.audit import checks as ck
    from sim.audit.measure import measure_activity, measure_lying
    from sim.contact import ContactModel, regional_tissue
    from sim.motion import ACTIVITIES

    t0 = time.monotonic()
    body = BodyModel.load("lite")
    carpet = ContactModel(96, 96, pitch_m=0.01905)
    tissue = regional_tissue(body)
    labels = {a: ACTIVITIES.index(a) for a in ACTIVITIES}
    standing = labels["standing"]
    results, out = {}, []
    for a in activities:
        if progress:
            progress(f"measuring {a}")
        results[a] = measure_activity(a, subjects, seconds, seed, carpet, body, tissue)
        out += ck.physics_checks(a, results[a], labels[a], standing)
        if a in ("stepping", "turning", "walking"):
            out += ck.gait_checks(a, results[a], labels[a])
    out += ck.load_checks(results, standing, labels)
    out += ck.law_checks(results)
    if progress:
        progress("measuring lying after a fall")
    out += ck.lying_checks(measure_lying("fall_backward", max(subjects, 5), seed, carpet, body, tissue))
    if progress:
        progress("measuring variety")
    for a in activities:
        out += ck.spread_checks(a, spread_subjects, seconds, seed, body)
    if "squat" in activities:
        out += ck.rate_checks(seed, body)
    ok = sum(c["ok"] for c in out)
    return {"settings": {"subjects": subjects, "seconds_per_activity": seconds, "seed": seed, "activities": list(activities),
                         "spread_subjects": spread_subjects, "body": "lite", "grid": 96, "pitch_mm": 19.05},
            "checks": out, "summary": {"in_range": ok, "total": len(out), "elapsed_s": round(time.monotonic() - t0, 1)}}


def markdown(report: dict) -> str:
    s = report["settings"]
    lines = [f"# Simulator audit: {report['summary']['in_range']} of {report['summary']['total']} checks in range", "",
             f"`cavatar sim audit --subjects {s['subjects']} --seconds {s['seconds_per_activity']:g} --seed {s['seed']}` "
             f"({s['subjects']} subjects × every activity × at least {s['seconds_per_activity']:g} s — longer where the activity "
             "needs it at the person's own tempo, as datasets give it — through the generator's motion and "
             f"contact physics; variety over {s['spread_subjects']} subjects).", "",
             "| check | measured | range | in range | source |", "|---|---|---|---|---|"]
    for c in report["checks"]:
        v = "n/a" if c["value"] is None else f"{_shown(c['value'], *c['range'])} {c['unit']}"
        lines.append(f"| {c['what']} | {v} | {c['range'][0]:g}–{c['range'][1]:g} | {'yes' if c['ok'] else '**no**'} | {c['source']} |")
    return "\n".join(lines) + "\n"


def _shown(value: float, lo: float, hi: float) -> str:
    """Three significant digits, or as many more as it takes for the shown number to fall on the same side of
    the range as the value itself (98.95 against 99–100 is not shown as "99")."""
    inside = lo <= value <= hi
    for digits in range(3, 8):
        text = f"{value:.{digits}g}"
        if (lo <= float(text) <= hi) == inside:
            return text
    return f"{value:.8g}"


def write_report(report: dict, out_dir) -> tuple[Path, Path]:
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    j, m = out / "audit.json", out / "audit.md"
    j.write_text(json.dumps(report, indent=1) + "\n")
    m.write_text(markdown(report))
    return j, m

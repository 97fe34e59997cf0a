"""The paper's Table 5: MPJPE on unseen users against the fraction of their data used to fine-tune.

    python -m export.sweep --bundle edge/models/lean-96 --data DATA --subject s06 --subject s43 \
        --fractions 0,0.1,0.2,0.3,0.4,0.5,0.6 --out docs/model/finetune

Each user is fine-tuned on their own (a new user, as the product does it), on the first F of
every one of their tracks, and every fraction is judged on the SAME held-out frames: the last
(1 − max F) of every track, in fp32 by default (an int8 encoder re-calibrated on one user's frames
can miss the int8 gate: measured +1.7 cm once; `cavatar finetune --precision fp32` is the way out
for such a user). Writes OUT.json and OUT.md.
"""

from __future__ import annotations

import argparse
import json
import sys
import tempfile
from pathlib import Path

import numpy as np


def sweep(bundle: str, data: str, subjects: list[str], fractions: list[float], steps: int, stage: str, split: str = "all",
          threads: int = 1, lr: float = 3e-5, precision: str = "fp32") -> dict:
    from export.finetune import finetune

    held_from = max(fractions)
    rows: dict[str, dict[str, float]] = {}
    for subject in subjects:
        rows[subject] = {}
        for f in fractions:
            with tempfile.TemporaryDirectory() as tmp:
                report = finetune(bundle, data, f, Path(tmp) / "b", steps=steps, lr=lr, stage=stage, split=split,
                                  subjects=[subject], threads=threads, progress=False, held_out_from=held_from,
                                  precision=precision)
            rows[subject][f"{round(100 * f)}%"] = report["metrics"]["mpjpe_cm"]
            print(f"{subject} fraction {f:.0%}: held-out MPJPE {report['metrics']['mpjpe_cm']:.2f} cm", file=sys.stderr, flush=True)
    mean = {k: float(np.mean([rows[s][k] for s in subjects])) for k in rows[subjects[0]]}
    return {"setup": {"bundle": bundle, "data": data, "split": split, "subjects": subjects, "fractions": fractions,
                      "held_out": f"the last {1 - held_from:.0%} of every track", "steps": steps, "stage": stage, "lr": lr,
                      "precision": precision},
            "mpjpe_cm": rows, "mean_mpjpe_cm": mean}


def markdown(result: dict) -> str:
    keys = list(result["mean_mpjpe_cm"])
    s = result["setup"]
    lines = [f"## Fine-tuning on unseen users ({s['stage']} stage, {s['steps']} steps, lr {s['lr']:g}, {s.get('precision', 'int8')}; "
             f"held out: {s['held_out']})", "",
             "| user | " + " | ".join(keys) + " |", "|---|" + "---|" * len(keys)]
    for subject, row in result["mpjpe_cm"].items():
        lines.append(f"| {subject} | " + " | ".join(f"{row[k]:.2f}" for k in keys) + " |")
    lines.append("| **mean** | " + " | ".join(f"**{result['mean_mpjpe_cm'][k]:.2f}**" for k in keys) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--bundle", required=True)
    p.add_argument("--data", required=True)
    p.add_argument("--subject", action="append", required=True)
    p.add_argument("--fractions", default="0,0.1,0.2,0.3,0.4,0.5,0.6")
    p.add_argument("--steps", type=int, default=300)
    p.add_argument("--stage", default="head", choices=("head", "windows"))
    p.add_argument("--split", default="all")
    p.add_argument("--lr", type=float, default=3e-5, help="learning rate (default the paper's 3e-5)")
    p.add_argument("--threads", type=int, default=1)
    p.add_argument("--precision", default="fp32", choices=("fp32", "int8"),
                   help="bundles judged in fp32 (default: the effect of fine-tuning alone) or int8 (each must pass the gate)")
    p.add_argument("--out", required=True, help="output prefix: OUT.json, OUT.md")
    a = p.parse_args(argv)
    fractions = [float(x) for x in a.fractions.split(",")]
    result = sweep(a.bundle, a.data, a.subject, fractions, a.steps, a.stage, a.split, a.threads, a.lr, a.precision)
    out = Path(a.out)
    out.parent.mkdir(parents=True, exist_ok=True)
    out.with_suffix(".json").write_text(json.dumps(result, indent=1) + "\n")
    out.with_suffix(".md").write_text(markdown(result))
    print(markdown(result))
    return 0


if __name__ == "__main__":
    sys.exit(main())

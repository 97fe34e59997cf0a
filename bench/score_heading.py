"""The heading resolver (edge/infer/heading.py) on unseen subjects: how often the body faces the wrong
way with and without it, what that does to MPJPE, and what it costs per person-frame.
Writes bench/results/score_heading.json.

    python -m bench.score_heading --data DATASET [--data …] [--split all] [--bundle edge/models/lean-96]

Inputs as `cavatar eval` builds them (the simulator's pressure through the training corruption); the
model runs on every frame of every track and the resolver sees every frame, as on the board. The cost
is the resolver's own work (the foot cue of one person's 96×96 frame + the decision), one thread,
median over every frame of the data, timed separately from the model.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from pathlib import Path

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")

import numpy as np  # noqa: E402

from bench.machine import describe  # noqa: E402

RESULT = Path(__file__).parent / "results" / "score_heading.json"


def _summary(err_deg: np.ndarray, mpjpe_cm: np.ndarray) -> dict:
    return {"heading_median_deg": round(float(np.median(err_deg)), 2),
            "heading_over45_pct": round(float(100 * (err_deg > 45).mean()), 2),
            "heading_over90_pct": round(float(100 * (err_deg > 90).mean()), 2),
            "mpjpe_cm": round(float(mpjpe_cm.mean()), 2)}


def run(data: list[str], split: str, bundle: str, heading_params: str | None) -> dict:
    from edge.body import BodyModel
    from edge.infer import heading, verify
    from edge.infer.heading import HeadingResolver, frame_cue
    from export import metrics
    from export.finetune import user_tracks
    from export.heading_cue import predictions
    from sim.motion import ACTIVITIES

    names = list(verify(bundle)["activities"])
    params, weights = heading.load(heading_params, names)
    body = BodyModel.load("lite")
    rows: dict[str, list] = {"model": [], "resolved": [], "activity": []}
    cost_ms = []
    tracks_n, frames_n = 0, 0
    for d in data:
        tracks, pitch, _ = user_tracks(d, split)
        tracks_n += len(tracks)
        for tr, (pose, kpa, probs) in zip(tracks, predictions(tracks, bundle, pitch)):
            r = HeadingResolver(params, weights)
            out = np.empty_like(pose)
            for t in range(len(pose)):
                t0 = time.perf_counter()
                cue, on_feet = frame_cue(kpa[t], pitch, params)
                out[t] = r.decide(pose[t], cue, probs[t], on_feet)
                cost_ms.append((time.perf_counter() - t0) * 1e3)
            frames_n += len(tr)
            for key, p in (("model", pose), ("resolved", out)):  # the true betas for both: the heading's share alone
                deg = np.degrees(np.abs(metrics.heading_error_rad(p[:, :3], tr.pose_aa[:, :3])))
                rows[key].append((deg, metrics.mpjpe(body.forward(p, tr.betas)["joints"], tr.joints_m) * 100))
            rows["activity"].append(tr.activity)
    act = np.concatenate(rows["activity"])
    result: dict = {"overall": {}, "by_activity": {}}
    for key in ("model", "resolved"):
        deg = np.concatenate([a for a, _ in rows[key]])
        mp = np.concatenate([b for _, b in rows[key]])
        result["overall"][key] = _summary(deg, mp)
        for a in np.unique(act):
            result["by_activity"].setdefault(ACTIVITIES[int(a)], {})[key] = _summary(deg[act == a], mp[act == a])
    cost = np.asarray(cost_ms)
    result["cost_per_person_frame_ms"] = {"median": round(float(np.median(cost)), 4),
                                          "p99": round(float(np.percentile(cost, 99)), 4)}
    result["setup"] = {"data": data, "split": split, "bundle": bundle, "tracks": tracks_n, "frames": frames_n,
                       "heading_params": heading_params or "edge/infer/heading.json (packaged)",
                       "note": "MPJPE here uses the true betas for both rows, so it isolates the heading's share; "
                               "`cavatar eval` gives the full tables"}
    return result


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--data", action="append", required=True, help="dataset of subjects the cue was NOT fitted on")
    ap.add_argument("--split", default="all", choices=("test", "val", "train", "all"))
    ap.add_argument("--bundle", default="edge/models/lean-96")
    ap.add_argument("--heading-params", default=None)
    ap.add_argument("--out", default=str(RESULT))
    args = ap.parse_args(argv)
    result = run(args.data, args.split, args.bundle, args.heading_params)
    result["machine"] = describe()
    result["command"] = "python -m bench.score_heading " + " ".join(argv if argv is not None else sys.argv[1:])
    result["date"] = time.strftime("%Y-%m-%dT%H:%M:%S%z")
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text(json.dumps(result, indent=1) + "\n")
    m, r = result["overall"]["model"], result["overall"]["resolved"]
    print(f"heading >90°: {m['heading_over90_pct']} % → {r['heading_over90_pct']} %; >45°: {m['heading_over45_pct']} % → "
          f"{r['heading_over45_pct']} %; MPJPE {m['mpjpe_cm']} → {r['mpjpe_cm']} cm (true betas); cost "
          f"{result['cost_per_person_frame_ms']['median']} ms per person-frame; wrote {args.out}")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())

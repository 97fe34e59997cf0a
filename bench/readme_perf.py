"""README.md's "Performance" section, generated from bench/results/*.json (so no number is typed by hand).

    python bench/readme_perf.py            # rewrite the block between <!-- perf:begin --> and <!-- perf:end -->
    python bench/readme_perf.py --check    # exit 1 when README.md's block differs from the results

Sources, each optional (a missing one is named, with the command that makes it): decoder_throughput.json,
calibration_runtime.json, speed_error.json (model latency and error, the ratios), runtime_latency.json (the
runtime by stage, bench/runtime_latency.py; without it, the stages bench/speed_error.py measured on its simulated day).
tests/bench/test_readme_perf.py checks that README.md holds exactly what this writes.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from export.benchmark import interval_sentence  # noqa: E402  (numpy only: the same sentence as docs/bench)

RESULTS = ROOT / "bench" / "results"
README = ROOT / "README.md"
BEGIN, END = "<!-- perf:begin -->", "<!-- perf:end -->"
STAGES = ("decode", "calibrate", "scene", "encoder", "head", "record", "frame", "publish", "lag")
RENAMED = {"record": "body"}  # stage names in results written before the rename (issue 15)


def _load(results: Path, name: str) -> dict[str, Any] | None:
    path = results / name
    return json.loads(path.read_text()) if path.is_file() else None


def _stage(stages: dict[str, Any], name: str) -> dict[str, Any] | None:
    """One stage's timings, found under its older name in results written before a rename."""
    return stages.get(name) or stages.get(RENAMED.get(name, name))


def _f(v: Any, digits: int = 2) -> str:
    return "—" if v is None else f"{v:.{digits}f}"


def measured_on(d: dict[str, Any]) -> str:
    """One line: machine, load, date, command (as recorded; absent fields said so)."""
    m = d.get("machine", {})
    cpu = m.get("cpu_model") or m.get("processor") or m.get("machine") or "CPU not recorded"
    cores = m.get("cpu_count") or m.get("cpus")
    load = next((v for k, v in m.items() if k.startswith("load_average") and v), None)
    parts = [f"{cpu}, {cores} cores" if cores else cpu]
    if load:
        parts.append("load average " + "/".join(f"{x:.1f}" for x in load))
    parts.append(d.get("date") or (f"date not recorded, git {d['git_revision'][:12]}" if d.get("git_revision") else "date not recorded"))
    return f"*Measured on {', '.join(parts)}: `{d.get('command', 'command not recorded')}`.*"


def missing(name: str, command: str) -> list[str]:
    return [f"*Not measured yet: `bench/results/{name}` is missing (`{command}` writes it).*"]


def decoder(d: dict[str, Any] | None) -> list[str]:
    lines = ["### Decoder throughput", ""]
    if d is None:
        return lines + missing("decoder_throughput.json", "python bench/decoder_throughput.py")
    lines += [f"One core, a realistic 96×96 stream at 14 Hz; goal ≥ {d.get('goal_x_real_time', 50):g}× real time "
              "(stream duration / CPU time of the decoding thread).", "",
              "| packing | read size | × real time (median) | IQR | min–max | µs per packet |", "|---|---|---|---|---|---|"]
    for r in d["results"]:
        x = r["x_real_time"]
        lines.append(f"| {r['packing']} | {r['chunk_bytes']} B | {x['median']:.1f}× | {x['iqr']:.1f} | {x['min']:.1f}–{x['max']:.1f} | "
                     f"{r['us_per_packet_median']:.2f} |")
    return lines + ["", measured_on(d)]


def calibration(d: dict[str, Any] | None) -> list[str]:
    lines = ["### Calibration and scene, per 96×96 frame", ""]
    if d is None:
        return lines + missing("calibration_runtime.json", "python bench/calibration_runtime.py")
    names = {"apply": "calibration apply", "apply_crosstalk": "apply + crosstalk inverse", "full_step": "full calibration step",
             "scene_update_only": "scene (filters, contacts, people, tracking)",
             "full_step_plus_scene": "calibration + scene"}
    r = d["results"]
    lines += [d.get("goal", ""), "", "| step | median ms | p99 ms |", "|---|---|---|"]
    lines += [f"| {label} | {r[k]['median_ms']:.3f} | {r[k]['p99_ms']:.3f} |" for k, label in names.items() if k in r]
    return lines + ["", measured_on(d)]


ERRORS = ("mpjpe_cm", "pa_mpjpe_cm", "heading_over90_pct", "pve_cm", "transl_cm")


def _error(e: dict[str, Any]) -> list[str]:
    if e["status"] == "evaluated":  # results from before PA-MPJPE and heading were measured show "—" there
        return [_f(e[k]) if k in e else "—" for k in ERRORS]
    return [e["status"]] * len(ERRORS)


def models(d: dict[str, Any] | None) -> list[str]:
    lines = ["### Model latency and error", ""]
    if d is None:
        return lines + missing("speed_error.json", "python bench/speed_error.py --data DATASET")
    ev = d["evaluation"]
    if ev["status"] == "evaluated":
        where = "; ".join(f"{', '.join(g['data'])} ({g['tracks']} tracks; subjects {', '.join(g['subjects'])})"
                          for g in ev["grids"].values())
        scope = f"Errors (cm, unseen subjects, {ev['split']} split, every {ev['frame_stride']}th frame): {where}."
    else:
        scope = f"Errors not evaluated: {ev['reason']}."
    lines += ["Per published frame: encoder (batch 1) + head over the 40-frame window of cached features, onnxruntime. "
              "Untrained variants are timed only. " + scope, "",
              "| variant | weights | threads | median ms | p99 ms | MPJPE | PA-MPJPE | heading >90° % | PVE | transl | size MB |",
              "|---" * 11 + "|"]
    for v in d["variants"]:
        for s in v["speed"]:
            lines.append("| " + " | ".join([v["name"], v["weights"].split(" (")[0], str(s["threads"]), _f(s["median_ms"], 3),
                                            _f(s["p99_ms"], 3), *_error(v["error"]), f"{v['size_bytes']['total'] / 1e6:.2f}"]) + " |")
    front = ", ".join(f"{p['variant']} ({p['threads']} thr)" for p in d["pareto_front"])
    if front:
        lines += ["", f"Pareto front (latency, MPJPE): {front}."]
    return lines + ["", "Full table (frames/s, peak memory) and the latency–MPJPE plot: "
                        "[docs/bench/speed_error.md](docs/bench/speed_error.md).",
                    "", measured_on(d)]


def ratios(d: dict[str, Any] | None) -> list[str]:
    lines = ["### Ratios, measured side by side", ""]
    if d is None:
        return lines + missing("speed_error.json", "python bench/speed_error.py")
    r = d["ratios"]
    lines += ["Both sides in every round, alternating which goes first; median and interquartile range of the per-round ratio.", "",
              "| ratio | a / b | median | IQR | rounds |", "|---|---|---|---|---|"]

    def row(label: str, a: str, b: str, q: dict[str, Any]) -> str:
        return f"| {label} | {a} / {b} | {q['median']:.2f}× | {q['p25']:.2f}–{q['p75']:.2f} | {q['rounds']} |"

    for key, label in (("onnxruntime_vs_torch_eager", "PyTorch eager vs onnxruntime (fp32, 1 thread)"),
                       ("feature_cache", "feature cache"), ("body_mesh_vs_joints", "body: full mesh vs joints only")):
        lines.append(row(label, r[key]["a"], r[key]["b"], r[key]["ratio"]))
    sa = r["scene_adaptive"]
    lines.append(row("scene-adaptive, model time", sa["a"], sa["b"], sa["model_time"]["ratio"]))
    lines.append(row("scene-adaptive, whole frame", sa["a"], sa["b"], sa["frame_time"]["ratio"]))
    day, inf = sa["day"], sa["inferences"]
    e2e = r["runtime_vs_frame_interval"]
    lines += ["", f"The simulated day: {day['frames']} frames, {100 * day['fraction']['empty']:.0f} % empty, "
              f"{100 * day['fraction']['still']:.0f} % one still person, {100 * day['fraction']['active']:.0f} % activity "
              f"({day['two_person_frames']} frames with two people); encoder runs: always-infer {inf['always_infer']['encoder_runs']}, "
              f"scene-adaptive {inf['scene_adaptive']['encoder_runs']}.",
              "", interval_sentence(e2e), "", measured_on(d)]
    return lines


def runtime(rl: dict[str, Any] | None, se: dict[str, Any] | None) -> list[str]:
    lines = ["### Runtime latency by stage", ""]
    scenes = [r for r in (rl or {}).get("results", []) if isinstance(r, dict) and isinstance(r.get("stages"), dict)]
    if scenes:
        goal = rl.get("goal")
        lines += ["One thread, per frame, recorded virtual-carpet scenes replayed through the runtime's own stages"
                  + (f"; goal: {', '.join(f'{k} {v:g}' for k, v in goal.items())}" if isinstance(goal, dict) else "")
                  + (f" ({'met' if rl['passed'] else 'NOT met'})" if "passed" in rl else "") + ".", ""]
        head = " | ".join(f"{r.get('people')} {'person' if r.get('people') == 1 else 'people'}: median / p99 ms" for r in scenes)
        lines += [f"| stage | {head} |", "|---" * (len(scenes) + 1) + "|"]
        rows = [(k, [_stage(r["stages"], k) for r in scenes]) for k in STAGES if any(_stage(r["stages"], k) for r in scenes)]
        rows.append(("frame total", [r.get("frame_total") for r in scenes]))
        for name, cells in rows:
            lines.append(f"| {name} | " + " | ".join(f"{_f(c.get('median_ms'), 3)} / {_f(c.get('p99_ms'), 3)}" if c else "—"
                                                     for c in cells) + " |")
        return lines + ["", measured_on(rl)]
    if se is not None and "stages_ms" in se["ratios"]["runtime_vs_frame_interval"]:
        stages = se["ratios"]["runtime_vs_frame_interval"]["stages_ms"]
        lines += ["`bench/results/runtime_latency.json` is absent: FrameStages on the simulated day of bench/speed_error.py, "
                  "scene-adaptive (decoding and publishing not included); model stages over the frames that ran them.", "",
                  "| stage | median ms | p99 ms |", "|---|---|---|"]
        lines += [f"| {k} | {_f(_stage(stages, k)['median_ms'], 3)} | {_f(_stage(stages, k)['p99_ms'], 3)} |" for k in STAGES
                  if (_stage(stages, k) or {}).get("median_ms") is not None]
        return lines + ["", measured_on(se)]
    return lines + ["*Not measured yet: neither `bench/results/runtime_latency.json` nor `bench/results/speed_error.json` "
                    "is present (`python bench/runtime_latency.py` writes the first).*"]


def render(results: Path = RESULTS) -> str:
    """The Markdown between the markers (without them)."""
    se = _load(results, "speed_error.json")
    parts = [["Generated by `python bench/readme_perf.py` from `bench/results/*.json`; each block names its machine, "
              "load, date and command. Absolute times on a shared 2-core machine move with its load: compare ratios."],
             decoder(_load(results, "decoder_throughput.json")), calibration(_load(results, "calibration_runtime.json")),
             models(se), ratios(se), runtime(_load(results, "runtime_latency.json"), se)]
    return "\n\n".join("\n".join(p) for p in parts)


def replace_block(text: str, block: str) -> str:
    if text.count(BEGIN) != 1 or text.count(END) != 1 or text.index(BEGIN) > text.index(END):
        raise ValueError(f"README.md needs exactly one {BEGIN} … {END} block")
    head, rest = text.split(BEGIN)
    _, tail = rest.split(END)
    return f"{head}{BEGIN}\n{block}\n{END}{tail}"


def current_block(text: str) -> str:
    return text.split(BEGIN)[1].split(END)[0].strip("\n")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--check", action="store_true", help="only check README.md; exit 1 if its block is stale")
    ap.add_argument("--readme", type=Path, default=README)
    ap.add_argument("--results", type=Path, default=RESULTS)
    args = ap.parse_args(argv)
    text = args.readme.read_text()
    new = replace_block(text, render(args.results))
    if args.check:
        if new != text:
            print(f"{args.readme}: the Performance block is stale; run python bench/readme_perf.py", file=sys.stderr)
            return 1
        return 0
    args.readme.write_text(new)
    print(f"wrote the Performance block of {args.readme}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

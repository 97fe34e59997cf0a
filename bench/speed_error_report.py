"""speed_error's outputs: the JSON, the Markdown table (docs/bench/speed_error.md) and the latency–MPJPE plot."""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

from bench.accuracy import ERROR_KEYS
from bench.stats import pareto_front


def pareto(rows: list[dict[str, Any]]) -> list[dict[str, Any]]:
    """The front over every evaluated (variant, threads) point: median latency vs MPJPE."""
    pts = [(r["name"], s["threads"], s["median_ms"], r["error"]["mpjpe_cm"]) for r in rows
           if r["error"]["status"] == "evaluated" for s in r["speed"]]
    return [{"variant": pts[i][0], "threads": pts[i][1], "median_ms": pts[i][2], "mpjpe_cm": pts[i][3]}
            for i in pareto_front([(p[2], p[3]) for p in pts])]



def _num(v: Any, digits: int = 2) -> str:
    return "—" if v is None else f"{v:.{digits}f}"


def _error_cells(e: dict[str, Any]) -> list[str]:
    if e["status"] == "evaluated":
        return [_num(e.get(k)) for k in ERROR_KEYS]
    return [e["status"]] * len(ERROR_KEYS)


def variant_table(result: dict[str, Any]) -> list[str]:
    lines = ["| variant | weights | threads | median ms | p99 ms | frames/s | peak MiB | size MB | MPJPE cm | PA-MPJPE cm | "
             "heading >90° % | PVE cm | transl cm |", "|---" * 13 + "|"]
    for r in result["variants"]:
        for s in r["speed"]:
            lines.append("| " + " | ".join([r["name"], r["weights"].split(" (")[0], str(s["threads"]), _num(s["median_ms"]),
                                            _num(s["p99_ms"]), f"{s['frames_per_s']:.0f}", f"{s['peak_rss_mb']:.1f}",
                                            f"{r['size_bytes']['total'] / 1e6:.2f}", *_error_cells(r["error"])]) + " |")
    return lines


def interval_sentence(e2e: dict[str, Any]) -> str:
    """The runtime's per-frame cost against the frame interval, in words (per scene when measured per scene)."""
    def one(r: dict[str, Any]) -> str:
        p99 = f", p99 {_num(r['frame_p99_ms'])} ms" + (f" = {100 * r['fraction_p99']:.1f} %" if r.get("fraction_p99") else "")
        return f"median {_num(r['frame_median_ms'])} ms = {100 * r['fraction_median']:.1f} %{p99}"

    if e2e.get("scenes"):
        body = "; ".join(f"{r['people']} {'person' if r['people'] == 1 else 'people'}: {one(r)}" for r in e2e["scenes"])
    else:
        body = one(e2e)
    return f"Runtime per frame against the {e2e['interval_ms']:.1f} ms frame interval at 14 Hz: {body}. Source: {e2e['source']}."


def ratio_lines(result: dict[str, Any]) -> list[str]:
    rt = result["ratios"]
    lines = ["| ratio | a | b | a ms | b ms | ratio a/b (median) | IQR | rounds |", "|---|---|---|---|---|---|---|---|"]
    for key in ("onnxruntime_vs_torch_eager", "feature_cache", "body_mesh_vs_joints"):
        r = rt[key]
        lines.append(f"| {key} | {r['a']} | {r['b']} | {_num(r['a_ms'], 3)} | {_num(r['b_ms'], 3)} | "
                     f"{r['ratio']['median']:.2f}× | {r['ratio']['p25']:.2f}–{r['ratio']['p75']:.2f} | {r['ratio']['rounds']} |")
    sa = rt["scene_adaptive"]
    for part in ("model_time", "frame_time"):
        r, q = sa[part], sa[part]["ratio"]
        lines.append(f"| scene_adaptive {part.replace('_', ' ')} (per frame) | {sa['a']} | {sa['b']} | "
                     f"{_num(r['a_ms_per_frame'], 3)} | {_num(r['b_ms_per_frame'], 3)} | {q['median']:.2f}× | "
                     f"{q['p25']:.2f}–{q['p75']:.2f} | {q['rounds']} |")
    inf, day = sa["inferences"], sa["day"]
    e2e = rt["runtime_vs_frame_interval"]
    lines += ["", f"Simulated day: {day['frames']} frames ({day['seconds']} s at {day['rate_hz']:g} Hz): "
              f"{100 * day['fraction']['empty']:.0f} % empty, {100 * day['fraction']['still']:.0f} % one still person, "
              f"{100 * day['fraction']['active']:.0f} % activity ({day['two_person_frames']} frames with two people). "
              f"Inferences (encoder runs): always-infer {inf['always_infer']['encoder_runs']}, scene-adaptive "
              f"{inf['scene_adaptive']['encoder_runs']} (still reuses {inf['scene_adaptive']['still_reuses']}, frames "
              f"without inference {inf['scene_adaptive']['frames_empty'] + inf['scene_adaptive']['frames_unconfirmed']}).",
              "", interval_sentence(e2e)]
    return lines


def markdown(result: dict[str, Any]) -> str:
    m = result["machine"]
    ev = result["evaluation"]
    if ev["status"] == "evaluated":
        where = "; ".join(f"{g}: {', '.join(x['data'])} ({x['tracks']} tracks, subjects {', '.join(x['subjects'])})"
                          for g, x in ev["grids"].items())
        errors = f"Errors on the {ev['split']} split, every {ev['frame_stride']}th frame: {where}."
        for g, x in ev["grids"].items():
            if x.get("baseline_mean_pose"):
                b = x["baseline_mean_pose"]
                errors += (f" Mean-pose baseline ({g}): MPJPE {b['mpjpe_cm']:.2f}, PVE {b['pve_cm']:.2f}, "
                           f"translation {b['transl_cm']:.2f} cm.")
    else:
        errors = f"Errors not evaluated: {ev['reason']}."
    front = ", ".join(f"{p['variant']} ({p['threads']} thr)" for p in result["pareto_front"]) or "none (no evaluated variant)"
    lines = ["# Speed against error", "",
             f"`{result['command']}` on {result['date']}, git {result['git_revision'][:12]}; {m['cpu_model']}, "
             f"{m['cpu_count']} cores, load average {', '.join(f'{x:.2f}' for x in m['load_average_1_5_15_min'])} at start; "
             f"onnxruntime {m['onnxruntime']}, torch {m['torch']}. Generated from bench/results/speed_error.json.", "",
             "Latency = encoder (batch 1, the new frame) + head (batch 1, the 40-frame window of cached features), per "
             "published frame. Untrained variants (random weights) are timed only: their error is never plotted. "
             + errors, "", *variant_table(result), "", f"Pareto front (latency, MPJPE): {front}.", "",
             "![latency per frame vs MPJPE](pareto.png)", "", "## Ratios, measured side by side", "",
             "Median and interquartile range of the per-round ratio (both sides in every round, alternating order).", "",
             *ratio_lines(result), ""]
    return "\n".join(lines)


def plot(result: dict[str, Any], path: str | Path) -> Path:
    """Latency per frame vs MPJPE: evaluated points labelled, the Pareto front drawn; speed-only variants
    on a strip below (never on the error axis). Marker shape = onnxruntime threads."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D
    from matplotlib.ticker import FormatStrFormatter, LogLocator

    evaluated = [r for r in result["variants"] if r["error"]["status"] == "evaluated"]
    speed_only = [r for r in result["variants"] if r["error"]["status"] != "evaluated"]
    fig, (ax, strip) = plt.subplots(2, 1, figsize=(9, 6.5), sharex=True,
                                    gridspec_kw={"height_ratios": [3.2, 0.4 + 0.3 * max(len(speed_only), 1)]})
    markers = {1: "o", 2: "s"}
    colours = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for i, r in enumerate(evaluated):
        y = r["error"]["mpjpe_cm"]
        for s in r["speed"]:
            ax.scatter(s["median_ms"], y, marker=markers.get(s["threads"], "^"), s=45, color=colours[i % len(colours)], zorder=3)
        x0 = min(s["median_ms"] for s in r["speed"])
        ax.annotate(r["name"], (x0, y), textcoords="offset points", xytext=(-4, 7), fontsize=8, ha="left")
    front = result["pareto_front"]
    if front:
        ax.step([p["median_ms"] for p in front], [p["mpjpe_cm"] for p in front], where="post", color="tab:red", lw=1.3,
                zorder=2)
    else:
        why = result["evaluation"].get("reason", "no trained variant")
        ax.text(0.5, 0.5, f"errors not evaluated: {why}", transform=ax.transAxes, ha="center", va="center", fontsize=10,
                color="0.3")
    handles = [Line2D([], [], marker=m, ls="", color="0.3", label=f"{t} thread{'s' if t > 1 else ''}") for t, m in markers.items()]
    handles.append(Line2D([], [], color="tab:red", lw=1.3, label="Pareto front"))
    ax.legend(handles=handles, loc="upper right", fontsize=8)
    ax.set_ylabel("MPJPE (cm), unseen subjects")
    ax.set_title("Latency per published frame (encoder batch 1 + head over the window) vs error", fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    labels = [r["name"] for r in speed_only]
    for y, r in enumerate(speed_only):
        for s in r["speed"]:
            strip.scatter(s["median_ms"], y, marker=markers.get(s["threads"], "^"), s=35, color="0.4", zorder=3)
    strip.set_yticks(range(len(labels)))
    strip.set_yticklabels([f"{r['name']} ({r['error']['status']})" for r in speed_only], fontsize=8)
    strip.set_ylim(-0.7, max(len(labels), 1) - 0.3)
    strip.set_title("speed only: no error on the axis above", fontsize=9)
    strip.set_xlabel("latency per frame, median (ms)")
    strip.grid(True, axis="x", which="both", alpha=0.3)
    xs = [s["median_ms"] for r in result["variants"] for s in r["speed"]]
    if xs and max(xs) / min(xs) > 5:
        strip.set_xscale("log")
        strip.xaxis.set_major_locator(LogLocator(subs=(1.0, 2.0, 5.0)))
        strip.xaxis.set_major_formatter(FormatStrFormatter("%g"))
        strip.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    fig.tight_layout()
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def write_outputs(result: dict[str, Any], json_path: str | Path, markdown_path: str | Path, plot_path: str | Path) -> None:
    for p in (json_path, markdown_path):
        Path(p).parent.mkdir(parents=True, exist_ok=True)
    Path(json_path).write_text(json.dumps(result, indent=1) + "\n")
    Path(markdown_path).write_text(markdown(result))
    plot(result, plot_path)

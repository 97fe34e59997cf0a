"""export/benchmark.py (`cavatar bench`, bench/speed_error.py) on a tiny bundle with a handful of frames: every field
of the results, finite positive ratios, the Pareto front, the table and the plot; a bundle without weights.npz."""

from __future__ import annotations

import json
import math

import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("onnxscript")

from export.benchmark import (  # noqa: E402
    BenchmarkError,
    SpeedErrorConfig,
    bundle_variants,
    markdown,
    pareto_front,
    run_speed_error,
    write_outputs,
)

TOP = {"schema", "benchmark", "command", "date", "git_revision", "machine", "method", "evaluation", "variants", "pareto_front",
       "ratios", "elapsed_s"}
VARIANT = {"name", "source", "precision", "weights", "trained", "grid", "window", "features", "size_bytes", "speed", "error"}
SPEED = {"threads", "median_ms", "p99_ms", "mean_ms", "frames_per_s", "frames", "peak_rss_mb"}
RATIOS = {"onnxruntime_vs_torch_eager", "feature_cache", "body_mesh_vs_joints", "scene_adaptive", "runtime_vs_frame_interval"}


@pytest.fixture(scope="module")
def result(tiny_bundle, tiny_data):
    from export.model import ModelConfig

    cfg = SpeedErrorConfig(bundles=[str(tiny_bundle)], data=[str(tiny_data)], split="test", stride=10, threads=(1, 2),
                           latency_rounds=2, frames_per_round=3, memory_frames=3, ratio_rounds=3, ratio_calls=2, day_s=3.0,
                           day_rounds=2, memory_baseline_runs=1, runtime_latency=None, log=lambda text: None,
                           untrained={"tiny-untrained": ModelConfig.preset("tiny", grid=(32, 32), head="mean")})  # quick to export
    return run_speed_error(cfg, command="pytest")


def _positive(x) -> bool:
    return isinstance(x, (int, float)) and math.isfinite(x) and x > 0


def test_the_results_have_every_field(result):
    assert TOP <= set(result) and result["schema"] == "cavatar.bench.speed_error/1"
    assert {"cpu_model", "cpu_count", "load_average_1_5_15_min", "load_average_1_5_15_min_at_end", "onnxruntime"} <= set(result["machine"])
    names = [v["name"] for v in result["variants"]]
    assert names == ["tiny-32 int8", "tiny-32 fp32", "tiny-untrained fp32", "tiny-untrained int8"]
    for v in result["variants"]:
        assert VARIANT <= set(v) and v["size_bytes"]["total"] == v["size_bytes"]["encoder"] + v["size_bytes"]["head"] > 0
        assert [s["threads"] for s in v["speed"]] == [1, 2]
        for s in v["speed"]:
            assert SPEED <= set(s) and s["frames"] == 6
            assert all(_positive(s[k]) for k in ("median_ms", "p99_ms", "mean_ms", "frames_per_s"))
            assert math.isfinite(s["peak_rss_mb"]) and s["peak_rss_mb"] > 0  # the graphs and their buffers, above the imports
    errors = {v["name"]: v["error"] for v in result["variants"]}
    for name in ("tiny-32 int8", "tiny-32 fp32"):
        e = errors[name]
        assert e["status"] == "evaluated" and e["frames"] > 0 and all(_positive(e[k]) for k in ("mpjpe_cm", "pve_cm", "transl_cm"))
    assert errors["tiny-32 int8"]["frames"] == errors["tiny-32 fp32"]["frames"]  # the same tracks and frames
    assert errors["tiny-untrained fp32"] == errors["tiny-untrained int8"] == {"status": "not trained"}
    ev = result["evaluation"]["grids"]["32x32"]
    assert result["evaluation"]["status"] == "evaluated" and ev["tracks"] > 0 and ev["subjects"]
    assert {p["variant"] for p in result["pareto_front"]} <= {"tiny-32 int8", "tiny-32 fp32"} and result["pareto_front"]


def test_the_ratios_are_finite_and_positive(result):
    r = result["ratios"]
    assert set(r) == RATIOS
    for key in ("onnxruntime_vs_torch_eager", "feature_cache", "body_mesh_vs_joints"):
        assert _positive(r[key]["a_ms"]) and _positive(r[key]["b_ms"])
        q = r[key]["ratio"]
        assert all(_positive(q[k]) for k in ("median", "p25", "p75")) and q["p25"] <= q["median"] <= q["p75"] and q["rounds"] == 3
    sa = r["scene_adaptive"]
    for part in ("model_time", "frame_time"):
        assert _positive(sa[part]["ratio"]["median"]) and _positive(sa[part]["a_ms_per_frame"])
    always, adaptive = sa["inferences"]["always_infer"], sa["inferences"]["scene_adaptive"]
    assert always["encoder_runs"] >= sa["day"]["frames"] > adaptive["encoder_runs"]  # every frame vs only what is needed
    assert always["records"] == adaptive["records"] and always["heartbeats"] == adaptive["heartbeats"]
    f = sa["day"]["fraction"]
    assert abs(f["empty"] - 0.6) < 0.1 and abs(f["still"] - 0.25) < 0.1 and abs(f["active"] - 0.15) < 0.1
    e2e = r["runtime_vs_frame_interval"]
    assert e2e["interval_ms"] == pytest.approx(1000 / 14) and _positive(e2e["fraction_median"]) and _positive(e2e["frame_median_ms"])


def test_pareto_front_on_hand_made_points():
    pts = [(1.0, 10.0), (2.0, 8.0), (1.5, 9.5), (3.0, 8.0), (0.5, 12.0), (2.5, 7.0), (1.0, 11.0), (4.0, 20.0)]
    # (3,8) is beaten by (2,8); (1,11) by (1,10); (4,20) by everything
    assert pareto_front(pts) == [4, 0, 2, 1, 5]
    assert pareto_front([(1.0, 1.0), (1.0, 1.0)]) == [0, 1]  # ties: neither beats the other
    assert pareto_front([]) == []


def test_outputs_are_written(result, tmp_path):
    write_outputs(result, tmp_path / "r" / "speed_error.json", tmp_path / "d" / "speed_error.md", tmp_path / "d" / "pareto.png")
    assert json.loads((tmp_path / "r" / "speed_error.json").read_text()) == json.loads(json.dumps(result))
    png = (tmp_path / "d" / "pareto.png").read_bytes()
    assert png[:8] == b"\x89PNG\r\n\x1a\n" and len(png) > 10_000
    md = (tmp_path / "d" / "speed_error.md").read_text()
    assert md == markdown(result)
    assert "| tiny-32 int8 | trained | 1 |" in md and "| tiny-untrained fp32 | random | 2 |" in md and "not trained" in md
    assert "scene_adaptive model time" in md and "Pareto front" in md


def test_a_bundle_without_weights_is_refused_when_errors_are_wanted(bundle_without_weights, tmp_path):
    with pytest.raises(BenchmarkError, match="no weights.npz"):
        bundle_variants(bundle_without_weights, tmp_path / "w", need_weights=True)


def test_cavatar_bench_refuses_clearly(bundle_without_weights, tiny_data, tmp_path, capsys):
    from edge.cli import main

    code = main(["bench", "--shipped", str(bundle_without_weights), "--data", str(tiny_data), "--json", str(tmp_path / "x.json")])
    assert code == 2 and "no weights.npz" in capsys.readouterr().err and not (tmp_path / "x.json").exists()


def test_the_runtime_against_the_interval_comes_from_runtime_latency_json_when_present(tmp_path):
    from export.benchmark import runtime_vs_interval

    path = tmp_path / "runtime_latency.json"
    path.write_text(json.dumps({"command": "python bench/runtime_latency.py", "results": [
        {"people": 1, "frame_total": {"median_ms": 5.0, "p99_ms": 8.0}},
        {"people": 2, "frame_total": {"median_ms": 10.0, "p99_ms": 25.0}}]}))
    r = runtime_vs_interval({}, str(path))
    assert r["people"] == 2 and r["fraction_median"] == pytest.approx(10.0 / (1000 / 14)) and len(r["scenes"]) == 2
    assert r["scenes"][0]["fraction_p99"] == pytest.approx(8.0 / (1000 / 14)) and str(path) in r["source"]

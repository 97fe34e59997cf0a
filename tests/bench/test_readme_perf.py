"""README.md's Performance block is exactly what bench/readme_perf.py makes of the committed results."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from bench import readme_perf

ROOT = Path(__file__).resolve().parents[2]


def test_readme_block_equals_the_generator_output():
    text = (ROOT / "README.md").read_text()
    assert readme_perf.BEGIN in text and readme_perf.END in text and "## Performance" in text
    assert readme_perf.current_block(text) == readme_perf.render(ROOT / "bench" / "results"), \
        "README.md's Performance block is stale: run `python -m bench.readme_perf`"


def test_missing_optional_results_are_named_not_fatal(tmp_path):
    shutil.copyfile(ROOT / "bench" / "results" / "decoder_throughput.json", tmp_path / "decoder_throughput.json")
    block = readme_perf.render(tmp_path)
    assert "### Decoder throughput" in block and "× real time" in block
    for name in ("calibration_runtime.json", "speed_error.json"):
        assert f"`bench/results/{name}` is missing" in block
    assert "neither `bench/results/runtime_latency.json` nor" in block
    assert "`bench/results/" in readme_perf.render(tmp_path / "empty")  # nothing at all: still a block


def test_runtime_latency_json_gives_the_stage_table(tmp_path):
    def scene(people, calibrate, frame):
        return {"people": people, "stages": {"calibrate": {"median_ms": calibrate, "p99_ms": 0.9, "n": 10},
                                             "encoder": {"median_ms": 0.5, "p99_ms": 1.0, "n": 4}},
                "frame_total": {"median_ms": frame, "p99_ms": 7.25, "n": 10}}

    (tmp_path / "runtime_latency.json").write_text(json.dumps({
        "command": "python bench/runtime_latency.py", "git_revision": "0123456789abcdef",
        "machine": {"cpu_model": "Test CPU", "cpu_count": 4, "load_average_1_5_15_min": [0.5, 0.5, 0.5]},
        "goal": {"real_time_factor": 10.0}, "passed": True, "results": [scene(1, 0.25, 3.5), scene(2, 0.5, 6.0)]}))
    block = readme_perf.render(tmp_path)
    assert "| stage | 1 person: median / p99 ms | 2 people: median / p99 ms |" in block
    assert "| calibrate | 0.250 / 0.900 | 0.500 / 0.900 |" in block and "| frame total | 3.500 / 7.250 | 6.000 / 7.250 |" in block
    assert "| scene |" not in block and "real_time_factor 10 (met)" in block
    assert "Test CPU, 4 cores" in block and "date not recorded, git 0123456789ab" in block


def test_replace_block_keeps_the_rest_and_refuses_a_readme_without_markers():
    text = f"# T\n\n## Performance\n\n{readme_perf.BEGIN}\nold\n{readme_perf.END}\n\n## Next\n"
    new = readme_perf.replace_block(text, "new")
    assert new == f"# T\n\n## Performance\n\n{readme_perf.BEGIN}\nnew\n{readme_perf.END}\n\n## Next\n"
    with pytest.raises(ValueError, match="perf:begin"):
        readme_perf.replace_block("# no markers\n", "x")

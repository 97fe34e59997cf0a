"""README.md's accuracy block is generated from the committed score, and --check catches a stale one."""

from __future__ import annotations

import json

import numpy as np

from export.score.capture import Scene
from export.score.readme import BEGIN, END, main
from export.score.summary import summarise


def test_the_repository_readme_is_current():
    assert main(["--check"]) == 0


def _score(tmp_path, mpjpe_m=0.2):
    frames = {"true": np.ones(4, int), "published": np.array([1, 1, 2, 1]), "extra": np.array([0, 0, 1, 0]),
              "missed": np.zeros(4, int), "switches": np.zeros(4, int), "frame_ms": np.full(4, 6.0),
              "activities": [["squat"]] * 4, "kind": ["people"] * 4}
    persons = {"activity": np.array(["squat"] * 4), "matched": np.ones(4, bool), "activity_ok": np.ones(4, bool),
               **{k: np.full(4, v) for k, v in (("mpjpe_m", mpjpe_m), ("pa_mpjpe_m", 0.1), ("local_mpjpe_m", 0.15),
                                                 ("heading_rad", 0.2), ("transl_m", 0.1))}}
    s = summarise([(Scene(1, 0, 1), frames, persons)], 14.0)
    result = {"schema": "cavatar.score/1", "set": "quick", "match_threshold_m": 0.5, "scenes": [{"name": "p1-s0", "status": "scored"}],
              "machine": {"cpu_count": 2, "load_average_1_5_15_min": [1.0, 1.0, 1.0]}, "date": "2026-01-01T00:00:00+00:00",
              "git_revision": "abc", "model": ["m@1"], "command": "cavatar score --set quick", **s}
    path = tmp_path / "score.json"
    path.write_text(json.dumps(result))
    return path


def test_targets_say_met_and_not_met(tmp_path):
    from export.score.markdown import targets

    result = json.loads(_score(tmp_path).read_text())
    two = {**result["by_people"]["1"], "count_right_pct": 98.0, "mota_pct": 94.99, "idsw_per_10_person_min": None}
    lines = targets({**result, "by_people": {**result["by_people"], "2": two}})
    assert "| 1 person: extra-track frames % | 25.00 | ≤ 1 | not met |" in lines
    assert "| 1 person: extra-track frames %, worst activity (squat) | 25.00 | ≤ 1 | not met |" in lines
    assert "| 2 people: count right % | 98.00 | ≥ 98 | met |" in lines
    assert "| 2 people: MOTA % | 94.99 | ≥ 95 | not met |" in lines
    assert "| 2 people: identity switches / 10 person-min | — | ≤ 1 | — |" in lines
    assert not any(line.startswith("| 3 people") for line in lines)


def test_write_then_check_then_stale(tmp_path):
    readme = tmp_path / "README.md"
    readme.write_text(f"# x\n\n{BEGIN}\nold\n{END}\ntail\n")
    score = _score(tmp_path)
    args = ["--readme", str(readme), "--score", str(score), "--eval", str(tmp_path / "none.json")]
    assert main(args + ["--check"]) == 1
    assert main(args) == 0
    text = readme.read_text()
    assert "| 1 | 4 | 75.0 | 25.0 | 0.0 | 75.0 | 0.0 | 20.0 |" in text and text.endswith(f"{END}\ntail\n")
    assert main(args + ["--check"]) == 0
    _score(tmp_path, mpjpe_m=0.3)  # new results: the block is stale
    assert main(args + ["--check"]) == 1


def test_missing_markers_or_foreign_json_is_one_line(tmp_path, capsys):
    readme = tmp_path / "README.md"
    readme.write_text("# no block\n")
    score = _score(tmp_path)
    assert main(["--readme", str(readme), "--score", str(score)]) == 2
    assert "no <!-- score:begin -->" in capsys.readouterr().err
    readme.write_text(f"{BEGIN}\n{END}\n")
    score.write_text(json.dumps({"schema": "other"}))
    assert main(["--readme", str(readme), "--score", str(score)]) == 2
    assert "not a cavatar.score/1" in capsys.readouterr().err

"""`cavatar score --set quick` end to end (the real runtime on the virtual carpet), and its refusals."""

from __future__ import annotations

import json

import pytest

from edge.cli import main


@pytest.fixture(scope="module")
def quick(tmp_path_factory):
    """The quick set with the truth calibration (the installer's session takes ~15 s; tested in tests/edge/runtime)."""
    out = tmp_path_factory.mktemp("score")
    code = main(["score", "--set", "quick", "--calibration", "truth", "--out", str(out / "q"), "--work", str(out / "work")])
    return code, out


def test_quick_set_scores_every_published_record(quick):
    code, out = quick
    assert code == 0
    r = json.loads((out / "q.json").read_text())
    assert r["schema"] == "cavatar.score/1" and r["set"] == "quick" and r["match_threshold_m"] == 0.5
    (scene,) = r["scenes"]
    assert scene["status"] == "scored" and scene["frames"] == 70
    line = r["timeline"][scene["name"]]
    assert len(line["true"]) == len(line["published"]) == 70 and set(line["true"]) == {1}
    (labels,) = line["chunk_activities"]  # 5 s: one simulated scene, one person, its activity named
    assert len(labels) == 1 and labels[0] in r["by_activity"] and labels[0] != "standing"
    # what the timeline says was published is what the JSON-lines sink holds, frame for frame
    records = [json.loads(x) for x in (out / "work" / f"{scene['name']}.bodies.jsonl").read_text().splitlines()]
    with_people = [len(x["people"]) for x in records if x["people"]]
    assert with_people == [n for n in line["published"] if n]
    o = r["overall"]
    assert o["frames"] == 70 and o["person_frames"] == 70
    assert o["matched_person_frames"] + o["missed_person_frames"] == 70
    assert 0 < o["mpjpe_cm"] < 60 and o["pa_mpjpe_cm"] <= o["mpjpe_cm"] and o["frame_ms_median"] > 0
    assert o["mota_pct"] == pytest.approx(100 * (1 - (o["extra_person_frames"] + o["missed_person_frames"] + o["idsw"]) / 70),
                                          abs=0.01)
    assert r["by_people"]["1"] == o and r["by_activity"]


def test_quick_set_writes_markdown_and_png(quick):
    _, out = quick
    md = (out / "q.md").read_text()
    assert "| 1 person | 70 |" in md and "](q.png)" in md and "threshold 0.5 m" in md
    assert "| 1 person: extra-track frames % |" in md and "2 people" not in md  # targets of what was scored only
    assert (out / "q.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_render_rewrites_markdown_from_the_json(quick, tmp_path):
    _, out = quick
    assert main(["score", "--render", str(out / "q.json"), "--out", str(tmp_path / "r")]) == 0
    assert (tmp_path / "r.md").read_text() == (out / "q.md").read_text().replace("](q.png)", "](r.png)")
    assert not (tmp_path / "r.json").exists()


def test_a_scene_that_cannot_start_is_reported_not_fatal(quick, tmp_path, capsys):
    """A calibration of another carpet: the runtime refuses it; the score says so and exits 1, no traceback."""
    _, out = quick
    other = next((out / "work").glob("calibration-truth-*.npz"))
    code = main(["score", "--source", "sim://?people=1&seed=5", "--seconds", "1", "--calibration", str(other),
                 "--out", str(tmp_path / "f"), "--work", str(tmp_path / "w")])
    assert code == 1
    r = json.loads((tmp_path / "f.json").read_text())
    assert r["scenes"][0]["status"] == "failed" and "sim-3" in r["scenes"][0]["reason"] and r["overall"] is None
    assert "no scene could be scored" in capsys.readouterr().err


@pytest.mark.parametrize("argv, says", [
    (["--source", "serial:///dev/ttyACM0", "--seconds", "5"], "only the virtual carpet"),
    (["--source", "sim://?people=1&seed=2"], "needs --seconds"),
    (["--source", "sim://?people=1&grid=32", "--seconds", "2"], "grid=32"),
    (["--source", "sim://?people=0", "--seconds", "2"], "people must be 1..3"),
    (["--source", "sim://?peeple=1", "--seconds", "2"], "peeple"),
    (["--set", "quick", "--seconds", "5"], "--seconds goes with --source"),
    (["--set", "quick", "--match-m", "0"], "--match-m must be > 0"),
    (["--set", "quick", "--calibration", "/nonexistent.npz"], "no such file"),
    (["--render", "/nonexistent.json"], "cannot read it"),
    (["--set", "quick", "--work", "/proc/score-work"], "cannot create /proc/score-work"),
])
def test_bad_input_is_one_line_and_exit_2(argv, says, tmp_path, capsys):
    assert main(["score", "--out", str(tmp_path / "x"), "--work", str(tmp_path / "w"), *argv]) == 2
    err = capsys.readouterr().err
    assert says in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not list(tmp_path.glob("x.*"))

"""The fall score on hand-made clips: a caught fall has its delay, a miss is a miss, an alarm in a
negative is counted per type, and a clip file that mixes paths is refused."""

from __future__ import annotations

import json

import numpy as np
import pytest

from edge.scene.falls import FallConfig
from export.score.falls import main, score

RATE = 14.0


def _frame(tid, force_n, area_m2, xy, length_m):
    """One observation as the clip file stores it: [track, load, area, centre, moments (6)]."""
    x, y = xy
    h, w = length_m / 4.0, force_n / 2.0
    xs = np.array([x - h, x + h])
    m = [force_n, w * xs.sum(), force_n * y, w * (xs ** 2).sum(), force_n * y * y, w * xs.sum() * y]
    return [tid, force_n, area_m2, [x, y], m]


def _clip(name, kind, shift_m, truth, path="board"):
    """3 s on the feet at (0.9, 0.4), 0.5 s in the air, then 35 s lying shift_m further along y."""
    frames = [[_frame(1, 350.0, 0.03, (0.9, 0.4), 0.5)]] * int(3 * RATE) + [[]] * int(0.5 * RATE)
    frames += [[_frame(2, 600.0, 0.09, (0.9, 0.4 + shift_m), 0.8)]] * int(35 * RATE)
    return {"name": name, "kind": kind, "what": name.split("-")[0], "seed": 5, "truth": truth, "path": path,
            "seconds": len(frames) / RATE, "frames": frames}


FALL = {"fall": True, "start_s": 3.0, "impact_s": 3.5, "floor_s": [3.5, 38.5]}


def test_a_caught_fall_a_missed_one_and_a_false_alarm_are_each_counted():
    clips = [_clip("fall_forward-s5", "fall", 0.8, FALL),
             _clip("slow_collapse-s5", "fall", 0.1, FALL),  # lands where it stood: missed
             _clip("lunge-s5-0", "activity", 0.8, {"fall": False})]  # a negative that looks like a fall
    s = score(clips, FallConfig())
    by = {c["name"]: c for c in s["clips"]}
    assert by["fall_forward-s5"]["detected"] and 0.0 < by["fall_forward-s5"]["delay_s"] <= 1.0
    assert by["fall_forward-s5"]["down_in_time"]
    assert not by["slow_collapse-s5"]["detected"]
    assert s["falls"] == 2 and s["detected_pct"] == 50.0
    assert s["false_alarms"] == 2  # fall and person_down in the lunge clip
    assert s["by_negative_type"]["lunge"]["false_alarms"] == 2


def test_the_score_names_its_path_and_refuses_a_mixed_clip_file(tmp_path):
    board = tmp_path / "board.jsonl"
    board.write_text(json.dumps(_clip("fall_forward-s5", "fall", 0.8, FALL)) + "\n")
    assert main(["--clips", str(board), "--out", str(tmp_path / "s")]) == 0
    md = (tmp_path / "s.md").read_text()
    assert "Path: the board's" in md and json.loads((tmp_path / "s.json").read_text())["path"] == "board"
    mixed = tmp_path / "mixed.jsonl"
    mixed.write_text(board.read_text() + json.dumps(_clip("fall_backward-s5", "fall", 0.8, FALL, path="clean")) + "\n")
    with pytest.raises(SystemExit, match="several paths"):
        main(["--clips", str(mixed), "--out", str(tmp_path / "m")])


def test_the_clip_simulator_refuses_an_unknown_scenario(tmp_path, capsys):
    from export.score.falls_clips import clip_list
    from export.score.falls_clips import main as clips_main

    with pytest.raises(SystemExit):
        clips_main([str(tmp_path / "c.jsonl"), "0", "--what", "slow_collapse,slow_colapse"])
    assert "unknown slow_colapse" in capsys.readouterr().err and not (tmp_path / "c.jsonl").exists()
    names = {c.what for c in clip_list([0])}
    assert {"slow_collapse", "lie_down_hand_first", "sitting", "pet", "bag"} <= names

"""Dataset generation end to end: deterministic, split by subject, ground truth consistent."""

import numpy as np
import pytest

from edge.body import BodyModel
from edge.cli import main
from sim.dataset import Dataset
from sim.dataset.generate import generate, split_subjects


def test_split_by_subject_has_val_and_test():
    splits = split_subjects(12, np.random.default_rng(0))
    assert splits.count("test") >= 1 and splits.count("val") >= 1 and splits.count("train") >= 8


@pytest.fixture(scope="module")
def tiny(tmp_path_factory):
    out = tmp_path_factory.mktemp("ds") / "a"
    generate(out, subjects=3, seconds_per_activity=1.5, people=(1, 1), seed=4, activities=("squat", "raising_arms"),
             progress=False)
    return out


def test_generation_is_deterministic_for_a_seed(tiny, tmp_path):
    again = generate(tmp_path / "b", subjects=3, seconds_per_activity=1.5, people=(1, 1), seed=4,
                     activities=("squat", "raising_arms"), progress=False)
    a, b = Dataset(tiny), Dataset(again)
    assert [s["sha256"] for s in a.manifest["shards"]] == [s["sha256"] for s in b.manifest["shards"]]


def test_test_subjects_never_appear_in_training(tiny):
    ds = Dataset(tiny, verify=True)
    seen = {split: set() for split in ("train", "val", "test")}
    for split in seen:
        for shard in ds.shards(split=split):
            seen[split] |= set(np.unique(shard["subject"][shard["present"]]).tolist())
    assert seen["test"] and not (seen["test"] & seen["train"]) and not (seen["val"] & seen["train"])


def test_ground_truth_joints_match_the_body_model_and_counts_follow_pressure(tiny):
    ds = Dataset(tiny)
    shard = ds.load_shard(0)
    assert shard["counts"].dtype == np.uint16 and shard["counts"].shape[1:] == (96, 96)
    k = len(shard["t_s"]) // 2
    p = np.flatnonzero(shard["present"][k])
    model = BodyModel.load("lite")
    joints = model.forward(shard["pose_aa"][k, p], shard["betas"][k, p], shard["transl_m"][k, p])["joints"]
    np.testing.assert_allclose(joints, shard["joints_m"][k, p], atol=1e-4)
    assert np.all(np.diff(shard["t_s"]) >= 0)
    loaded = shard["pressure_kpa"][k].astype(np.float32) > 2.0
    baseline = np.median(shard["counts"][k][~loaded])
    assert np.abs(shard["counts"][k][loaded].astype(float) - baseline).mean() > 50  # the sensor saw the load


def test_cli_generate_and_show(tmp_path, capsys):
    out = tmp_path / "c"
    assert main(["sim", "generate", "--out", str(out), "--subjects", "1", "--seconds-per-activity", "1",
                 "--activities", "squat", "--workers", "1"]) == 0
    assert main(["sim", "show", str(out), "--frame", "3", "--png", str(tmp_path / "f.png")]) == 0
    assert (tmp_path / "f.png").stat().st_size > 10_000
    assert main(["sim", "show", str(out), "--frame", "99999", "--png", str(tmp_path / "g.png")]) == 2
    assert "outside 0.." in capsys.readouterr().err
    assert main(["sim", "generate", "--out", str(tmp_path / "d"), "--subjects", "1", "--activities", "flying"]) == 2
    assert "unknown activities ['flying']" in capsys.readouterr().err
    too_short = tmp_path / "e"  # every sequence would be skipped: an error, not an empty dataset
    assert main(["sim", "generate", "--out", str(too_short), "--subjects", "1", "--seconds-per-activity", "0.05"]) == 2
    assert "at least 2 frames" in capsys.readouterr().err and not too_short.exists()
    assert main(["sim", "generate", "--out", str(out), "--subjects", "1", "--activities", "squat"]) == 2
    assert "already holds a dataset" in capsys.readouterr().err


def test_grids_in_one_process_do_not_share_models(tmp_path):
    """Renderers are cached per process; a 32×32 run must not leak into a 96×96 one."""
    small = generate(tmp_path / "g32", subjects=1, seconds_per_activity=0.5, grid=32, pitch_mm=57.15,
                     activities=("squat",), progress=False)
    big = generate(tmp_path / "g96", subjects=1, seconds_per_activity=0.5, grid=96, activities=("squat",), progress=False)
    assert Dataset(small).load_shard(0)["counts"].shape[1:] == (32, 32)
    assert Dataset(big).load_shard(0)["counts"].shape[1:] == (96, 96)

"""The dataset format: validation on write, splits by subject, hashes checked on read."""

import numpy as np
import pytest

from sim.dataset import Dataset, DatasetError, DatasetWriter, Subject


def shard_arrays(n, seqs, subjects, rows=4, cols=5, p=3):
    """``seqs``: sequence id per frame; ``subjects``: subject index per sequence in slot 0."""
    present = np.zeros((n, p), bool)
    present[:, 0] = True
    subj = np.full((n, p), -1, np.int16)
    subj[:, 0] = [subjects[s] for s in seqs]
    return {
        "counts": np.arange(n * rows * cols).reshape(n, rows, cols) % 4096,
        "pressure_kpa": np.zeros((n, rows, cols)), "t_s": np.arange(n) / 14, "sequence": np.array(seqs),
        "frame_flags": np.zeros(n), "present": present, "subject": subj, "activity": np.where(present, 0, -1),
        "pose_aa": np.zeros((n, p, 72)), "betas": np.zeros((n, p, 10)), "transl_m": np.zeros((n, p, 3)),
        "joints_m": np.zeros((n, p, 24, 3)),
    }


def make(tmp_path, **kw):
    subjects = [Subject("s0", "train"), Subject("s1", "test"), Subject("s2", "val")]
    return DatasetWriter(tmp_path / "ds", rows=4, cols=5, pitch_m=0.019, rate_hz=14, activities=["standing"], subjects=subjects, **kw)


def test_round_trip_and_split_by_subject(tmp_path):
    with make(tmp_path) as w:
        w.write_shard(shard_arrays(6, [0, 0, 0, 1, 1, 1], {0: 0, 1: 1}))
        w.write_shard(shard_arrays(4, [0, 0, 1, 1], {0: 2, 1: 1}))
    ds = Dataset(tmp_path / "ds", verify=True)
    assert len(ds) == 10
    test = list(ds.shards(split="test"))
    assert [len(s["t_s"]) for s in test] == [3, 2]
    assert all((s["subject"][:, 0] == 1).all() for s in test)
    train = list(ds.shards(split="train"))
    assert len(train) == 1 and len(train[0]["t_s"]) == 3
    np.testing.assert_array_equal(ds.frame(7)["counts"], shard_arrays(4, [0] * 4, {0: 0})["counts"][1])


def test_write_refuses_inconsistent_arrays_and_leaves_no_manifest(tmp_path):
    w = make(tmp_path)
    bad = shard_arrays(3, [0, 0, 0], {0: 0})
    bad["t_s"] = bad["t_s"][:2]
    with pytest.raises(ValueError, match="t_s has 2 frames, counts has 3"):
        w.write_shard(bad)
    bad = shard_arrays(3, [0, 0, 0], {0: 0})
    bad["pose_aa"] = np.zeros((3, 2, 72))
    with pytest.raises(ValueError, match=r"pose_aa must start with \(frames, 3\)"):
        w.write_shard(bad)
    with pytest.raises(DatasetError, match="no manifest.json"):
        Dataset(tmp_path / "ds")


def test_a_damaged_shard_fails_its_hash(tmp_path):
    with make(tmp_path) as w:
        path = w.write_shard(shard_arrays(3, [0, 0, 0], {0: 0}))
    data = bytearray(path.read_bytes())
    data[-30] ^= 0xFF
    path.write_bytes(bytes(data))
    with pytest.raises(DatasetError, match="does not match its SHA-256"):
        Dataset(tmp_path / "ds", verify=True)


def test_existing_dataset_is_not_overwritten(tmp_path):
    with make(tmp_path) as w:
        w.write_shard(shard_arrays(3, [0, 0, 0], {0: 0}))
    with pytest.raises(DatasetError, match="already holds a dataset"):
        make(tmp_path)

"""Datasets with each carpet's calibration, and the board's path (counts → calibration → kPa) for training."""

import hashlib

import numpy as np
import pytest

from export.data import load_tracks
from sim.dataset import Dataset
from sim.dataset.generate import generate


@pytest.fixture(scope="module")
def calibrated(tmp_path_factory):
    out = tmp_path_factory.mktemp("cal") / "a"
    generate(out, subjects=1, seconds_per_activity=2.0, people=(1, 1), seed=2, activities=("squat",), progress=False,
             calibration="truth")
    return out


def test_every_shard_names_a_carpet_whose_calibration_is_in_the_dataset(calibrated):
    ds = Dataset(calibrated)
    cals = ds.manifest["calibrations"]
    assert ds.manifest["settings"]["calibration"] == "truth"
    for info in ds.manifest["shards"]:
        entry = cals[str(info["carpet"])]
        assert entry["method"] == "truth" and (calibrated / entry["file"]).exists()


def test_board_path_reads_the_load_the_true_pressure_holds(calibrated):
    board = load_tracks(calibrated, "test", board=True) + load_tracks(calibrated, "train", board=True)
    truth = load_tracks(calibrated, "test") + load_tracks(calibrated, "train")
    assert len(board) == len(truth) > 0
    for b, t in zip(board, truth):
        np.testing.assert_array_equal(b.pose_aa, t.pose_aa)  # same ground truth
        pb, pt = b.pressure_kpa.astype(np.float32), t.pressure_kpa.astype(np.float32)
        assert not np.array_equal(pb, pt)  # the sensor is in the loop
        loaded = pt > 2.0
        # where the true pressure is well inside the sensor's range, the board reads it within a few kPa
        mid = loaded & (pt < 10.0)
        assert np.median(np.abs(pb[mid] - pt[mid])) < 2.0
        assert (pb[~(pt > 0.05)] > 1.0).mean() < 0.01  # and reads (almost) nothing where nobody stands


def test_board_path_without_calibrations_says_how_to_make_them(tmp_path):
    out = generate(tmp_path / "b", subjects=1, seconds_per_activity=1.0, people=(1, 1), seed=3, activities=("squat",),
                   progress=False)
    with pytest.raises(ValueError, match="--calibration installer"):
        load_tracks(out, "test", board=True)


def test_calibration_files_are_the_same_bytes_for_a_seed(calibrated, tmp_path):
    again = generate(tmp_path / "c", subjects=1, seconds_per_activity=2.0, people=(1, 1), seed=2, activities=("squat",),
                     progress=False, calibration="truth")
    for entry in Dataset(calibrated).manifest["calibrations"].values():
        a = hashlib.sha256((calibrated / entry["file"]).read_bytes()).hexdigest()
        b = hashlib.sha256((again / entry["file"]).read_bytes()).hexdigest()
        assert a == b


def test_unknown_calibration_method_is_refused(tmp_path):
    with pytest.raises(ValueError, match="installer"):
        generate(tmp_path / "d", subjects=1, seconds_per_activity=1.0, activities=("squat",), progress=False,
                 calibration="guess")
    assert not (tmp_path / "d" / "manifest.json").exists()


def test_sim_finds_calibration_through_its_entry_point_and_says_when_it_is_missing(monkeypatch):
    """sim may not import calibration (design.md): the procedure comes from the entry point cavatar.calibrations."""
    from calibration.virtual import calibrate_virtual
    from sim.dataset import calibrate

    assert calibrate.calibrator() is calibrate_virtual
    monkeypatch.setattr(calibrate, "ENTRY_POINT", ("cavatar.calibrations", "no-such-procedure"))
    with pytest.raises(RuntimeError, match="cavatar.calibrations: no-such-procedure.*reinstall cavatar-edge"):
        calibrate.carpet_calibration(3, grid=32, adc_bits=12, pitch_mm=19.05, method="truth")


def test_calibrate_virtual_names_the_board_and_refuses_an_unknown_method():
    from calibration.virtual import calibrate_virtual
    from sim.sensor import CarpetSensor

    sensor = CarpetSensor.random(3, grid=32, adc_bits=12)
    cal, validation = calibrate_virtual(sensor, seed=3, method="truth", device_id="sim-3")
    assert validation is None and cal.device["device_id"] == "sim-3" and cal.baseline_counts.shape == (32, 32)
    with pytest.raises(ValueError, match=r"one of \('installer', 'truth'\)"):
        calibrate_virtual(sensor, seed=3, method="guess")


def test_board_tracks_reach_the_model_floored_and_clipped_as_the_runtime_feeds_it(calibrated):
    from edge.infer.model_input import FLOOR_KPA, SATURATION_KPA
    from export.evaluate import track_pressure

    board = (load_tracks(calibrated, "test", board=True) + load_tracks(calibrated, "train", board=True))[0]
    assert board.board and board.slice(0, 3).board and not load_tracks(calibrated, "train")[0].board
    raw = board.pressure_kpa.astype(np.float32)
    fed = track_pressure(board, seed=0)
    np.testing.assert_array_equal(fed, np.minimum(np.where(raw < FLOOR_KPA, 0.0, raw), SATURATION_KPA))
    np.testing.assert_array_equal(fed, track_pressure(board, seed=1))  # no random corruption on top of the sensor


def test_training_input_of_a_board_track_is_floored_and_clipped_as_the_runtime_does():
    from edge.infer.model_input import FLOOR_KPA, SATURATION_KPA
    from export.data import corrupt, training_input

    p = np.array([[[0.0, 0.1, 0.5, 5.0, 40.0]]], np.float32)
    out = training_input(p, np.random.default_rng(0), board=True).numpy()[0, 0]
    assert out[0] == out[1] == 0.0                       # below the runtime's floor: nothing
    assert 0.92 * 0.5 <= out[2] <= 1.08 * 0.5 and 0.92 * 5.0 <= out[3] <= 1.08 * 5.0  # one global gain, nothing else
    assert out[4] == SATURATION_KPA and FLOOR_KPA > 0.1
    clean = training_input(p, np.random.default_rng(0), board=False).numpy()
    np.testing.assert_array_equal(clean, corrupt(p, np.random.default_rng(0)).numpy())


def test_a_frames_run_trains_on_the_board_path_and_refuses_an_unknown_input(calibrated, tmp_path):
    from export.model import ModelConfig
    from export.train import TrainConfig, Trainer

    cfg = TrainConfig(data=str(calibrated), out=str(tmp_path / "run"), stage="frames", input="board", steps=2, batch=4,
                      checkpoint_every=1, val_every=100, progress=False)
    tr = Trainer(cfg, ModelConfig.preset("tiny"))
    assert tr.tracks and all(t.board for t in tr.tracks)
    tr.run()
    with pytest.raises(ValueError, match="'clean' or 'board'"):
        Trainer(TrainConfig(data=str(calibrated), out=str(tmp_path / "x"), stage="frames", input="counts"),
                ModelConfig.preset("tiny"))


def test_board_path_masks_a_person_alone_to_their_footprint_as_the_runtime_does(calibrated):
    from scipy import ndimage

    board = load_tracks(calibrated, "test", board=True) + load_tracks(calibrated, "train", board=True)
    truth = load_tracks(calibrated, "test") + load_tracks(calibrated, "train")
    for b, t in zip(board, truth):
        pt = t.pressure_kpa.astype(np.float32)
        footprint = np.stack([ndimage.binary_dilation(f > 0.2, iterations=2) for f in pt])
        assert not b.pressure_kpa[~footprint].any()  # nothing read away from the person reaches the model
        # and their own load does (the sensor reads less than the truth: saturation, crosstalk)
        assert b.pressure_kpa[footprint].astype(np.float32).sum() > 0.3 * pt.sum()

"""Loaders for real recordings, tested on small files written here in the release's formats."""

import pickle

import h5py
import joblib
import numpy as np
import pytest

from sim.dataset import Dataset
from sim.real.convert import convert
from sim.real.intelligent_carpet import RecordingError, TileLayout, load_aligned, load_tiles, read_tile
from sim.real.vibe import load_vibe, match_to_carpet, read_video_times


def write_tile(path, ts, pressure, extra_rows=5):
    """A tile file as the recorder leaves it: arrays pre-allocated past frame_count."""
    n = len(ts)
    with h5py.File(path, "w") as f:
        f["frame_count"] = np.array([n])
        f["ts"] = np.concatenate([ts, np.zeros(extra_rows)])
        f["pressure"] = np.concatenate([pressure, np.full((extra_rows, *pressure.shape[1:]), 999)]).astype(np.int32)


def tile_values(k, n, size=4):
    """Tile k's frames: every value encodes (tile, frame) so the assembly can be checked."""
    return np.stack([np.full((size, size), 100 * k + i) for i in range(n)])


@pytest.fixture
def recording(tmp_path):
    rng = np.random.default_rng(0)
    t0 = 1000.0
    for k in range(9):
        ts = t0 + np.arange(30) / 14.0 + rng.uniform(-0.004, 0.004, 30) + 0.002 * k  # own clock per tile
        write_tile(tmp_path / f"touch{k}.hdf5", ts, tile_values(k, 30))
    return tmp_path


def test_read_tile_trims_to_frame_count(recording):
    ts, pressure = read_tile(recording / "touch0.hdf5")
    assert len(ts) == 30 and pressure.shape == (30, 4, 4) and pressure.max() < 999


def test_tiles_assemble_into_frames_on_one_time_base(recording):
    layout = TileLayout.row_major(3, 3, tile=4)
    rec = load_tiles(recording, layout)
    assert rec.frames.shape[1:] == (12, 12)
    assert len(rec.frames) >= 28
    assert rec.max_skew_s < 0.03
    f = rec.frames[5]
    for k in range(9):
        r, c = divmod(k, 3)
        block = f[4 * r : 4 * r + 4, 4 * c : 4 * c + 4]
        assert (block // 100 == k).all(), "tile landed in the wrong place"
    # every tile contributes its frame nearest in time: the frame numbers agree within one
    frame_numbers = np.array([f[4 * (k // 3), 4 * (k % 3)] % 100 for k in range(9)])
    assert frame_numbers.max() - frame_numbers.min() <= 1


def test_rotated_tile_layout(tmp_path):
    write_tile(tmp_path / "touch0.hdf5", np.arange(3) / 14, np.stack([np.arange(4).reshape(2, 2)] * 3))
    rec = load_tiles(tmp_path, TileLayout(((0, 0, 1),), 2, 2))
    np.testing.assert_array_equal(rec.frames[0], np.rot90(np.arange(4).reshape(2, 2)))


def test_bad_tile_files_are_named(tmp_path):
    with h5py.File(tmp_path / "touch0.hdf5", "w") as f:
        f["ts"] = np.arange(3.0)
    with pytest.raises(RecordingError, match=r"touch0.hdf5: no dataset \['frame_count', 'pressure'\]"):
        load_tiles(tmp_path)
    (tmp_path / "touch1.hdf5").write_bytes(b"not hdf5")
    with pytest.raises(RecordingError, match="not a readable HDF5"):
        read_tile(tmp_path / "touch1.hdf5")
    with pytest.raises(RecordingError, match="no touch<k>.hdf5"):
        load_tiles(tmp_path / "nowhere")


@pytest.mark.parametrize("form", ["array", "tuple", "dict"])
def test_aligned_pickle_forms(tmp_path, form):
    frames = np.random.default_rng(1).integers(0, 1024, (5, 96, 96))
    ts = 10 + np.arange(5) / 14
    obj = {"array": frames, "tuple": (ts, frames), "dict": {"ts": ts, "pressure": frames}}[form]
    path = tmp_path / "touch_aligned.p"
    path.write_bytes(pickle.dumps(obj, protocol=2))
    rec = load_aligned(path)
    np.testing.assert_array_equal(rec.frames, frames)
    assert rec.t_s[1] - rec.t_s[0] == pytest.approx(1 / 14)


def write_vibe(path, n_video=60):
    rng = np.random.default_rng(2)
    out = {}
    for tid, ids in ((1, np.arange(0, 40)), (4, np.arange(20, 60))):
        out[tid] = {
            "pose": rng.normal(0, 0.3, (len(ids), 72)), "betas": rng.normal(0, 1, (len(ids), 10)),
            "pred_cam": rng.normal(1, 0.1, (len(ids), 3)), "joints3d": rng.normal(0, 1, (len(ids), 49, 3)),
            "frame_ids": ids, "verts": np.zeros((len(ids), 10, 3)),
        }
    joblib.dump(out, path)
    return out


def test_vibe_tracks_match_carpet_frames_by_time(tmp_path):
    truth = write_vibe(tmp_path / "vibe_output.pkl")
    (tmp_path / "webcam1.txt").write_text("\n".join(f"{100 + i / 30:.6f}" for i in range(60)) + "\n")
    tracks = load_vibe(tmp_path / "vibe_output.pkl")
    assert [t.track_id for t in tracks] == [1, 4]
    video_t = read_video_times(tmp_path / "webcam1.txt")
    carpet_t = 100 + np.arange(28) / 14
    people = match_to_carpet(tracks, video_t, carpet_t)
    # track 1 covers video frames 0..39 (t < 101.33 s), track 4 frames 20..59
    assert people["present"][:, 0].sum() == (carpet_t <= 100 + 39 / 30 + 0.05).sum()
    assert people["present"][0, 0] and not people["present"][0, 1]
    k = 10  # carpet t = 100.714 s → video frame 21 (t = 100.7), track 1 row 21
    np.testing.assert_allclose(people["pose_aa"][k, 0], truth[1]["pose"][21], atol=1e-6)
    np.testing.assert_allclose(people["betas"][k, 1], truth[4]["betas"][1], atol=1e-6)
    assert np.isnan(people["transl_m"]).all()


def test_camera_rotation_turns_only_the_global_orientation(tmp_path):
    write_vibe(tmp_path / "v.pkl")
    tracks = load_vibe(tmp_path / "v.pkl")
    rx90 = np.array([[1, 0, 0], [0, 0, -1], [0, 1, 0]], float)
    t = 100 + np.arange(60) / 30
    a = match_to_carpet(tracks, t, t[:5], cam_to_carpet=rx90)
    b = match_to_carpet(tracks, t, t[:5])
    np.testing.assert_allclose(a["pose_aa"][:, 0, 3:], b["pose_aa"][:, 0, 3:])
    assert not np.allclose(a["pose_aa"][:, 0, :3], b["pose_aa"][:, 0, :3])


def test_bad_vibe_files_are_named(tmp_path):
    joblib.dump({1: {"pose": np.zeros((3, 72))}}, tmp_path / "v.pkl")
    with pytest.raises(RecordingError, match=r"track 1 lacks \['betas', 'frame_ids'\]"):
        load_vibe(tmp_path / "v.pkl")
    (tmp_path / "t.txt").write_text("0.1\nabc\n")
    with pytest.raises(RecordingError, match="one number per line"):
        read_video_times(tmp_path / "t.txt")


def test_convert_writes_a_dataset_that_says_what_is_unknown(tmp_path, recording):
    write_vibe(recording / "vibe_output.pkl")
    (recording / "webcam1.txt").write_text("\n".join(f"{1000 + i / 30:.6f}" for i in range(60)))
    out = convert(recording, tmp_path / "ds", subject_id="p01", vibe=recording / "vibe_output.pkl",
                  video_times=recording / "webcam1.txt")
    ds = Dataset(out, verify=True)
    assert ds.manifest["source"] == "intelligent_carpet"
    assert set(ds.manifest["settings"]["unknown"]) == {"pressure_kpa", "transl_m", "joints_m"}
    shard = next(ds.shards(split="test"))
    assert shard["counts"].dtype == np.uint16 and shard["present"].any()
    assert ds.manifest["rate_hz"] == pytest.approx(14, rel=0.05)

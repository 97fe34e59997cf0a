"""The staged recipe: frames (encoder, i.i.d. frames) → head (frozen encoder, cached features) → windows."""

from __future__ import annotations

import json

import numpy as np
import pytest

torch = pytest.importorskip("torch")

from export.model import ModelConfig  # noqa: E402
from export.train import TrainConfig, Trainer  # noqa: E402


def _trainer(data, out, stage, steps, init="", **kw):
    cfg = TrainConfig(data=data, out=str(out), stage=stage, init=str(init), steps=steps, batch=8, lr=3e-3, optimizer="adamw",
                      val_every=0, checkpoint_every=1000, log_every=1, progress=False, seed=5, threads=1, cache_copies=1, **kw)
    return Trainer(cfg, ModelConfig.preset("tiny"))


@pytest.fixture(scope="module")
def frames_run(tiny_data, tmp_path_factory):
    out = tmp_path_factory.mktemp("frames")
    tr = _trainer(str(tiny_data), out, "frames", 40, turns=False)  # learning, without the harder turned copies
    tr.run()
    return out


def _losses(run):
    return [x["loss"] for x in map(json.loads, (run / "log.jsonl").read_text().splitlines()) if "loss" in x]


def test_frames_stage_learns_and_saves_its_frame_head(frames_run):
    losses = _losses(frames_run)
    assert len(losses) == 40
    assert np.mean(losses[-8:]) < 0.8 * np.mean(losses[:8])
    ck = torch.load(frames_run / "checkpoint.pt", weights_only=False)
    assert ck["frame_head"] is not None and ck["train_config"]["stage"] == "frames"


def test_frames_batches_mix_tracks(tiny_data, tmp_path):
    tr = _trainer(str(tiny_data), tmp_path, "frames", 1)
    batch_activities = [set(tr.sample()[1]["activity"].tolist()) for _ in range(5)]
    assert max(len(a) for a in batch_activities) > 1  # one chunk of one track would give one activity


def test_head_stage_freezes_the_encoder_and_trains_the_head(tiny_data, frames_run, tmp_path):
    tr = _trainer(str(tiny_data), tmp_path, "head", 15, init=frames_run / "checkpoint.pt")
    enc0 = {k: v.clone() for k, v in tr.net.encoder.state_dict().items()}
    head0 = {k: v.clone() for k, v in tr.net.head.state_dict().items()}
    tr.run()
    assert all(torch.equal(enc0[k], v) for k, v in tr.net.encoder.state_dict().items())
    assert any(not torch.equal(head0[k], v) for k, v in tr.net.head.state_dict().items())
    # the cache holds one feature row per frame, equal to encoding that frame again
    frames = sum(len(t) for t in tr.tracks)
    assert sum(len(f) for f in tr.cache.feats[0]) == frames
    batch = tr.cache.sample(tr.tracks, tr.weights, 4, tr.model_cfg.window, np.random.default_rng(0), "cpu")
    assert batch["windows"].shape == (4, tr.model_cfg.window, tr.model_cfg.features)


def test_windows_stage_starts_from_the_head_stage(tiny_data, frames_run, tmp_path):
    head = _trainer(str(tiny_data), tmp_path / "head", "head", 3, init=frames_run / "checkpoint.pt")
    head.run()
    e2e = _trainer(str(tiny_data), tmp_path / "e2e", "windows", 2, init=tmp_path / "head" / "checkpoint.pt")
    for k, v in head.net.state_dict().items():
        assert torch.equal(v, e2e.net.state_dict()[k])
    e2e.run()
    assert e2e.step == 2


def test_resumed_frames_stage_gives_the_same_next_step(tiny_data, tmp_path):
    straight = _trainer(str(tiny_data), tmp_path / "a", "frames", 4)
    straight.run()
    first = _trainer(str(tiny_data), tmp_path / "b", "frames", 2)
    first.run()
    resumed = _trainer(str(tiny_data), tmp_path / "b", "frames", 4)
    resumed.load(tmp_path / "b" / "checkpoint.pt")
    resumed.run()
    for k, v in straight.net.state_dict().items():
        assert torch.allclose(v, resumed.net.state_dict()[k], atol=1e-6), k


def test_several_datasets_and_a_wrong_init(tiny_data, tmp_path):
    one = _trainer(str(tiny_data), tmp_path / "one", "frames", 1)
    two = _trainer([str(tiny_data), str(tiny_data)], tmp_path / "two", "frames", 1)
    assert len(two.tracks) == 2 * len(one.tracks)
    with pytest.raises(ValueError, match="stage must be one of"):
        _trainer(str(tiny_data), tmp_path / "x", "everything", 1)
    other = ModelConfig.preset("tiny", features=8)
    cfg = TrainConfig(data=str(tiny_data), out=str(tmp_path / "y"), stage="head", init=str(tmp_path / "one" / "checkpoint.pt"),
                      progress=False, threads=1)
    one.run()
    with pytest.raises(ValueError, match="same architecture"):
        Trainer(cfg, other)


def test_leave_one_activity_out_never_trains_on_it(tiny_data, tmp_path):
    from sim.motion import ACTIVITIES

    tr = _trainer(str(tiny_data), tmp_path, "frames", 1, exclude_activities=["squat"])
    assert tr.tracks and all((t.activity != ACTIVITIES.index("squat")).all() for t in tr.tracks)
    full = _trainer(str(tiny_data), tmp_path / "all", "frames", 1)
    assert sum(map(len, tr.tracks)) < sum(map(len, full.tracks))
    with pytest.raises(ValueError, match="unknown activities"):
        _trainer(str(tiny_data), tmp_path / "x", "frames", 1, exclude_activities=["juggling"])


def test_cosine_schedule_decays_to_a_hundredth(tiny_data, tmp_path):
    tr = _trainer(str(tiny_data), tmp_path, "frames", 10, lr_schedule="cosine")
    assert tr.lr_at(0) == pytest.approx(3e-3) and tr.lr_at(5) == pytest.approx(3e-3 * 0.505)
    assert tr.lr_at(10) == pytest.approx(3e-5)
    tr.run()
    assert tr.opt.param_groups[0]["lr"] == pytest.approx(tr.lr_at(9))  # the last step ran at the schedule's value


@pytest.mark.parametrize("k", [1, 2, 3])
def test_a_quarter_turn_turns_pressure_and_labels_alike(tiny_data, k):
    from edge.body import BodyModel
    from edge.infer.normalise import center_of_pressure_m
    from export.data import load_tracks
    from export.stages import turn_frames, turn_labels

    pitch = 19.05e-3 * 3
    tr = load_tracks(tiny_data, "train")[0]
    f = np.arange(0, len(tr), 7)
    p = tr.pressure_kpa[f].astype(np.float32)
    side = p.shape[-1] * pitch
    pose, transl, joints = turn_labels(tr.pose_aa[f], tr.transl_m[f], tr.joints_m[f], k, side)
    q = np.linalg.matrix_power(np.array([[0.0, -1.0], [1.0, 0.0]]), k)
    centre = np.array([side / 2, side / 2])
    loaded = p.sum((1, 2)) > 0
    cop, cop_turned = center_of_pressure_m(p, pitch), center_of_pressure_m(turn_frames(p, k), pitch)
    np.testing.assert_allclose(cop_turned[loaded], ((cop - centre) @ q.T + centre)[loaded], atol=1e-9)
    # the turned labels through the body model give the turned joints: pressure and body moved together
    body = BodyModel.load("lite")
    j = body.forward(pose, tr.betas[f], transl)["joints"]
    j0 = body.forward(tr.pose_aa[f], tr.betas[f], tr.transl_m[f])["joints"]
    np.testing.assert_allclose(j - j[:, :1], joints - joints[:, :1], atol=2e-5)
    np.testing.assert_allclose(j[:, :, :2] - centre, (j0[:, :, :2] - centre) @ q.T, atol=2e-5)
    np.testing.assert_allclose(j[:, :, 2], j0[:, :, 2], atol=2e-5)
    assert np.array_equal(turn_frames(turn_frames(p, k), 4 - k), p)

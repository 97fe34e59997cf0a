"""`cavatar eval` tables, the mean-pose baseline, bundle weights and `cavatar finetune`, on a tiny model."""

from __future__ import annotations

import json

import numpy as np
import pytest

torch = pytest.importorskip("torch")
pytest.importorskip("onnxscript")

from edge.cli import main  # noqa: E402
from export.model import ModelConfig  # noqa: E402
from export.train import TrainConfig, Trainer  # noqa: E402

PITCH = 19.05e-3 * 3


@pytest.fixture(scope="module")
def bundle(tiny_data, tmp_path_factory):
    from export.bundle import build_bundle

    run = tmp_path_factory.mktemp("evalrun")
    cfg = TrainConfig(data=str(tiny_data), out=str(run), stage="frames", steps=30, batch=16, lr=3e-3, optimizer="adamw",
                      val_every=0, progress=False, seed=2, threads=1)
    Trainer(cfg, ModelConfig.preset("tiny")).run()
    out = tmp_path_factory.mktemp("bundles") / "tiny-32"
    build_bundle(run / "checkpoint.pt", tiny_data, out, "tiny-32", max_eval_tracks=2)
    return out


def test_bundle_carries_its_weights_and_baseline(bundle, tiny_data):
    from edge.infer import ModelBundle
    from export.bundle import load_net
    from export.data import load_tracks
    from export.evaluate import track_inputs

    net, manifest = load_net(bundle)
    assert "weights.npz" in manifest["files"] and len(manifest["baseline"]["pose_aa"]) == 72
    x = track_inputs(load_tracks(tiny_data, "train", max_tracks=1)[0], PITCH, 0)[0][:3]
    with torch.no_grad():
        ref = net.encoder(torch.from_numpy(x)).numpy()
    b = ModelBundle.load(bundle)
    assert np.abs(b.encode(x) - ref).max() < 0.1 * np.abs(ref).max()  # int8 encoder against the float weights


def test_tables_are_zero_for_the_truth_and_positive_for_the_baseline(tiny_data):
    from export.data import load_tracks
    from export.tables import _bodies, _errors, baseline_errors, mean_pose, summarise

    lite, full = _bodies()
    tr = load_tracks(tiny_data, "test")[0]
    frames = np.arange(0, len(tr), 5)
    truth = _errors(tr.pose_aa[frames], tr.betas[frames], tr.transl_m[frames], tr, frames, lite, full)
    assert truth["mpjpe_cm"].max() < 1e-3 and truth["pve_cm"].max() < 1e-3 and truth["transl_cm"].max() < 1e-6
    assert truth["pa_mpjpe_cm"].max() < 1e-3 and truth["local_mpjpe_cm"].max() < 1e-3 and truth["heading_deg"].max() < 1e-3
    # the truth turned 180° about the vertical: heading 180°, the local pose (root-aligned) and PA still perfect
    from edge.infer.heading import turn_half

    turned = _errors(turn_half(tr.pose_aa[frames]), tr.betas[frames], tr.transl_m[frames], tr, frames, lite, full,
                     model_pose_aa=tr.pose_aa[frames])
    np.testing.assert_allclose(turned["heading_deg"], 180.0, atol=1e-3)
    assert turned["local_mpjpe_cm"].max() < 1e-3 and turned["pa_mpjpe_cm"].max() < 1e-3 and turned["mpjpe_cm"].min() > 1.0
    assert turned["model_heading_deg"].max() < 1e-3 and turned["model_mpjpe_cm"].max() < 1e-3
    base = baseline_errors(mean_pose(load_tracks(tiny_data, "train")), [tr], PITCH, frame_stride=5, bodies=(lite, full))
    assert base["mpjpe_cm"].mean() > 1.0 and base["pve_cm"].mean() > 1.0
    s = summarise(truth, base)
    assert s["overall"]["mpjpe_vs_baseline"] < 1e-3 and len(s["by_joint_cm"]) == 24
    t = summarise(turned)["overall"]
    assert t["heading_over90_pct"] == 100.0 and t["model_heading_over45_pct"] == 0.0 and t["heading_median_deg"] > 179.9


def test_eval_cli_writes_json_and_markdown(bundle, tiny_data, tmp_path, capsys):
    assert main(["eval", "--bundle", str(bundle), "--data", str(tiny_data), "--split", "all", "--stride", "4",
                 "--out", str(tmp_path / "t" / "tiny")]) == 0
    result = json.loads((tmp_path / "t" / "tiny.json").read_text())
    md = (tmp_path / "t" / "tiny.md").read_text()
    assert {"stepping", "squat", "lunge"} <= set(result["by_activity"]) <= {"stepping", "squat", "lunge", "standing"}
    assert len(result["setup"]["subjects"]) == 3 and result["baseline"]["mpjpe_cm"] > 0
    for row in result["by_activity"].values():
        assert np.isfinite([row["mpjpe_cm"], row["pve_cm"], row["transl_cm"]]).all()
    assert "### per activity" in md and "mean pose at CoP (baseline)" in md and "| left_wrist |" in md
    assert "model alone (heading not resolved)" in md and "PA-MPJPE" in md and "root-aligned" in md
    o = result["overall"]
    for k in ("pa_mpjpe_cm", "local_mpjpe_cm", "heading_median_deg", "heading_over45_pct", "heading_over90_pct",
              "model_heading_over90_pct"):
        assert np.isfinite(o[k])
    assert o["pa_mpjpe_cm"] <= o["mpjpe_cm"] and 0 <= o["heading_over90_pct"] <= o["heading_over45_pct"] <= 100
    assert "heading median" in capsys.readouterr().out
    # the paper's protocol: training subjects, the last 10 % of every track in time
    assert main(["eval", "--bundle", str(bundle), "--data", str(tiny_data), "--protocol", "seen-time", "--stride", "1",
                 "--no-resolve-heading", "--out", str(tmp_path / "seen")]) == 0
    seen = json.loads((tmp_path / "seen.json").read_text())
    from export.data import load_tracks

    train = load_tracks(tiny_data, "train")
    assert seen["setup"]["split"] == "train" and "80/10/10" in seen["setup"]["protocol"]
    assert seen["overall"]["frames"] == sum(len(t) - int(np.ceil(0.9 * len(t))) for t in train)
    assert "model_heading_over90_pct" not in seen["overall"] and seen["setup"]["heading"] == "model alone"
    assert main(["eval", "--bundle", str(bundle), "--data", str(tiny_data), "--people", "3", "--out", str(tmp_path / "x")]) == 2
    # the board's path needs the carpets' calibrations, and says how to make them
    capsys.readouterr()
    assert main(["eval", "--bundle", str(bundle), "--data", str(tiny_data), "--input", "board",
                 "--out", str(tmp_path / "b")]) == 2
    assert "--calibration installer" in capsys.readouterr().err and not (tmp_path / "b.json").exists()


def test_finetune_splits_in_time_and_writes_a_new_bundle(bundle, tiny_data, tmp_path):
    from edge.infer import ModelBundle
    from export.data import load_tracks
    from export.finetune import split_in_time

    tracks = load_tracks(tiny_data, "test")
    head, rest = split_in_time(tracks, 0.5)
    assert sum(map(len, head)) + sum(map(len, rest)) == sum(map(len, tracks))
    np.testing.assert_array_equal(head[0].pose_aa[-1], tracks[0].pose_aa[len(head[0]) - 1])
    np.testing.assert_array_equal(rest[0].pose_aa[0], tracks[0].pose_aa[len(head[0])])
    with pytest.raises(ValueError, match="fraction"):
        split_in_time(tracks, 1.0)

    out = tmp_path / "ft"
    assert main(["finetune", "--bundle", str(bundle), "--data", str(tiny_data), "--split", "test", "--fraction", "0.5",
                 "--steps", "3", "--out", str(out)]) == 0
    m = ModelBundle.load(out).manifest
    assert m["training"]["finetuned_from"].startswith("tiny-32@") and m["training"]["fraction"] == 0.5
    assert m["name"] == "tiny-32-ft50" and m["baseline"] == json.loads((bundle / "manifest.json").read_text())["baseline"]
    before = np.load(bundle / "weights.npz")
    after = np.load(out / "weights.npz")
    assert any(not np.array_equal(before[k], after[k]) for k in before.files)  # it trained
    assert main(["finetune", "--bundle", str(bundle), "--data", str(tiny_data), "--fraction", "1.2", "--out", str(tmp_path / "no")]) == 2
    assert not (tmp_path / "no").exists()


def test_finetune_sweep_judges_every_fraction_on_the_same_frames(bundle, tiny_data, tmp_path):
    from export.sweep import main as sweep_main

    assert sweep_main(["--bundle", str(bundle), "--data", str(tiny_data), "--subject", "s02", "--fractions", "0,0.4",
                       "--steps", "2", "--out", str(tmp_path / "ft")]) == 0
    result = json.loads((tmp_path / "ft.json").read_text())
    assert set(result["mpjpe_cm"]["s02"]) == {"0%", "40%"} and result["setup"]["held_out"] == "the last 60% of every track"
    assert all(np.isfinite(v) for v in result["mean_mpjpe_cm"].values())
    assert "| s02 |" in (tmp_path / "ft.md").read_text()


@pytest.mark.parametrize("argv", [["train", "--data", "d", "--out", "o"], ["bundle", "c.pt", "--data", "d", "--out", "o", "--name", "n"],
                                  ["eval", "--bundle", "b", "--data", "d", "--out", "o"],
                                  ["finetune", "--bundle", "b", "--data", "d", "--fraction", "0.5", "--out", "o"]])
def test_export_commands_without_torch_name_the_extra(argv, monkeypatch, capsys):
    import sys

    monkeypatch.setitem(sys.modules, "torch", None)  # a board: no torch
    for name in [m for m in sys.modules if m.startswith("export.") and m != "export.cli"]:
        monkeypatch.delitem(sys.modules, name)
    assert main(argv) == 2
    assert "needs the export extra (pip install '.[export]')" in capsys.readouterr().err

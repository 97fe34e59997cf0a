"""edge.infer.ModelBundle: loads, runs, and refuses tampered or mismatched bundles (no torch)."""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np
import pytest

onnx = pytest.importorskip("onnx")
from onnx import TensorProto, helper, numpy_helper  # noqa: E402

from edge.infer import BundleError, ModelBundle  # noqa: E402
from edge.infer.bundle import SCHEMA, sha256_file, write_manifest  # noqa: E402

H, W, T, F = 16, 12, 40, 8
SIZES = {"rot6d": 144, "betas": 10, "transl_rel_m": 3, "activity_logits": 12, "confidence": 1}


def _encoder() -> onnx.ModelProto:
    """pressure (B,1,H,W) → mean over H,W (B,1) → ×w (1,F) → features (B,F)."""
    w = numpy_helper.from_array(np.linspace(0.5, 2.0, F, dtype=np.float32)[None], "w")
    nodes = [helper.make_node("ReduceMean", ["pressure", "axes"], ["m"], keepdims=0),
             helper.make_node("MatMul", ["m", "w"], ["features"])]
    axes = numpy_helper.from_array(np.array([2, 3], np.int64), "axes")
    g = helper.make_graph(nodes, "enc", [helper.make_tensor_value_info("pressure", TensorProto.FLOAT, ["batch", 1, H, W])],
                          [helper.make_tensor_value_info("features", TensorProto.FLOAT, ["batch", F])], [w, axes])
    return helper.make_model(g, opset_imports=[helper.make_opsetid("", 20)])


def _head() -> onnx.ModelProto:
    """features (B,T,F) → last frame (B,F) → a linear map per output (rot6d biased to identity)."""
    rng = np.random.default_rng(0)
    inits = [numpy_helper.from_array(np.array([T - 1], np.int64), "last")]
    nodes = [helper.make_node("Gather", ["features", "last"], ["g"], axis=1),
             helper.make_node("Squeeze", ["g", "one"], ["h"])]
    inits.append(numpy_helper.from_array(np.array([1], np.int64), "one"))
    outputs = []
    for name, n in SIZES.items():
        inits.append(numpy_helper.from_array((rng.normal(size=(F, n)) * 0.01).astype(np.float32), f"w_{name}"))
        bias = np.zeros(n, np.float32)
        if name == "rot6d":
            bias[:] = np.tile([1, 0, 0, 0, 1, 0], 24)
        inits.append(numpy_helper.from_array(bias, f"b_{name}"))
        raw = name if name != "confidence" else "conf_raw"
        nodes += [helper.make_node("MatMul", ["h", f"w_{name}"], [f"mm_{name}"]),
                  helper.make_node("Add", [f"mm_{name}", f"b_{name}"], [raw])]
        shape = ["batch", n]
        if name == "confidence":
            nodes += [helper.make_node("Sigmoid", ["conf_raw"], ["conf_s"]),
                      helper.make_node("Squeeze", ["conf_s", "one"], ["confidence"])]
            shape = ["batch"]
        outputs.append(helper.make_tensor_value_info(name, TensorProto.FLOAT, shape))
    g = helper.make_graph(nodes, "head", [helper.make_tensor_value_info("features", TensorProto.FLOAT, ["batch", T, F])],
                          outputs, inits)
    return helper.make_model(g, opset_imports=[helper.make_opsetid("", 20)])


def make_bundle(folder: Path, grid=(H, W)) -> Path:
    folder.mkdir(parents=True, exist_ok=True)
    onnx.save(_encoder(), folder / "encoder.onnx")
    onnx.save(_head(), folder / "head.onnx")
    from edge.body.model import shipped_model_path

    manifest = {"schema": SCHEMA, "name": "toy", "grid": list(grid), "pitch_m": 0.05, "window": T, "features": F,
                "input": {"normalisation": {"kind": "log1p", "scale_kpa": 1.0}},
                "activities": [f"a{i}" for i in range(12)],
                "body_model": {"name": "lite", "file": "cavatar_body_lite.npz", "sha256": sha256_file(shipped_model_path("lite"))},
                "files": {f: sha256_file(folder / f) for f in ("encoder.onnx", "head.onnx")}}
    write_manifest(folder, manifest)
    return folder


def test_loads_and_runs(tmp_path):
    b = ModelBundle.load(make_bundle(tmp_path / "b"), grid=(H, W))
    p = np.zeros((3, H, W), np.float32)
    p[:, 4:6, 5:7] = 10.0
    feats = b.encode(b.normalise(p)[:, None])
    assert feats.shape == (3, F)
    origin = b.origin_m(p)
    np.testing.assert_allclose(origin[0], [6 * 0.05, 5 * 0.05, 0.0])
    out = b.head(np.repeat(feats[:, None], T, 1), origin_m=origin)
    assert out["pose_aa"].shape == (3, 72) and out["betas"].shape == (3, 10) and out["transl_m"].shape == (3, 3)
    assert out["activity_probs"].shape == (3, 12) and out["confidence"].shape == (3,)
    np.testing.assert_allclose(out["activity_probs"].sum(1), 1.0, rtol=1e-5)
    np.testing.assert_allclose(out["transl_m"], out["transl_rel_m"] + origin, atol=1e-6)
    assert np.abs(out["pose_aa"]).max() < 0.2  # near-identity rotations
    assert b.version.startswith("toy@")
    with pytest.raises(ValueError, match="expects"):
        b.encode(np.zeros((1, 1, H + 1, W), np.float32))


def test_head_outputs_are_the_graphs_own_outputs_that_head_publishes(tmp_path):
    """Evaluation (export.evaluate.bundle_callables) reads the raw head outputs through this public method."""
    from edge.infer.bundle import HEAD_OUTPUTS
    from edge.infer.rotations import rot6d_to_axis_angle

    b = ModelBundle.load(make_bundle(tmp_path / "b"), grid=(H, W))
    window = np.random.default_rng(0).normal(size=(2, T, F)).astype(np.float64)  # any float dtype is taken
    raw = b.head_outputs(window)
    assert set(HEAD_OUTPUTS) <= set(raw) and raw["rot6d"].shape == (2, 144) and raw["rot6d"].dtype == np.float32
    out = b.head(window)
    np.testing.assert_allclose(out["pose_aa"], rot6d_to_axis_angle(raw["rot6d"]), atol=1e-6)
    np.testing.assert_array_equal(out["transl_rel_m"], raw["transl_rel_m"])
    with pytest.raises(ValueError, match=rf"head expects \(B,{T},{F}\), got \(2, {T + 1}, {F}\)"):
        b.head_outputs(np.zeros((2, T + 1, F), np.float32))
    with pytest.raises(ValueError, match="head input"):
        b.head_outputs(np.full((1, T, F), np.nan, np.float32))


def test_tampered_file_is_refused_naming_file_and_hashes(tmp_path):
    folder = make_bundle(tmp_path / "b")
    expected = json.loads((folder / "manifest.json").read_text())["files"]["head.onnx"]
    data = bytearray((folder / "head.onnx").read_bytes())
    data[-5] ^= 0xFF
    (folder / "head.onnx").write_bytes(bytes(data))
    with pytest.raises(BundleError, match="head.onnx") as exc:
        ModelBundle.load(folder)
    assert expected in str(exc.value) and sha256_file(folder / "head.onnx") in str(exc.value)


def test_grid_mismatch_is_refused(tmp_path):
    folder = make_bundle(tmp_path / "b")
    with pytest.raises(BundleError, match=r"16×12 carpet, this carpet is 96×96"):
        ModelBundle.load(folder, grid=(96, 96))


def test_manifest_grid_that_disagrees_with_the_graph_is_refused(tmp_path):
    folder = make_bundle(tmp_path / "b")
    m = json.loads((folder / "manifest.json").read_text())
    m["grid"] = [32, 32]
    write_manifest(folder, m)  # a consistent manifest that is wrong about its graph
    with pytest.raises(BundleError, match="encoder.onnx"):
        ModelBundle.load(folder)


def test_missing_and_unlisted_files_and_body_model(tmp_path):
    folder = make_bundle(tmp_path / "b")
    (folder / "encoder.onnx").unlink()
    with pytest.raises(BundleError, match="encoder.onnx is listed in the manifest but missing"):
        ModelBundle.load(folder)
    folder = make_bundle(tmp_path / "c")
    m = json.loads((folder / "manifest.json").read_text())
    m["body_model"]["sha256"] = "0" * 64
    write_manifest(folder, m)
    with pytest.raises(BundleError, match="body model 'lite'"):
        ModelBundle.load(folder)
    with pytest.raises(BundleError, match="no manifest.json"):
        ModelBundle.load(tmp_path / "nothing")

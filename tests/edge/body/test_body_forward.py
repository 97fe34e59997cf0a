"""numpy SMPL forward: conventions, paths, hard inputs; against a naive reference."""

import hashlib
import json
import subprocess
import sys
import warnings

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from edge.body import SMPL_PARENTS, BodyModel, BodyModelWarning, lbs, shipped_model_path, write_body_npz


@pytest.fixture(scope="module")
def lite():
    return BodyModel.load("lite")


@pytest.fixture(scope="module")
def lite64():
    return BodyModel.load("lite", vertex_dtype=np.float64)


def naive_smpl(arrays, pose, betas, transl):
    """Textbook SMPL for one body, loops and 4x4 matrices, scipy rotations."""
    v = arrays.v_template + arrays.shapedirs @ betas
    joints = arrays.J_regressor @ v
    rots = Rotation.from_rotvec(pose.reshape(-1, 3)).as_matrix()
    if arrays.posedirs is not None:
        v = v + arrays.posedirs @ (rots[1:] - np.eye(3)).reshape(-1)
    world = []
    for i, p in enumerate(arrays.parents):
        local = np.eye(4)
        local[:3, :3] = rots[i]
        local[:3, 3] = joints[i] - (joints[p] if p >= 0 else 0)
        world.append(local if p < 0 else world[p] @ local)
    posed_joints = np.array([w[:3, 3] for w in world])
    verts = np.zeros_like(v)
    for i, w in enumerate(world):
        a = w.copy()
        a[:3, 3] -= w[:3, :3] @ joints[i]
        verts += arrays.weights[:, i : i + 1] * (v @ a[:3, :3].T + a[:3, 3])
    shift = transl - joints[0]
    return posed_joints + shift, verts + shift


def random_model(tmp_path, posedirs="random", n_v=60, seed=0):
    rng = np.random.default_rng(seed)
    w = rng.random((n_v, 24)) ** 4
    w /= w.sum(1, keepdims=True)
    reg = rng.random((24, n_v))
    reg /= reg.sum(1, keepdims=True)
    pd = {"random": rng.normal(size=(n_v, 3, 207)) * 1e-3, "zero": np.zeros((n_v, 3, 207)), "none": None}[posedirs]
    path = tmp_path / f"random_{posedirs}.npz"
    write_body_npz(
        path, v_template=rng.normal(size=(n_v, 3)) * 0.3 + [0, 0.4, 0], shapedirs=rng.normal(size=(n_v, 3, 10)) * 0.01,
        J_regressor=reg, weights=w, parents=SMPL_PARENTS, faces=rng.integers(0, n_v, (40, 3)), posedirs=pd, dtype=np.float64,
    )
    return path


def test_matches_naive_reference_with_posedirs(tmp_path):
    """Vectorised forward (float64) = textbook SMPL to 1e-12 m, posedirs included, non-zero pelvis."""
    model = BodyModel.load(random_model(tmp_path), vertex_dtype=np.float64)
    assert model.has_posedirs
    rng = np.random.default_rng(1)
    pose, betas, transl = rng.normal(size=(3, 72)), rng.normal(size=(3, 10)), rng.normal(size=(3, 3))
    out = model.forward(pose, betas, transl, vertices=True)
    for b in range(3):
        j, v = naive_smpl(model.arrays, pose[b], betas[b], transl[b])
        assert np.abs(out["joints"][b] - j).max() < 1e-12
        assert np.abs(out["vertices"][b] - v).max() < 1e-12


@pytest.mark.parametrize("kind", ["none", "zero"])
def test_posedirs_missing_or_all_zero_is_none(tmp_path, kind):
    """A file without posedirs, or with all-zero posedirs, loads with has_posedirs False
    and gives the same bodies (no 207-wide product is done)."""
    model = BodyModel.load(random_model(tmp_path, posedirs=kind), vertex_dtype=np.float64)
    assert not model.has_posedirs and model.arrays.posedirs is None
    pose = np.random.default_rng(2).normal(size=72)
    j, v = naive_smpl(model.arrays, pose, np.zeros(10), np.zeros(3))
    out = model.forward(pose, None, None, vertices=True)
    assert np.abs(out["vertices"][0] - v).max() < 1e-12


def test_shipped_files_match_their_provenance_hashes():
    """The committed .npz files are the ones PROVENANCE.json describes (SHA-256, sizes)."""
    manifest = json.loads((shipped_model_path("full").parent / "PROVENANCE.json").read_text())
    for name in ("full", "lite"):
        path = shipped_model_path(name)
        entry = manifest["files"][path.name]
        assert hashlib.sha256(path.read_bytes()).hexdigest() == entry["sha256"] == BodyModel.load(name).sha256
        assert path.stat().st_size == entry["bytes"] < 3_000_000
    assert (shipped_model_path("full").parent / "LICENSE-anny.txt").stat().st_size > 1000


def test_shipped_models_shape_and_frame():
    """24 joints, 10 betas, no posedirs; rest pelvis at the origin (< 2 mm; measured 6 µm); Y up: head above feet;
    T-pose: left wrist at +x; beta 0 + is taller; both levels of detail agree on joints."""
    full, lite = BodyModel.load("full"), BodyModel.load("lite")
    assert (full.num_vertices, lite.num_vertices) == (13348, 1229)
    for m in (full, lite):
        assert (m.num_joints, m.num_betas, m.has_posedirs) == (24, 10, False)
        rest = m._j_template
        assert np.abs(rest[0]).max() < 2e-3
        assert rest[15, 1] > 0.5 > -0.7 > rest[7, 1]
        assert rest[20, 0] > 0.5 and rest[21, 0] < -0.5
        assert m.arrays.provenance["conventions"]["axes"].startswith("SMPL canonical: +Y up, facing +Z")
    betas = np.zeros(10)
    betas[0] = 1.0
    tall = full.forward(np.zeros(72), betas, None)["joints"][0]
    base = full.forward(np.zeros(72), None, None)["joints"][0]
    assert tall[15, 1] - tall[7, 1] > base[15, 1] - base[7, 1] + 0.02
    rng = np.random.default_rng(5)
    b = rng.normal(size=(20, 10))
    p = rng.normal(size=(20, 72)) * 0.3
    diff = np.linalg.norm(full.forward(p, b, None)["joints"] - lite.forward(p, b, None)["joints"], axis=-1)
    assert diff.max() < 0.01


def test_pelvis_is_transl_and_upright_convention(lite):
    """transl_m is where joint 0 lands, whatever the betas (computed, not assumed 0).
    Global orientation +90° about x stands the canonical body up in the Z-up carpet frame,
    facing −y, its left toward +x."""
    rng = np.random.default_rng(7)
    transl = rng.normal(size=(4, 3))
    out = lite.forward(np.tile([np.pi / 2, 0, 0] + [0] * 69, (4, 1)), np.clip(rng.normal(size=(4, 10)) * 2, -5, 5), transl, vertices=True)
    assert np.abs(out["joints"][:, 0] - transl).max() < 1e-12
    j = out["joints"][0] - transl[0]
    assert j[15, 2] > 0.4 and j[7, 2] < -0.6  # head up, ankles down (z)
    assert j[20, 0] > 0.5  # left wrist toward +x
    nose_side = out["vertices"][0][:, 1].min() - transl[0, 1]
    assert nose_side < -0.08  # the front of the body is toward −y


def test_joints_only_never_touches_vertices(lite, monkeypatch):
    """vertices=False must not call the shape-blend or skinning code (cheap path) and must
    give the same joints as the mesh path."""
    rng = np.random.default_rng(8)
    pose, betas = rng.normal(size=(2, 72)), rng.normal(size=(2, 10))
    with_mesh = lite.forward(pose, betas, None, vertices=True)

    def boom(*a, **k):
        raise AssertionError("vertex code called on the joints-only path")

    monkeypatch.setattr(lbs, "skin", boom)
    monkeypatch.setattr(lbs, "shape_vertices", boom)
    joints = lite.forward(pose, betas, None)
    assert set(joints) == {"joints"}
    assert np.array_equal(joints["joints"], with_mesh["joints"])


def test_batching_and_input_shapes(lite):
    """(72,), (24,3), (B,72), (B,24,3) poses; batch-1 arguments broadcast; rows independent."""
    rng = np.random.default_rng(9)
    pose = rng.normal(size=(3, 72))
    betas = rng.normal(size=(3, 10))
    batch = lite.forward(pose, betas, np.zeros(3))["joints"]
    for b in range(3):
        one = lite.forward(pose[b].reshape(24, 3), betas[b, :10], None)["joints"]
        assert np.abs(one[0] - batch[b]).max() < 1e-13
    short = lite.forward(pose[0], betas[0, :4], None)["joints"]
    padded = np.concatenate([betas[0, :4], np.zeros(6)])
    assert np.array_equal(short, lite.forward(pose[0], padded, None)["joints"])
    with pytest.raises(ValueError, match="pose_aa has shape"):
        lite.forward(np.zeros(70))
    with pytest.raises(ValueError, match="batch sizes differ"):
        lite.forward(np.zeros((2, 72)), np.zeros((3, 10)))
    with pytest.raises(ValueError, match="betas has shape"):
        lite.forward(np.zeros(72), np.zeros(11))


@pytest.mark.parametrize("bad", [np.nan, np.inf, -np.inf])
@pytest.mark.parametrize("arg", ["pose_aa", "betas", "transl_m"])
def test_nonfinite_input_raises_naming_the_argument(lite, bad, arg):
    """One NaN/Inf anywhere → ValueError naming the argument (one NaN would make every
    vertex NaN through the skinning product)."""
    kwargs = {"pose_aa": np.zeros(72), "betas": np.zeros(10), "transl_m": np.zeros(3)}
    kwargs[arg] = kwargs[arg].copy()
    kwargs[arg][1] = bad
    with pytest.raises(ValueError, match=arg):
        lite.forward(**kwargs, vertices=True)


def test_nonfinite_zeroed_when_asked(lite):
    """nonfinite='zero' replaces non-finite values by 0 with a BodyModelWarning; the result
    equals the call with those zeros and is finite everywhere."""
    pose = np.zeros(72)
    pose[5] = np.nan
    betas = np.ones(10)
    betas[0] = np.inf
    with pytest.warns(BodyModelWarning, match="replaced by 0"):
        out = lite.forward(pose, betas, None, vertices=True, nonfinite="zero")
    ref_betas = betas.copy()
    ref_betas[0] = 0
    ref = lite.forward(np.zeros(72), ref_betas, None, vertices=True)
    assert np.isfinite(out["vertices"]).all()
    assert np.array_equal(out["joints"], ref["joints"])


def test_betas_within_five_pass_unchanged(lite):
    """|β| = 5 exactly is inside the limit: no warning, no change."""
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        a = lite.forward(np.zeros(72), np.full(10, 5.0), None)["joints"]
        b = lite.forward(np.zeros(72), np.full(10, -5.0), None)["joints"]
    assert not np.allclose(a, b)


@pytest.mark.parametrize("value", [100.0, -100.0, 5.5])
def test_betas_beyond_limit_clamped_with_warning(lite, value):
    """β beyond ±5 (e.g. ±100, which gives inverted 8–12 m bodies) is clamped to ±5 with a
    BodyModelWarning; the body is then the ±5 body, of human size."""
    betas = np.zeros(10)
    betas[0] = value
    with pytest.warns(BodyModelWarning, match="clamped"):
        out = lite.forward(np.zeros(72), betas, None, vertices=True)
    betas[0] = np.sign(value) * 5
    ref = lite.forward(np.zeros(72), betas, None, vertices=True)
    assert np.array_equal(out["vertices"], ref["vertices"])
    height = np.ptp(out["vertices"][0][:, 1])
    assert 1.0 < height < 2.4


def test_float32_vs_float64_drift(lite, lite64):
    """The float32 vertex path (float64 rotations and chain) is within 2 µm of float64 at
    carpet scale (bodies 3 m from the origin, random poses and shapes); joints are identical."""
    rng = np.random.default_rng(11)
    pose, betas = rng.normal(size=(8, 72)), np.clip(rng.normal(size=(8, 10)) * 2, -5, 5)
    transl = rng.uniform(0, 3, size=(8, 3))
    a = lite.forward(pose, betas, transl, vertices=True)
    b = lite64.forward(pose, betas, transl, vertices=True)
    assert a["vertices"].dtype == np.float32 and b["vertices"].dtype == np.float64
    assert np.array_equal(a["joints"], b["joints"])
    assert np.abs(a["vertices"] - b["vertices"]).max() < 2e-6


def test_hard_pose_angles_give_finite_bodies(lite):
    """Joint angles 0, 1e-8, π, π−1e-9, 2π+0.3 and 1e6 rad give finite bodies; 2π+x and x
    give the same body."""
    angles = [0.0, 1e-8, np.pi, np.pi - 1e-9, 2 * np.pi + 0.3, 1e6]
    pose = np.zeros((len(angles), 24, 3))
    for k, a in enumerate(angles):
        pose[k, 1:] = a * np.array([0.0, 0.6, 0.8])
    out = lite.forward(pose, None, None, vertices=True)
    assert np.isfinite(out["vertices"]).all()
    wrapped = pose[4:5].copy()
    wrapped[0, 1:] = 0.3 * np.array([0.0, 0.6, 0.8])
    assert np.abs(lite.forward(wrapped)["joints"][0] - out["joints"][4]).max() < 1e-12


def test_edge_body_and_render_cli_do_not_import_torch():
    """The runtime side (edge.body, the render CLI module) imports without torch or anny."""
    code = (
        "import sys, edge.body, edge.body.render, edge.body.poses, edge.cli.render;"
        "edge.body.BodyModel.load('lite').forward([0]*72, vertices=True);"
        "bad=[m for m in ('torch','anny','matplotlib') if m in sys.modules]; print(bad); sys.exit(bool(bad))"
    )
    res = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert res.returncode == 0, res.stdout + res.stderr

"""Loading SMPL-layout files: official-style pickles without chumpy, npz, and bad files."""

import io
import pickle
import sys
import types
import zipfile

import numpy as np
import pytest
import scipy.sparse

from edge.body import SMPL_PARENTS, BodyModel, BodyModelFileError, read_body_file, write_body_npz

N_V = 40


def _arrays(seed=0):
    rng = np.random.default_rng(seed)
    w = rng.random((N_V, 24))
    reg = rng.random((24, N_V)) * (rng.random((24, N_V)) > 0.7)
    reg[:, 0] += 1e-3
    return {
        "v_template": rng.normal(size=(N_V, 3)),
        "shapedirs": rng.normal(size=(N_V, 3, 10)) * 0.01,
        "posedirs": rng.normal(size=(N_V, 3, 207)) * 1e-3,
        "J_regressor": reg / reg.sum(1, keepdims=True),
        "weights": w / w.sum(1, keepdims=True),
        "kintree_table": np.stack([np.array([4294967295] + list(SMPL_PARENTS[1:]), dtype=np.int64), np.arange(24)]),
        "f": rng.integers(0, N_V, (30, 3)).astype(np.uint32),
    }


@pytest.fixture
def fake_chumpy(monkeypatch):
    """A stand-in 'chumpy.ch.Ch' that pickles like chumpy's (its __dict__ minus caches,
    with 'x' the array), so the test builds an official-style file without chumpy."""
    ch_mod = types.ModuleType("chumpy.ch")

    class Ch:
        def __init__(self, x):
            self.x = np.asarray(x, dtype=np.float64)
            self._dirty_vars = set()
            self._itr = None
            self._depends_on_deps = {}
            self._make_dense = False
            self._make_sparse = False

        def __getstate__(self):
            return dict(self.__dict__)

    Ch.__module__ = "chumpy.ch"
    Ch.__qualname__ = "Ch"
    ch_mod.Ch = Ch
    root = types.ModuleType("chumpy")
    root.ch = ch_mod
    monkeypatch.setitem(sys.modules, "chumpy", root)
    monkeypatch.setitem(sys.modules, "chumpy.ch", ch_mod)
    return Ch


def _official_pickle(path, arrays, Ch, protocol=2):
    obj = dict(arrays)
    for key in ("v_template", "shapedirs", "posedirs"):
        obj[key] = Ch(arrays[key])
    obj["J_regressor"] = scipy.sparse.csc_matrix(arrays["J_regressor"])
    obj["bs_style"] = "lbs"
    obj["bs_type"] = "lrotmin"
    obj["J"] = arrays["J_regressor"] @ arrays["v_template"]
    path.write_bytes(pickle.dumps(obj, protocol=protocol))


@pytest.mark.parametrize("protocol", [0, 2])
def test_official_style_pickle_without_chumpy(tmp_path, fake_chumpy, protocol, monkeypatch):
    """A pickle with chumpy arrays, a scipy sparse J_regressor and uint32 root parent loads
    (chumpy absent at load time) into the same arrays, and evaluates like the npz."""
    arrays = _arrays()
    pkl = tmp_path / "basicModel_neutral_lbs_10_207_0_v1.0.0.pkl"
    _official_pickle(pkl, arrays, fake_chumpy, protocol)
    monkeypatch.delitem(sys.modules, "chumpy")
    monkeypatch.delitem(sys.modules, "chumpy.ch")
    loaded = read_body_file(pkl)
    assert np.array_equal(loaded.v_template, arrays["v_template"])
    assert np.array_equal(loaded.shapedirs, arrays["shapedirs"])
    assert np.array_equal(loaded.posedirs, arrays["posedirs"])
    assert np.allclose(loaded.J_regressor, arrays["J_regressor"], rtol=0, atol=1e-15)
    assert list(loaded.parents) == list(SMPL_PARENTS)
    npz = tmp_path / "same.npz"
    write_body_npz(npz, v_template=arrays["v_template"], shapedirs=arrays["shapedirs"], J_regressor=arrays["J_regressor"],
                   weights=arrays["weights"], parents=SMPL_PARENTS, faces=arrays["f"], posedirs=arrays["posedirs"], dtype=np.float64)
    pose = np.random.default_rng(1).normal(size=72)
    a = BodyModel.load(pkl, vertex_dtype=np.float64).forward(pose, np.ones(10), [1, 2, 3], vertices=True)
    b = BodyModel.load(npz, vertex_dtype=np.float64).forward(pose, np.ones(10), [1, 2, 3], vertices=True)
    assert np.abs(a["vertices"] - b["vertices"]).max() < 1e-12


def test_official_npz_with_extra_keys(tmp_path):
    """An official-SMPL-layout .npz (extra keys, dense regressor, uint32 parents) loads."""
    arrays = _arrays()
    path = tmp_path / "SMPL_NEUTRAL.npz"
    np.savez(path, **arrays, J=np.zeros((24, 3)), bs_style=np.array("lbs"))
    model = BodyModel.load(path)
    assert model.has_posedirs and model.num_vertices == N_V


def test_pickle_refuses_code(tmp_path):
    """A pickle that would call a function (here os.system) is refused, not run."""

    class Evil:
        def __reduce__(self):
            import os
            return (os.system, ("echo pwned",))

    path = tmp_path / "evil.pkl"
    path.write_bytes(pickle.dumps({"v_template": Evil()}, protocol=2))
    with pytest.raises(BodyModelFileError, match="refusing to load"):
        read_body_file(path)


def test_chumpy_expression_is_a_clear_error(tmp_path, fake_chumpy, monkeypatch):
    """A chumpy object without a plain 'x' (an expression) → error naming the key."""
    arrays = _arrays()
    obj = dict(arrays)
    expr = fake_chumpy(arrays["v_template"])
    del expr.x
    obj["v_template"] = expr
    path = tmp_path / "expr.pkl"
    path.write_bytes(pickle.dumps(obj, protocol=2))
    monkeypatch.delitem(sys.modules, "chumpy.ch")
    with pytest.raises(BodyModelFileError, match="'v_template' is a chumpy expression"):
        read_body_file(path)


@pytest.mark.parametrize(
    "key,value,message",
    [
        ("shapedirs", np.zeros((N_V, 10)), r"'shapedirs' has shape \(40, 10\), expected \(40, 3, any\)"),
        ("J_regressor", np.zeros((24, N_V + 1)), r"'J_regressor' has shape \(24, 41\), expected \(24, 40\)"),
        ("weights", np.zeros((N_V, 23)), r"'weights' has shape \(40, 23\)"),
        ("posedirs", np.zeros((N_V, 3, 206)), r"'posedirs' has shape \(40, 3, 206\)"),
        ("f", np.full((3, 3), N_V), r"'f' indexes vertex 40"),
        ("v_template", np.full((N_V, 3), np.nan), r"'v_template' contains NaN"),
        ("kintree_table", np.zeros((2, 24), dtype=np.int64), r"'kintree_table'"),
        ("v_template", np.array(["a"] * N_V), r"'v_template' has dtype"),
    ],
)
def test_wrong_shaped_key_names_the_key(tmp_path, key, value, message):
    """Each malformed key → BodyModelFileError naming the file, the key and what was expected."""
    arrays = _arrays()
    arrays[key] = value
    path = tmp_path / "bad.npz"
    np.savez(path, **arrays)
    with pytest.raises(BodyModelFileError, match=message) as err:
        BodyModel.load(path)
    assert str(path) in str(err.value)


def test_missing_key_is_named(tmp_path):
    arrays = _arrays()
    del arrays["weights"]
    path = tmp_path / "missing.npz"
    np.savez(path, **arrays)
    with pytest.raises(BodyModelFileError, match="missing key 'weights'"):
        BodyModel.load(path)


@pytest.mark.parametrize("keep", [0.1, 0.5, 0.9, 0.999])
def test_truncated_npz_is_a_clear_error(tmp_path, keep):
    """A file cut short (download interrupted) → BodyModelFileError saying truncated/corrupt."""
    path = tmp_path / "model.npz"
    write_body_npz(path, v_template=np.zeros((N_V, 3)), shapedirs=np.zeros((N_V, 3, 10)), J_regressor=np.ones((24, N_V)) / N_V,
                   weights=np.ones((N_V, 24)) / 24, parents=SMPL_PARENTS, faces=np.zeros((1, 3), int))
    data = path.read_bytes()
    path.write_bytes(data[: int(len(data) * keep)])
    with pytest.raises(BodyModelFileError, match="truncated or corrupt"):
        BodyModel.load(path)


def test_truncated_member_names_the_key(tmp_path):
    """A zip whose 'shapedirs' member holds fewer bytes than its header says → error naming
    'shapedirs' (the archive itself is intact)."""
    arrays = _arrays()
    buf = io.BytesIO()
    np.lib.format.write_array(buf, arrays["shapedirs"])
    path = tmp_path / "member.npz"
    with zipfile.ZipFile(path, "w") as zf:
        for key, value in arrays.items():
            member = io.BytesIO()
            np.lib.format.write_array(member, value)
            raw = member.getvalue()
            zf.writestr(f"{key}.npy", raw[: len(raw) // 2] if key == "shapedirs" else raw)
    with pytest.raises(BodyModelFileError, match="key 'shapedirs' is unreadable"):
        BodyModel.load(path)


def test_truncated_pickle_and_garbage(tmp_path, fake_chumpy):
    """A cut pickle and a non-model file → BodyModelFileError, never a raw traceback."""
    pkl = tmp_path / "m.pkl"
    _official_pickle(pkl, _arrays(), fake_chumpy)
    pkl.write_bytes(pkl.read_bytes()[:5000])
    with pytest.raises(BodyModelFileError, match="truncated or corrupt"):
        read_body_file(pkl)
    junk = tmp_path / "junk.bin"
    junk.write_bytes(b"hello world")
    with pytest.raises(BodyModelFileError, match="neither an .npz nor a pickle"):
        read_body_file(junk)
    with pytest.raises(BodyModelFileError, match="cannot read"):
        read_body_file(tmp_path / "absent.npz")


def test_unknown_shipped_name():
    with pytest.raises(ValueError, match="unknown shipped body model"):
        from edge.body import shipped_model_path
        shipped_model_path("medium")

"""Reading and writing body-model files in SMPL's layout, without chumpy.

Accepted files (the format is sniffed from the first bytes, not the suffix):

* ``.npz`` (a zip of ``.npy``): ours, or an official SMPL file converted to npz.
  Read with ``allow_pickle=False``.
* ``.pkl``: the official SMPL pickles (Python 2, latin-1). ``v_template``,
  ``shapedirs`` and ``posedirs`` are chumpy ``Ch`` objects and ``J_regressor`` is a
  scipy sparse matrix. A restricted unpickler maps chumpy classes to a stub that keeps
  the pickled state (whose ``x`` is the plain array) and refuses every class that is
  not a numpy array, a chumpy array or a scipy sparse matrix: loading never imports
  chumpy and never runs code from the file.

Keys (B batch, V vertices, J joints, NB betas):

| key | shape | notes |
|---|---|---|
| ``v_template`` | (V,3) | metres |
| ``shapedirs`` | (V,3,NB) | |
| ``posedirs`` | (V,3,9·(J−1)) | optional; all zero → treated as absent |
| ``J_regressor`` | (J,V) | dense or scipy sparse |
| ``weights`` | (V,J) | skinning weights |
| ``kintree_table`` | (2,J) | row 0: parents; root's is −1 or 2³²−1 |
| ``f`` | (F,3) | triangles, vertex indices |

Our files add ``provenance`` (a JSON string), ``license`` and ``joint_names``.
Every problem is a ``BodyModelFileError`` that names the file and the key.
"""

from __future__ import annotations

import hashlib
import io
import json
import pickle
import zipfile
import zlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

REQUIRED_KEYS = ("v_template", "shapedirs", "J_regressor", "weights", "kintree_table", "f")
OPTIONAL_KEYS = ("posedirs",)


class BodyModelFileError(ValueError):
    """A body-model file that cannot be used: unreadable, missing or malformed key."""


@dataclass
class BodyArrays:
    """The validated contents of a body-model file (float64 arrays, int64 indices)."""

    v_template: np.ndarray  # (V,3)
    shapedirs: np.ndarray  # (V,3,NB)
    posedirs: np.ndarray | None  # (V,3,9(J-1)) or None
    J_regressor: np.ndarray  # (J,V)
    weights: np.ndarray  # (V,J)
    parents: np.ndarray  # (J,), parents[0] == -1
    faces: np.ndarray  # (F,3)
    provenance: dict = field(default_factory=dict)
    license: str = ""
    joint_names: list[str] = field(default_factory=list)
    source: str = ""
    sha256: str = ""

    @property
    def num_vertices(self) -> int:
        return self.v_template.shape[0]

    @property
    def num_joints(self) -> int:
        return self.J_regressor.shape[0]

    @property
    def num_betas(self) -> int:
        return self.shapedirs.shape[2]


# --------------------------------------------------------------------------- pickles


class _ChumpyStub:
    """Stands in for any chumpy class while unpickling; keeps the pickled state."""

    chumpy_class = "chumpy.Ch"

    def __setstate__(self, state):
        self.state = state


class _SparseStub:
    """Stands in for a scipy sparse matrix while unpickling; keeps the pickled state."""

    sparse_class = "csc_matrix"

    def __setstate__(self, state):
        self.state = state


def _reconstructor(cls, base, state):
    """copyreg._reconstructor for the stub classes only (Python 2 pickles use it)."""
    if not (isinstance(cls, type) and issubclass(cls, (_ChumpyStub, _SparseStub))):
        raise pickle.UnpicklingError(f"refusing to reconstruct {cls!r}")
    return cls.__new__(cls)


_NUMPY_NAMES = {"_reconstruct", "ndarray", "dtype", "scalar", "_frombuffer"}
_SPARSE_NAMES = {"csc_matrix", "csr_matrix", "coo_matrix"}


class _SmplUnpickler(pickle.Unpickler):
    def find_class(self, module: str, name: str):
        if module.split(".")[0] == "chumpy":
            return type(name, (_ChumpyStub,), {"chumpy_class": f"{module}.{name}"})
        if module.startswith("scipy.sparse") and name in _SPARSE_NAMES:
            return type(name, (_SparseStub,), {"sparse_class": name})
        if module in ("copy_reg", "copyreg") and name == "_reconstructor":
            return _reconstructor
        if module == "_codecs" and name == "encode":  # bytes in protocol <= 2 pickles
            return super().find_class(module, name)
        if module in ("__builtin__", "builtins") and name in ("object", "set", "frozenset", "slice"):
            return super().find_class("builtins", name)
        if module.split(".")[0] == "numpy" and name in _NUMPY_NAMES:
            return super().find_class(module, name)
        raise pickle.UnpicklingError(f"refusing to load {module}.{name} (not an array type)")


def _plain(value, key: str, where: str):
    """A pickled value (ndarray, chumpy stub, sparse stub, list) → ndarray."""
    if isinstance(value, _ChumpyStub):
        state: Any = getattr(value, "state", None)
        if not isinstance(state, dict) or "x" not in state:
            raise BodyModelFileError(
                f"{where}: key {key!r} is a chumpy expression ({value.chumpy_class}), not a plain "
                "chumpy array: it cannot be read without chumpy; re-save it as an array"
            )
        return _plain(state["x"], key, where)
    if isinstance(value, _SparseStub):
        state = getattr(value, "state", None) or {}
        try:
            shape = tuple(state.get("_shape", state.get("shape")))
            data = np.asarray(state["data"])
            if value.sparse_class == "coo_matrix":
                dense = np.zeros(shape)
                np.add.at(dense, (np.asarray(state["row"]), np.asarray(state["col"])), data)
                return dense
            indices, indptr = np.asarray(state["indices"]), np.asarray(state["indptr"])
        except (KeyError, TypeError) as exc:
            raise BodyModelFileError(f"{where}: key {key!r}: unreadable sparse matrix ({exc})") from None
        dense = np.zeros(shape)
        major = shape[1] if value.sparse_class == "csc_matrix" else shape[0]
        if len(indptr) != major + 1 or indptr[-1] > len(data) or len(indices) < indptr[-1]:
            raise BodyModelFileError(f"{where}: key {key!r}: inconsistent sparse matrix")
        counts = np.diff(indptr)
        outer = np.repeat(np.arange(major), counts)
        inner = indices[: indptr[-1]]
        if value.sparse_class == "csc_matrix":
            np.add.at(dense, (inner, outer), data[: indptr[-1]])
        else:
            np.add.at(dense, (outer, inner), data[: indptr[-1]])
        return dense
    if isinstance(value, (np.ndarray, list, tuple, int, float, np.generic)):
        return np.asarray(value)
    raise BodyModelFileError(f"{where}: key {key!r} holds a {type(value).__name__}, not an array")


def _read_pickle(data: bytes, where: str) -> dict:
    try:
        obj = _SmplUnpickler(io.BytesIO(data), encoding="latin1").load()
    except (pickle.UnpicklingError, EOFError, ValueError, TypeError, AttributeError, IndexError) as exc:
        raise BodyModelFileError(f"{where}: not a readable SMPL pickle (truncated or corrupt?): {exc}") from None
    if not isinstance(obj, dict):
        raise BodyModelFileError(f"{where}: the pickle holds a {type(obj).__name__}, expected a dict of arrays")
    out = {}
    for key in REQUIRED_KEYS + OPTIONAL_KEYS:
        if key in obj:
            out[key] = _plain(obj[key], key, where)
    return out


# --------------------------------------------------------------------------- npz


def _read_npz(data: bytes, where: str) -> dict:
    try:
        archive = np.load(io.BytesIO(data), allow_pickle=False)
    except (zipfile.BadZipFile, ValueError, OSError, EOFError) as exc:
        raise BodyModelFileError(f"{where}: not a readable .npz (truncated or corrupt?): {exc}") from None
    out = {}
    with archive:
        for key in REQUIRED_KEYS + OPTIONAL_KEYS + ("provenance", "license", "joint_names"):
            if key not in archive.files:
                continue
            try:
                out[key] = archive[key]
            except (zipfile.BadZipFile, ValueError, OSError, EOFError, zlib.error) as exc:
                raise BodyModelFileError(f"{where}: key {key!r} is unreadable (truncated or corrupt?): {exc}") from None
    return out


# --------------------------------------------------------------------------- validation


def _float_array(raw: dict, key: str, shape: tuple, where: str) -> np.ndarray:
    """raw[key] as float64 with the given shape (None = any size); clear error otherwise."""
    value = raw[key]
    if value.dtype.kind not in "fiub":
        raise BodyModelFileError(f"{where}: key {key!r} has dtype {value.dtype}, expected numbers")
    if value.ndim != len(shape) or any(s is not None and s != v for s, v in zip(shape, value.shape)):
        expected = "(" + ", ".join("any" if s is None else str(s) for s in shape) + ")"
        raise BodyModelFileError(f"{where}: key {key!r} has shape {value.shape}, expected {expected}")
    value = value.astype(np.float64)
    if not np.all(np.isfinite(value)):
        raise BodyModelFileError(f"{where}: key {key!r} contains NaN or Inf")
    return value


def validate(raw: dict, where: str) -> BodyArrays:
    """Check shapes and consistency of the raw arrays of a file; see the module table."""
    for key in REQUIRED_KEYS:
        if key not in raw:
            raise BodyModelFileError(f"{where}: missing key {key!r} (a body-model file needs {', '.join(REQUIRED_KEYS)})")
    v_template = _float_array(raw, "v_template", (None, 3), where)
    n_v = v_template.shape[0]
    kintree = raw["kintree_table"]
    if kintree.ndim != 2 or kintree.shape[0] != 2 or kintree.dtype.kind not in "iu":
        raise BodyModelFileError(f"{where}: key 'kintree_table' has shape {kintree.shape} dtype {kintree.dtype}, expected (2, J) integers")
    n_j = kintree.shape[1]
    parents = kintree[0].astype(np.int64)
    if not (parents[0] < 0 or parents[0] >= n_j):
        raise BodyModelFileError(f"{where}: key 'kintree_table': joint 0 must be the root (its parent is {parents[0]})")
    parents[0] = -1
    bad = [i for i in range(1, n_j) if not 0 <= parents[i] < i]
    if bad:
        raise BodyModelFileError(
            f"{where}: key 'kintree_table': joints must follow their parents, but joint {bad[0]} has parent {parents[bad[0]]}"
        )
    shapedirs = _float_array(raw, "shapedirs", (n_v, 3, None), where)
    j_regressor = _float_array(raw, "J_regressor", (n_j, n_v), where)
    weights = _float_array(raw, "weights", (n_v, n_j), where)
    posedirs = None
    if "posedirs" in raw:
        posedirs = _float_array(raw, "posedirs", (n_v, 3, 9 * (n_j - 1)), where)
        if not np.any(posedirs):
            posedirs = None
    faces = raw["f"]
    if faces.ndim != 2 or faces.shape[1] != 3 or faces.dtype.kind not in "iu":
        raise BodyModelFileError(f"{where}: key 'f' has shape {faces.shape} dtype {faces.dtype}, expected (F, 3) integers")
    faces = faces.astype(np.int64)
    if faces.size and (faces.min() < 0 or faces.max() >= n_v):
        raise BodyModelFileError(f"{where}: key 'f' indexes vertex {faces.max()} but there are {n_v}")
    provenance: dict = {}
    if "provenance" in raw:
        try:
            provenance = json.loads(str(raw["provenance"]))
        except json.JSONDecodeError as exc:
            raise BodyModelFileError(f"{where}: key 'provenance' is not JSON: {exc}") from None
    joint_names = [str(n) for n in raw["joint_names"]] if "joint_names" in raw else []
    if joint_names and len(joint_names) != n_j:
        raise BodyModelFileError(f"{where}: key 'joint_names' has {len(joint_names)} names for {n_j} joints")
    return BodyArrays(
        v_template=v_template,
        shapedirs=shapedirs,
        posedirs=posedirs,
        J_regressor=j_regressor,
        weights=weights,
        parents=parents,
        faces=faces,
        provenance=provenance,
        license=str(raw["license"]) if "license" in raw else "",
        joint_names=joint_names,
    )


def read_body_file(path: str | Path) -> BodyArrays:
    """Read and validate an SMPL-layout file (.npz or official .pkl), see module doc."""
    path = Path(path)
    where = str(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise BodyModelFileError(f"{where}: cannot read: {exc.strerror or exc}") from None
    if data[:2] == b"PK":
        raw = _read_npz(data, where)
    elif data[:1] == b"\x80" or data[:1] in (b"(", b"}"):
        raw = _read_pickle(data, where)
    else:
        raise BodyModelFileError(f"{where}: neither an .npz nor a pickle (first bytes {data[:4]!r})")
    arrays = validate(raw, where)
    arrays.source = where
    arrays.sha256 = hashlib.sha256(data).hexdigest()
    return arrays


def write_body_npz(
    path: str | Path,
    *,
    v_template: np.ndarray,
    shapedirs: np.ndarray,
    J_regressor: np.ndarray,
    weights: np.ndarray,
    parents: np.ndarray,
    faces: np.ndarray,
    posedirs: np.ndarray | None = None,
    provenance: dict | None = None,
    license: str = "",
    joint_names: list[str] | None = None,
    dtype=np.float32,
) -> str:
    """Write an SMPL-layout .npz (compressed, deterministic bytes); returns its SHA-256.

    Arrays are stored in ``dtype`` (float32 keeps files small; the loader computes in
    float64). ``kintree_table`` row 0 is ``parents`` with −1 at the root, row 1 the
    joint index, as in SMPL. The zip members carry a fixed timestamp so the same
    arrays always give the same bytes.
    """
    parents = np.asarray(parents, dtype=np.int64)
    members = {
        "v_template": np.asarray(v_template, dtype),
        "shapedirs": np.asarray(shapedirs, dtype),
        "J_regressor": np.asarray(J_regressor, dtype),
        "weights": np.asarray(weights, dtype),
        "kintree_table": np.stack([parents, np.arange(len(parents))]).astype(np.int64),
        "f": np.asarray(faces, np.int32),
    }
    if posedirs is not None:
        members["posedirs"] = np.asarray(posedirs, dtype)
    if provenance is not None:
        members["provenance"] = np.array(json.dumps(provenance, sort_keys=True, indent=1))
    if license:
        members["license"] = np.array(license)
    if joint_names:
        members["joint_names"] = np.array(list(joint_names))
    buf = io.BytesIO()
    with zipfile.ZipFile(buf, "w", compression=zipfile.ZIP_DEFLATED, compresslevel=9) as zf:
        for key, value in members.items():
            info = zipfile.ZipInfo(f"{key}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            member = io.BytesIO()
            np.lib.format.write_array(member, value, allow_pickle=False)
            zf.writestr(info, member.getvalue())
    data = buf.getvalue()
    Path(path).write_bytes(data)
    return hashlib.sha256(data).hexdigest()

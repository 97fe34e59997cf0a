"""Load a model bundle and run it with onnxruntime (no torch: this runs on the board).

    b = ModelBundle.load("edge/models/lean-96", grid=(96, 96))
    feats = b.encode(b.normalise(pressure_kpa)[:, None])        # (B,1,H,W) → (B,F), once per frame
    out = b.head(window_feats, origin_m=cop)                    # (B,40,F) → pose_aa, betas, transl_m, …

A bundle is a folder (design.md): ``encoder.onnx``, ``head.onnx``, ``manifest.json`` and
``manifest.json.sha256`` (the manifest's own SHA-256, ``sha256sum`` format, written with it by
:func:`write_manifest`). Loading REFUSES (BundleError, one line naming the file, the expected
and the actual value) a bundle whose manifest does not match its sidecar hash, whose manifest
values are out of range (:func:`check_manifest`), which lists a file outside the bundle folder
(or a link), whose files do not match their SHA-256 in the manifest, whose grid differs from the
carpet's, whose graphs disagree with the manifest, or whose body model differs from the one it
was trained with.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import stat
from pathlib import Path
from typing import Any, Callable

import numpy as np

from cavatar_common.provenance import sha256_file  # noqa: F401  (re-exported: export and tests use it from here)
from edge.infer.normalise import NORMALISATION, center_of_pressure_m, check_finite, normalise_kpa
from edge.infer.rotations import rot6d_to_axis_angle

SCHEMA = "cavatar.bundle/1"
GRAPHS = ("encoder.onnx", "head.onnx")
HEAD_OUTPUTS = ("rot6d", "betas", "transl_rel_m", "activity_logits", "confidence")
MANIFEST = "manifest.json"
SIDECAR = "manifest.json.sha256"
MANIFEST_MAX_BYTES = 1 << 20
MAX_GRID = 512
FILE_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9._-]{0,127}$")  # a plain file name in the bundle folder
HEX64 = re.compile(r"^[0-9a-f]{64}$")


class BundleError(Exception):
    """A model bundle that is missing, tampered with, or does not fit this carpet."""


def session_options(threads: int = 1):
    """One intra-op thread by default, no spinning between frames (idle threads burn CPU otherwise)."""
    import onnxruntime as ort

    opts = ort.SessionOptions()
    opts.intra_op_num_threads = threads
    opts.inter_op_num_threads = 1
    opts.add_session_config_entry("session.intra_op.allow_spinning", "0")
    opts.log_severity_level = 3
    return opts


def write_manifest(folder: str | Path, manifest: dict[str, Any], default: Callable[[Any], Any] | None = None) -> Path:
    """Write ``manifest.json`` and its ``manifest.json.sha256`` sidecar, each atomically (the only way a
    manifest should be written: a manifest without a matching sidecar is refused at load)."""
    folder = Path(folder)
    data = (json.dumps(manifest, indent=1, default=default) + "\n").encode()
    _replace(folder / MANIFEST, data)
    _replace(folder / SIDECAR, f"{hashlib.sha256(data).hexdigest()}  {MANIFEST}\n".encode())
    return folder / MANIFEST


def seal_manifest(folder: str | Path) -> str:
    """(Re)write the sidecar for the manifest.json as it is now; its SHA-256. For a manifest edited on purpose."""
    folder = Path(folder)
    data = (folder / MANIFEST).read_bytes()
    digest = hashlib.sha256(data).hexdigest()
    _replace(folder / SIDECAR, f"{digest}  {MANIFEST}\n".encode())
    return digest


def _replace(path: Path, data: bytes) -> None:
    part = path.with_name(path.name + ".part")
    part.write_bytes(data)
    part.replace(path)


def _read_plain(path: Path, limit: int) -> bytes:
    """A regular file (not a link) of at most ``limit`` bytes; BundleError otherwise."""
    try:
        st = os.lstat(path)
    except FileNotFoundError:
        raise BundleError(f"{path}: missing") from None
    if not stat.S_ISREG(st.st_mode):
        raise BundleError(f"{path}: not a regular file (a link or a device); a bundle holds plain files only")
    if st.st_size > limit:
        raise BundleError(f"{path}: {st.st_size} bytes, more than a manifest ever holds ({limit})")
    return path.read_bytes()


def verify(path: str | Path, grid: tuple[int, int] | None = None) -> dict[str, Any]:
    """Check a bundle folder's manifest (its sidecar hash and values), file hashes and grid; return the
    manifest or raise BundleError."""
    folder = Path(path)
    mpath = folder / MANIFEST
    if not os.path.lexists(mpath):
        raise BundleError(f"{folder}: no manifest.json (not a model bundle)")
    data = _read_plain(mpath, MANIFEST_MAX_BYTES)
    if not os.path.lexists(folder / SIDECAR):
        raise BundleError(f"{folder}: no {SIDECAR} beside the manifest, so its content is unprotected; re-export the "
                          "bundle (`cavatar bundle`), reinstall the package, or after a deliberate edit run "
                          f"`python -m export.bundle --seal {folder}`")
    side = _read_plain(folder / SIDECAR, 4096).decode(errors="replace").split()
    expected = side[0].lower() if side else ""
    actual = hashlib.sha256(data).hexdigest()
    if expected != actual:
        raise BundleError(f"{mpath}: SHA-256 {actual}, {SIDECAR} expects {expected or '(nothing)'}: the manifest was "
                          "edited or damaged; re-export the bundle or reinstall the package")
    try:
        manifest = json.loads(data)
    except ValueError as exc:
        raise BundleError(f"{mpath}: unreadable manifest ({exc})") from None
    if not isinstance(manifest, dict):
        raise BundleError(f"{mpath}: the manifest is not a JSON object")
    if manifest.get("schema") != SCHEMA:
        raise BundleError(f"{mpath}: schema {manifest.get('schema')!r}, this runtime reads {SCHEMA!r}")
    check_manifest(manifest, mpath)
    files = manifest["files"]
    for name in GRAPHS:
        if name not in files:
            raise BundleError(f"{mpath}: {name} is not listed in the manifest's files")
    root = folder.resolve()
    for name, expected in files.items():
        f = folder / name
        if not os.path.lexists(f):
            raise BundleError(f"{folder}: {name} is listed in the manifest but missing")
        if f.is_symlink() or not f.is_file() or f.resolve().parent != root:
            raise BundleError(f"{folder}: {name} is a link or not a plain file in the bundle folder; refused")
        actual = sha256_file(f)
        if actual != expected:
            raise BundleError(f"{f}: SHA-256 mismatch: manifest expects {expected}, file has {actual} (tampered or corrupt)")
    bundle_grid = tuple(int(g) for g in manifest["grid"])
    if grid is not None and tuple(int(g) for g in grid) != bundle_grid:
        raise BundleError(f"{folder}: the bundle is for a {bundle_grid[0]}×{bundle_grid[1]} carpet, "
                          f"this carpet is {grid[0]}×{grid[1]}")
    return manifest


def _int_in(value: Any, lo: int, hi: int) -> bool:
    return isinstance(value, int) and not isinstance(value, bool) and lo <= value <= hi


def _float_in(value: Any, lo: float, hi: float) -> bool:
    return (isinstance(value, (int, float)) and not isinstance(value, bool) and math.isfinite(value)
            and lo < value <= hi)


def check_manifest(m: dict[str, Any], where: Path | str = MANIFEST) -> None:
    """BundleError (one line, every problem) unless the values the runtime uses are in range."""
    bad: list[str] = []

    def need(ok: bool, key: str, rule: str) -> None:
        if not ok:
            bad.append(f"{key} {json.dumps(_get(m, key))[:60]} ({rule})")

    need(isinstance(m.get("name"), str) and FILE_NAME.match(m.get("name") or "") is not None, "name",
         "letters, digits, '.', '_', '-'")
    g = m.get("grid")
    need(isinstance(g, list) and len(g) == 2 and all(_int_in(x, 1, MAX_GRID) for x in g), "grid",
         f"two integers 1..{MAX_GRID}")
    need(_float_in(m.get("pitch_m"), 0.0, 0.2), "pitch_m", "metres, 0 < pitch <= 0.2")
    need(_int_in(m.get("window"), 1, 1000), "window", "an integer 1..1000")
    need(_int_in(m.get("features"), 1, 8192), "features", "an integer 1..8192")
    norm = _get(m, "input.normalisation")
    need(isinstance(norm, dict) and norm.get("kind") == NORMALISATION["kind"], "input.normalisation.kind",
         f"{NORMALISATION['kind']!r}")
    need(_float_in(_get(m, "input.normalisation.scale_kpa"), 0.0, 1e6), "input.normalisation.scale_kpa",
         "kPa, 0 < scale <= 1e6")
    acts = m.get("activities")
    need(isinstance(acts, list) and 1 <= len(acts) <= 256 and all(isinstance(a, str) and 0 < len(a) <= 64 for a in acts),
         "activities", "1..256 names")
    files = m.get("files")
    need(isinstance(files, dict) and all(isinstance(k, str) and FILE_NAME.match(k) and k not in (MANIFEST, SIDECAR)
                                         and isinstance(v, str) and HEX64.match(v) for k, v in files.items()),
         "files", "plain file names in the bundle folder → lowercase SHA-256")
    if bad:
        raise BundleError(f"{where}: values out of range: " + "; ".join(bad) + ". Re-export the bundle (`cavatar bundle`).")


def _get(m: Any, dotted: str) -> Any:
    for key in dotted.split("."):
        m = m.get(key) if isinstance(m, dict) else None
    return m


class ModelBundle:
    """A verified bundle with its two onnxruntime sessions."""

    def __init__(self, folder: Path, manifest: dict[str, Any], threads: int = 1):
        import onnxruntime as ort

        self.folder, self.manifest = folder, manifest
        opts = session_options(threads)
        self._encoder = ort.InferenceSession(str(folder / "encoder.onnx"), opts, providers=["CPUExecutionProvider"])
        self._head = ort.InferenceSession(str(folder / "head.onnx"), opts, providers=["CPUExecutionProvider"])
        enc_in = self._encoder.get_inputs()[0]
        if [d for d in enc_in.shape[2:]] != list(self.grid):
            raise BundleError(f"{folder / 'encoder.onnx'}: input is {enc_in.shape[2:]}, the manifest's grid is {list(self.grid)}")
        head_in = self._head.get_inputs()[0]
        if list(head_in.shape[1:]) != [self.window, self.features]:
            raise BundleError(f"{folder / 'head.onnx'}: input is {head_in.shape[1:]}, "
                              f"the manifest says window {self.window}, features {self.features}")
        names = {o.name for o in self._head.get_outputs()}
        if not set(HEAD_OUTPUTS) <= names:
            raise BundleError(f"{folder / 'head.onnx'}: outputs {sorted(names)}, expected {list(HEAD_OUTPUTS)}")
        self._enc_name, self._head_name = enc_in.name, head_in.name

    @classmethod
    def load(cls, path: str | Path, grid: tuple[int, int] | None = None, threads: int = 1,
             check_body_model: bool = True) -> "ModelBundle":
        """Verify and open a bundle; ``grid`` is the carpet's (rows, cols) and must match."""
        folder = Path(path)
        manifest = verify(folder, grid)
        if check_body_model:
            check_body(manifest, folder)
        return cls(folder, manifest, threads)

    # -- properties ---------------------------------------------------------------------------
    @property
    def grid(self) -> tuple[int, int]:
        rows, cols = self.manifest["grid"]
        return int(rows), int(cols)

    @property
    def pitch_m(self) -> float:
        return float(self.manifest["pitch_m"])

    @property
    def window(self) -> int:
        return int(self.manifest["window"])

    @property
    def features(self) -> int:
        return int(self.manifest["features"])

    @property
    def activities(self) -> list[str]:
        return list(self.manifest["activities"])

    @property
    def version(self) -> str:
        """``<name>@<sha256(manifest)[:12]>`` for published records."""
        return f"{self.manifest['name']}@{sha256_file(self.folder / 'manifest.json')[:12]}"

    # -- inference -----------------------------------------------------------------------------
    def normalise(self, pressure_kpa: np.ndarray) -> np.ndarray:
        """(…,H,W) one person's kPa → model input, as the manifest says (log1p(p / 1 kPa))."""
        norm = self.manifest["input"]["normalisation"]
        if norm.get("kind") != NORMALISATION["kind"]:
            raise BundleError(f"{self.folder}: unknown input normalisation {norm!r}")
        return normalise_kpa(check_finite(pressure_kpa), float(norm["scale_kpa"]))

    def origin_m(self, pressure_kpa: np.ndarray) -> np.ndarray:
        """(…,H,W) → (…,3) the translation origin: the person's centre of pressure, z = 0."""
        cop = center_of_pressure_m(check_finite(pressure_kpa), self.pitch_m)
        return np.concatenate([cop, np.zeros(cop.shape[:-1] + (1,))], -1)

    def encode(self, frames: np.ndarray) -> np.ndarray:
        """(B,1,H,W) float32 normalised frames → (B,F) features."""
        x = np.ascontiguousarray(frames, np.float32)
        if x.ndim != 4 or x.shape[1:] != (1, *self.grid):
            raise ValueError(f"encode expects (B,1,{self.grid[0]},{self.grid[1]}), got {x.shape}")
        # The int8 encoder's QuantizeLinear maps NaN to an arbitrary code: its features would look
        # valid and be published. Refuse instead (nothing NaN is ever published).
        check_finite(x, "encode input (normalised pressure)")
        features = self._encoder.run(None, {self._enc_name: x})[0]
        _check_outputs(self.folder / "encoder.onnx", {"features": features})
        return features

    def head_outputs(self, features: np.ndarray) -> dict[str, np.ndarray]:
        """(B,T,F) features → the head graph's own outputs by name, as exported: rot6d (B,144), betas (B,10),
        transl_rel_m (B,3), activity_logits (B,12), confidence (B,1) (and any extra output the graph has).
        :meth:`head` turns them into published parameters; evaluation reads them raw."""
        w = np.ascontiguousarray(features, np.float32)
        if w.ndim != 3 or w.shape[1:] != (self.window, self.features):
            raise ValueError(f"head expects (B,{self.window},{self.features}), got {w.shape}")
        check_finite(w, "head input (window features)")
        return dict(zip([o.name for o in self._head.get_outputs()], self._head.run(None, {self._head_name: w})))

    def head(self, features: np.ndarray, origin_m: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """(B,T,F) features → pose_aa (B,72), betas (B,10), transl_m (B,3), transl_rel_m (B,3),
        activity_probs (B,12), confidence (B,).

        ``transl_m = transl_rel_m + origin_m``; ``origin_m`` (B,3) is :meth:`origin_m` of the
        window's LAST frame (the person's centre of pressure); without it, transl_m = transl_rel_m.
        """
        out = self.head_outputs(features)
        _check_outputs(self.folder / "head.onnx", {k: out[k] for k in HEAD_OUTPUTS})
        logits = out["activity_logits"].astype(np.float64)
        probs = np.exp(logits - logits.max(-1, keepdims=True))
        probs /= probs.sum(-1, keepdims=True)
        rel = out["transl_rel_m"].astype(np.float32)
        origin = np.zeros_like(rel) if origin_m is None else np.broadcast_to(np.asarray(origin_m, np.float32), rel.shape)
        return {"pose_aa": rot6d_to_axis_angle(out["rot6d"]), "betas": out["betas"].astype(np.float32),
                "transl_m": rel + origin, "transl_rel_m": rel, "activity_probs": probs.astype(np.float32),
                "confidence": out["confidence"].astype(np.float32).reshape(-1)}


def _check_outputs(graph: Path, outputs: dict[str, np.ndarray]) -> None:
    """A graph that overflowed on finite input must not publish NaN/∞ as a body: ValueError naming it."""
    bad = [k for k, v in outputs.items() if not np.isfinite(v).all()]
    if bad:
        raise ValueError(f"{graph}: output(s) {', '.join(bad)} hold NaN/∞ for a finite input; this frame is "
                         "refused (if it keeps happening the bundle is broken: re-export it)")


def check_body(manifest: dict[str, Any], folder: Path) -> None:
    """The body model the bundle was trained with must be the one this installation ships."""
    info = manifest.get("body_model") or {}
    name, expected = info.get("name"), info.get("sha256")
    if not name or not expected:
        raise BundleError(f"{folder / 'manifest.json'}: no body_model name/sha256")
    from edge.body.model import SHIPPED_MODELS, shipped_model_path

    if name not in SHIPPED_MODELS:
        return  # a user's own body file: the runtime checks it when it loads one
    actual = sha256_file(shipped_model_path(name))
    if actual != expected:
        raise BundleError(f"{folder}: body model {name!r} ({info.get('file')}) has SHA-256 {actual}, "
                          f"the bundle was trained with {expected}")

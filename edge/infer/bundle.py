"""Load a model bundle and run it with onnxruntime (no torch: this runs on the board).

    b = ModelBundle.load("edge/models/lean-96", grid=(96, 96))
    feats = b.encode(b.normalise(pressure_kpa)[:, None])        # (B,1,H,W) → (B,F), once per frame
    out = b.head(window_feats, origin_m=cop)                    # (B,40,F) → pose_aa, betas, transl_m, …

A bundle is a folder (design.md): ``encoder.onnx``, ``head.onnx``, ``manifest.json``. Loading
REFUSES (BundleError, naming the file, the expected and the actual value) a bundle whose files
do not match their SHA-256 in the manifest, whose grid differs from the carpet's, whose graphs
disagree with the manifest, or whose body model differs from the one it was trained with.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np

from edge.provenance import sha256_file  # noqa: F401  (re-exported: export and tests use it from here)
from edge.infer.normalise import NORMALISATION, center_of_pressure_m, check_finite, normalise_kpa
from edge.infer.rotations import rot6d_to_axis_angle

SCHEMA = "cavatar.bundle/1"
GRAPHS = ("encoder.onnx", "head.onnx")
HEAD_OUTPUTS = ("rot6d", "betas", "transl_rel_m", "activity_logits", "confidence")


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


def verify(path: str | Path, grid: tuple[int, int] | None = None) -> dict[str, Any]:
    """Check a bundle folder's manifest, file hashes and grid; return the manifest or raise BundleError."""
    folder = Path(path)
    mpath = folder / "manifest.json"
    if not mpath.is_file():
        raise BundleError(f"{folder}: no manifest.json (not a model bundle)")
    try:
        manifest = json.loads(mpath.read_text())
    except (OSError, ValueError) as exc:
        raise BundleError(f"{mpath}: unreadable manifest ({exc})") from None
    if manifest.get("schema") != SCHEMA:
        raise BundleError(f"{mpath}: schema {manifest.get('schema')!r}, this runtime reads {SCHEMA!r}")
    files = manifest.get("files", {})
    for name in GRAPHS:
        if name not in files:
            raise BundleError(f"{mpath}: {name} is not listed in the manifest's files")
    for name, expected in files.items():
        f = folder / name
        if not f.is_file():
            raise BundleError(f"{folder}: {name} is listed in the manifest but missing")
        actual = sha256_file(f)
        if actual != expected:
            raise BundleError(f"{f}: SHA-256 mismatch: manifest expects {expected}, file has {actual} (tampered or corrupt)")
    bundle_grid = tuple(int(g) for g in manifest["grid"])
    if grid is not None and tuple(int(g) for g in grid) != bundle_grid:
        raise BundleError(f"{folder}: the bundle is for a {bundle_grid[0]}×{bundle_grid[1]} carpet, "
                          f"this carpet is {grid[0]}×{grid[1]}")
    return manifest


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
        return tuple(int(g) for g in self.manifest["grid"])

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

    def head(self, features: np.ndarray, origin_m: np.ndarray | None = None) -> dict[str, np.ndarray]:
        """(B,T,F) features → pose_aa (B,72), betas (B,10), transl_m (B,3), transl_rel_m (B,3),
        activity_probs (B,12), confidence (B,).

        ``transl_m = transl_rel_m + origin_m``; ``origin_m`` (B,3) is :meth:`origin_m` of the
        window's LAST frame (the person's centre of pressure); without it, transl_m = transl_rel_m.
        """
        w = np.ascontiguousarray(features, np.float32)
        if w.ndim != 3 or w.shape[1:] != (self.window, self.features):
            raise ValueError(f"head expects (B,{self.window},{self.features}), got {w.shape}")
        check_finite(w, "head input (window features)")
        out = dict(zip([o.name for o in self._head.get_outputs()], self._head.run(None, {self._head_name: w})))
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

"""The calibration file: what a carpet's sensels read and how to turn that into kPa.

One ``.npz`` file, written atomically, holding per-sensel arrays and one JSON
metadata record (``meta``) with its own SHA-256 over everything else::

    baseline_counts (H, W) float32  unloaded reading
    noise_counts    (H, W) float32  temporal noise (1.4826 · MAD, floored)
    gain            (H, W) float32  relative sensitivity (1 = typical), clipped to [0.5, 2]
    fault           (H, W) uint8    bit flags, FAULT below (0 = healthy)
    meta            JSON: schema, device (id, rows, cols, adc_bits, sign, firmware,
                    protocol), pitch_m, curve (model, half_scale_kpa, exponent,
                    span_counts, saturation_kpa), crosstalk_r_norm, temperature
                    (at calibration, coefficient per °C), line faults, steps done,
                    validation summary, created, software version, sha256

The response model (the same family the simulator draws from, the note's Hill curve)::

    counts = baseline + sign · gain · span · r(p),   r(p) = pⁿ / (pⁿ + p_halfⁿ)

A file that does not match the device (id, grid, bit depth, sign, firmware) is refused
with a message that says what differs and how to recalibrate.
"""

from __future__ import annotations

import hashlib
import io
import json
import os
import stat
import struct
import zipfile
import zlib
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import numpy as np

from cavatar_common.atomic import write_atomic

SCHEMA = "cavatar.calibration/1"
ARRAYS = {"baseline_counts": np.float32, "noise_counts": np.float32, "gain": np.float32, "fault": np.uint8}

# Per-sensel fault flags.
FAULT = {
    "dead": 1,  # never responds (open line, dead sensel)
    "weak": 2,  # responds far less than its neighbours (half-dead line)
    "stuck": 4,  # reads at a rail or constant whatever happens
    "noisy": 8,  # temporal noise far above the carpet's
    "short": 16,  # a shorted crossing couples its row and column
    "outside": 32,  # not part of the carpet (non-rectangular mask)
}
UNUSABLE = FAULT["dead"] | FAULT["stuck"] | FAULT["noisy"] | FAULT["short"] | FAULT["outside"]


class CalibrationError(Exception):
    """A calibration file that is unreadable, damaged, or does not fit this device."""


MAX_FILE_BYTES = 64 << 20  # a 512×512 calibration is ~3 MB uncompressed
MAX_META_BYTES = 1 << 20
MAX_GRID = 512
NPY_HEADER_MAX = 4096  # an .npy header (magic, version, dict) is ~128 bytes


def _read_npz(path: Path) -> tuple[dict[str, Any], dict[str, np.ndarray]]:
    """``meta`` and the arrays of a calibration npz, checking sizes BEFORE decompressing anything."""
    st = os.stat(path)
    if not stat.S_ISREG(st.st_mode):
        raise CalibrationError("not a regular file")
    if st.st_size == 0:
        raise CalibrationError("the file is empty")
    if st.st_size > MAX_FILE_BYTES:
        raise CalibrationError(f"{st.st_size} bytes, more than a calibration ever takes ({MAX_FILE_BYTES})")
    with zipfile.ZipFile(path) as zf:
        members = {i.filename: i for i in zf.infolist()}
        want = {f"{k}.npy" for k in ("meta", *ARRAYS)}
        if set(members) != want:
            extra, missing = sorted(set(members) - want), sorted(want - set(members))
            raise CalibrationError(f"not a calibration npz (missing {missing or '-'}, unexpected {extra or '-'})")
        if members["meta.npy"].file_size > MAX_META_BYTES + NPY_HEADER_MAX:
            raise CalibrationError(f"its meta would inflate to {members['meta.npy'].file_size} bytes "
                                   f"(at most {MAX_META_BYTES})")
        meta_arr = _read_member(zf, "meta.npy", MAX_META_BYTES)
        if meta_arr.dtype.kind != "U" or meta_arr.shape != ():
            raise CalibrationError("its meta is not one JSON string")
        meta = json.loads(str(meta_arr))
        if not isinstance(meta, dict):
            raise CalibrationError("its meta is not a JSON object")
        device = meta.get("device")
        rows, cols = (device.get("rows"), device.get("cols")) if isinstance(device, dict) else (None, None)
        if not all(isinstance(n, int) and not isinstance(n, bool) and 1 <= n <= MAX_GRID for n in (rows, cols)):
            raise CalibrationError(f"its device grid {rows!r}×{cols!r} is out of range (1..{MAX_GRID} each)")
        arrays = {}
        for name in ARRAYS:
            limit = rows * cols * 8  # float64 is the widest dtype a writer could have used
            declared = members[f"{name}.npy"].file_size
            if declared > limit + NPY_HEADER_MAX:
                raise CalibrationError(f"{name} would inflate to {declared} bytes; a {rows}×{cols} grid needs at most "
                                       f"{limit + NPY_HEADER_MAX}")
            arrays[name] = _read_member(zf, f"{name}.npy", limit)
    return meta, arrays


def _read_member(zf: zipfile.ZipFile, name: str, limit: int) -> np.ndarray:
    """One .npy member of at most ``limit`` data bytes: its header is checked before its data is read (no
    pickles, no object arrays); zipfile itself stops at the size the entry declares."""
    fmt = np.lib.format
    with zf.open(name) as f:
        version = fmt.read_magic(f)
        if version == (1, 0):
            shape, fortran, dtype = fmt.read_array_header_1_0(f)
        elif version == (2, 0):
            shape, fortran, dtype = fmt.read_array_header_2_0(f)
        else:
            raise CalibrationError(f"{name} has an unknown .npy version {version}")
        if dtype.hasobject:
            raise CalibrationError(f"{name} holds Python objects; a calibration holds numbers only")
        nbytes = int(np.prod(shape, dtype=np.int64)) * dtype.itemsize
        if nbytes > limit:
            raise CalibrationError(f"{name} declares {shape} of {dtype} ({nbytes} bytes), at most {limit} expected")
        data = f.read(nbytes)
        if len(data) != nbytes:
            raise CalibrationError(f"{name} is truncated ({len(data)} of {nbytes} bytes)")
    return np.frombuffer(data, dtype).reshape(shape, order="F" if fortran else "C").copy()


@dataclass
class Curve:
    """Global response curve (per-sensel differences live in ``gain``)."""

    half_scale_kpa: float = 8.0
    exponent: float = 1.2
    span_counts: float = 0.0  # counts from baseline to the rail direction at r = 1, for gain 1
    saturation_kpa: float = 14.0  # above this the reading is censored (≥)

    def response(self, p_kpa: np.ndarray) -> np.ndarray:
        p = np.maximum(p_kpa, 0.0) ** self.exponent
        return p / (p + self.half_scale_kpa**self.exponent)

    def inverse(self, r: np.ndarray) -> np.ndarray:
        r = np.clip(r, 0.0, 1.0 - 1e-6)
        return self.half_scale_kpa * (r / (1.0 - r)) ** (1.0 / self.exponent)


@dataclass
class Calibration:
    baseline_counts: np.ndarray
    noise_counts: np.ndarray
    gain: np.ndarray
    fault: np.ndarray
    device: dict[str, Any]  # device_id, rows, cols, adc_bits, sign, firmware, protocol_version
    pitch_m: float
    curve: Curve = field(default_factory=Curve)
    crosstalk_r_norm: float = 0.0  # line-loading resistance × full-scale conductance; 0 = off
    temperature_c: float | None = None
    temp_coeff_per_c: float = 0.0025  # relative sensitivity change per °C
    line_faults: list[dict[str, Any]] = field(default_factory=list)
    steps: dict[str, Any] = field(default_factory=dict)
    validation: dict[str, Any] = field(default_factory=dict)
    created: str = field(default_factory=lambda: datetime.now(timezone.utc).isoformat(timespec="seconds"))
    sha256: str = ""

    def __post_init__(self) -> None:
        self.check_arrays()

    def check_arrays(self) -> None:
        """Refuse per-sensel values that no procedure writes (CalibrationError naming how many).

        NaN/∞ in ``baseline_counts``, ``noise_counts`` or ``gain`` (anywhere: one NaN gain
        would poison the crosstalk inverse's line sums and zero the whole carpet), and a gain
        ≤ 0 on a usable sensel (the procedures write 0.5–2; dividing by it would read pressure
        as negative or infinite). A masked sensel's gain is never used, so it is not checked.
        """
        for name in ("baseline_counts", "noise_counts", "gain"):
            bad = ~np.isfinite(np.asarray(getattr(self, name), np.float64))
            if bad.any():
                r, c = np.argwhere(bad)[0]
                raise CalibrationError(f"calibration {name} has {int(bad.sum())} NaN/∞ value(s) (first at row {r}, "
                                       f"col {c}): the file is damaged; recalibrate with `cavatar calibrate`")
        fault = np.asarray(self.fault)
        bad = (np.asarray(self.gain) <= 0) & ((fault & UNUSABLE) == 0)
        if bad.any():
            r, c = np.argwhere(bad)[0]
            raise CalibrationError(f"calibration gain is zero or negative at {int(bad.sum())} usable sensel(s) (first at "
                                   f"row {r}, col {c}); gains must be > 0 (the procedures write 0.5–2): recalibrate, "
                                   "or flag those sensels dead in `fault`")

    @property
    def shape(self) -> tuple[int, int]:
        return self.baseline_counts.shape

    @property
    def usable(self) -> np.ndarray:
        """(H, W) bool: sensels whose readings are trusted."""
        return (self.fault & UNUSABLE) == 0

    @property
    def full_scale(self) -> int:
        return (1 << int(self.device["adc_bits"])) - 1

    def age_s(self, now: datetime | None = None) -> float:
        now = now or datetime.now(timezone.utc)
        return (now - datetime.fromisoformat(self.created)).total_seconds()

    def meta(self) -> dict[str, Any]:
        return {
            "schema": SCHEMA, "device": self.device, "pitch_m": self.pitch_m, "curve": self.curve.__dict__,
            "crosstalk_r_norm": self.crosstalk_r_norm, "temperature_c": self.temperature_c,
            "temp_coeff_per_c": self.temp_coeff_per_c, "line_faults": self.line_faults, "steps": self.steps,
            "validation": self.validation, "created": self.created,
        }

    # ------------------------------------------------------------------ checks

    def check_device(self, info: Any) -> None:
        """Refuse to apply to a device that is not the one calibrated (``info``: the INFO packet)."""
        d, diffs = self.device, []
        for key, theirs in (("device_id", info.device_id), ("rows", info.rows), ("cols", info.cols),
                            ("adc_bits", info.adc_bits), ("sign", info.sign)):
            if d.get(key) != theirs:
                diffs.append(f"{key} {d.get(key)!r} in the file, {theirs!r} on the device")
        fw = [info.fw_major, info.fw_minor, info.fw_patch]
        if d.get("firmware") and list(d["firmware"])[:2] != fw[:2]:
            diffs.append(f"firmware {'.'.join(map(str, d['firmware']))} in the file, {'.'.join(map(str, fw))} on the device")
        if diffs:
            raise CalibrationError(
                "this calibration belongs to another carpet or configuration: " + "; ".join(diffs)
                + ". Run `cavatar calibrate` on this carpet (or pass the file made for it)."
            )

    # ------------------------------------------------------------------ files

    def _payload(self) -> tuple[dict[str, np.ndarray], str]:
        arrays = {k: np.ascontiguousarray(getattr(self, k), dtype=t) for k, t in ARRAYS.items()}
        shapes = {k: a.shape for k, a in arrays.items()}
        if len(set(shapes.values())) != 1:
            raise CalibrationError(f"calibration arrays differ in shape: {shapes}")
        return arrays, json.dumps(self.meta(), sort_keys=True)

    @staticmethod
    def _digest(arrays: dict[str, np.ndarray], meta_json: str) -> str:
        h = hashlib.sha256(meta_json.encode())
        for k in sorted(arrays):
            h.update(k.encode() + arrays[k].tobytes())
        return h.hexdigest()

    def save(self, path: str | Path) -> str:
        """Write atomically; returns the SHA-256 recorded in the file."""
        arrays, meta_json = self._payload()
        self.sha256 = self._digest(arrays, meta_json)
        buf = io.BytesIO()
        np.savez_compressed(buf, meta=np.array(json.dumps({**json.loads(meta_json), "sha256": self.sha256})), **arrays)
        write_atomic(path, buf.getvalue())  # fsynced: the board restarts with this calibration
        return self.sha256

    @classmethod
    def load(cls, path: str | Path) -> "Calibration":
        """Read and verify a calibration file; CalibrationError (one line: what is wrong, what to do) otherwise.

        Checked before anything is decompressed: a regular file of at most ``MAX_FILE_BYTES``; an npz holding
        exactly ``meta`` and the arrays; the meta small, the grid in range, and every array's declared size the
        size its grid needs (so a small file that would inflate to gigabytes is refused unread)."""
        path = Path(path)
        if not path.exists():
            raise CalibrationError(f"no calibration file {path}; create one with `cavatar calibrate`")
        try:
            meta, arrays = _read_npz(path)
        except CalibrationError as exc:
            raise CalibrationError(f"{path}: {exc}; restore the file or recalibrate with `cavatar calibrate`") from None
        except (OSError, EOFError, ValueError, KeyError, RuntimeError, NotImplementedError, zipfile.BadZipFile,
                zlib.error, struct.error) as exc:
            reason = str(exc).splitlines()[0][:160] if str(exc) else type(exc).__name__
            raise CalibrationError(f"{path} is not a readable calibration file (damaged or truncated: {reason}); "
                                   "restore it or recalibrate with `cavatar calibrate`") from None
        if meta.get("schema") != SCHEMA:
            raise CalibrationError(f"{path}: schema {meta.get('schema')!r}; this version reads {SCHEMA!r}")
        stored = meta.pop("sha256", "")
        arrays = {k: np.ascontiguousarray(a, dtype=ARRAYS[k]) for k, a in arrays.items()}
        if cls._digest(arrays, json.dumps(meta, sort_keys=True)) != stored:
            raise CalibrationError(f"{path} is damaged: its contents do not match the SHA-256 it records; recalibrate")
        try:
            cal = cls(**arrays, device=meta["device"], pitch_m=meta["pitch_m"], curve=Curve(**meta["curve"]),
                      crosstalk_r_norm=meta["crosstalk_r_norm"], temperature_c=meta["temperature_c"],
                      temp_coeff_per_c=meta["temp_coeff_per_c"], line_faults=meta["line_faults"], steps=meta["steps"],
                      validation=meta["validation"], created=meta["created"], sha256=stored)
        except CalibrationError as exc:
            raise CalibrationError(f"{path}: {exc}") from None
        except (KeyError, TypeError, ValueError) as exc:
            raise CalibrationError(f"{path}: its metadata lacks or mistypes a field ({type(exc).__name__}: {exc}); "
                                   "recalibrate with `cavatar calibrate`") from None
        if cal.shape != (meta["device"]["rows"], meta["device"]["cols"]):
            raise CalibrationError(f"{path}: arrays are {cal.shape}, the device record says "
                                   f"{meta['device']['rows']}×{meta['device']['cols']}")
        return cal

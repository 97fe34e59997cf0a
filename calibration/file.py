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
from dataclasses import dataclass, field
from datetime import datetime, timezone
from pathlib import Path
from typing import Any

import numpy as np

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
        path = Path(path)
        part = path.with_name(path.name + ".part")
        buf = io.BytesIO()
        np.savez_compressed(buf, meta=np.array(json.dumps({**json.loads(meta_json), "sha256": self.sha256})), **arrays)
        part.write_bytes(buf.getvalue())
        os.replace(part, path)
        return self.sha256

    @classmethod
    def load(cls, path: str | Path) -> "Calibration":
        path = Path(path)
        if not path.exists():
            raise CalibrationError(f"no calibration file {path}; create one with `cavatar calibrate`")
        try:
            with np.load(path, allow_pickle=False) as z:
                meta = json.loads(str(z["meta"]))
                arrays = {k: z[k] for k in ARRAYS}
        except (OSError, ValueError, KeyError, json.JSONDecodeError) as exc:
            raise CalibrationError(f"{path} is not a readable calibration file ({exc})") from None
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
        if cal.shape != (meta["device"]["rows"], meta["device"]["cols"]):
            raise CalibrationError(f"{path}: arrays are {cal.shape}, the device record says {meta['device']['rows']}×{meta['device']['cols']}")
        return cal

"""The published record ``cavatar.bodies/1``: build it, check it, serialise it.

One record per frame with at least one person, and a heartbeat (``people: []``) when the
carpet is empty (design.md, "Published record")::

    {"schema":"cavatar.bodies/1","device":"carpet-01","seq":1234,"time":1732240000.123,
     "model":"default@0123456789ab","people":[
       {"track_id":3,"transl_m":[x,y,z],"pose_aa":[72 floats],"betas":[10 floats],
        "confidence":0.91,"activity":"squat"}]}

    person = make_person(3, transl_m, pose_aa, betas, confidence=0.91, activity="squat")
    rec = make_record("carpet-01", seq=1234, time_s=t, model="default@0123456789ab", people=[person])
    line = dumps(rec)              # one line of compact JSON, no newline

Floats are rounded (:data:`DECIMALS` places: 10 µm, 1e-5 rad; time to the millisecond);
NaN and infinities are refused with :class:`RecordError` and never published.

Privacy: the record is a closed set of fields (the JSON Schema says
``additionalProperties: false`` at every level). :func:`check_record` is the small
structural check every sink runs before it publishes; it refuses any other key and names
pressure-like keys (:class:`PrivacyError`). :func:`check_telemetry` guards the free-form
payloads (``info``): no pressure-like keys, no arrays that could carry a frame.
The JSON Schema (``edge/schema/bodies.schema.json``, :func:`load_schema`) is the published
contract; tests validate with ``jsonschema``, the runtime needs only this module.
"""

from __future__ import annotations

import json
import math
import re
from importlib import resources
from typing import Any, Iterable, Mapping, Sequence

SCHEMA_ID = "cavatar.bodies/1"
TRANSL_LEN = 3
POSE_LEN = 72  # 24 joints x axis-angle; pose_aa[0:3] is the global orientation
BETAS_LEN = 10
MAX_PEOPLE = 32
DECIMALS = 5
TIME_DECIMALS = 3
CONFIDENCE_DECIMALS = 3
MAX_SEQ = 2**53 - 1  # exact in every JSON reader
MAX_TRACK_ID = 2**31 - 1

RECORD_KEYS = ("schema", "device", "seq", "time", "model", "people")
PERSON_KEYS = ("track_id", "transl_m", "pose_aa", "betas", "confidence", "activity")

# Same patterns as the JSON Schema (a test keeps them equal).
DEVICE_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,63}$"
MODEL_PATTERN = r"^[A-Za-z0-9][A-Za-z0-9_.+-]{0,63}@[0-9a-f]{12}$"
ACTIVITY_PATTERN = r"^[a-z][a-z0-9_]{0,31}$"
_DEVICE = re.compile(DEVICE_PATTERN)
_MODEL = re.compile(MODEL_PATTERN)
_ACTIVITY = re.compile(ACTIVITY_PATTERN)

# Keys that smell of sensor data. Never allowed in anything a sink publishes.
FORBIDDEN_KEY = re.compile(r"pressure|kpa|sensel|heatmap|^raw|(^|_)counts$|^frames?$|^image|^mask", re.I)
# Telemetry (info) may carry short lists (versions, counters), never an array that could hold a frame.
MAX_TELEMETRY_LIST = 64
MAX_TELEMETRY_STRING = 512


class RecordError(ValueError):
    """A record (or payload) that must not be published; the message says which field and why."""


class PrivacyError(RecordError):
    """Something that looks like sensor data (pressure, counts, frames) was about to be published."""


# ----------------------------------------------------------------------------- building


def _number(value: Any, name: str) -> float:
    if isinstance(value, bool) or isinstance(value, (str, bytes)):
        raise RecordError(f"{name} must be a number, got {value!r}")
    try:
        x = float(value)
    except (TypeError, ValueError):
        raise RecordError(f"{name} must be a number, got {type(value).__name__}") from None
    if not math.isfinite(x):
        raise RecordError(f"{name} is {x} (NaN/Inf are never published)")
    return x


def _floats(values: Any, n: int, name: str, decimals: int = DECIMALS) -> list[float]:
    """Flatten one level of nesting ((24,3) → 72), check the length, round. Accepts numpy arrays."""
    if isinstance(values, (str, bytes, Mapping)):
        raise RecordError(f"{name} must be {n} numbers")
    flat: list[Any] = []
    for v in values:
        if hasattr(v, "__iter__") and not isinstance(v, (str, bytes)):
            flat.extend(v)
        else:
            flat.append(v)
    if len(flat) != n:
        raise RecordError(f"{name} must have {n} numbers, got {len(flat)}")
    return [round(_number(v, f"{name}[{i}]"), decimals) + 0.0 for i, v in enumerate(flat)]


def _int(value: Any, name: str, lo: int, hi: int) -> int:
    if isinstance(value, bool):
        raise RecordError(f"{name} must be an integer, got {value!r}")
    try:
        i = int(value)
    except (TypeError, ValueError):
        raise RecordError(f"{name} must be an integer, got {value!r}") from None
    if i != value or not lo <= i <= hi:
        raise RecordError(f"{name} must be an integer in [{lo}, {hi}], got {value!r}")
    return i


def make_person(track_id: int, transl_m: Iterable, pose_aa: Iterable, betas: Iterable,
                confidence: float, activity: str) -> dict:
    """One person of a record. ``pose_aa`` is (72,) or (24, 3) axis-angle, radians."""
    conf = round(_number(confidence, "confidence"), CONFIDENCE_DECIMALS)
    if not 0.0 <= conf <= 1.0:
        raise RecordError(f"confidence must be in [0, 1], got {confidence!r}")
    if not isinstance(activity, str) or not _ACTIVITY.match(activity):
        raise RecordError(f"activity must match {ACTIVITY_PATTERN}, got {activity!r}")
    return {
        "track_id": _int(track_id, "track_id", 0, MAX_TRACK_ID),
        "transl_m": _floats(transl_m, TRANSL_LEN, "transl_m"),
        "pose_aa": _floats(pose_aa, POSE_LEN, "pose_aa"),
        "betas": _floats(betas, BETAS_LEN, "betas"),
        "confidence": conf,
        "activity": activity,
    }


def make_record(device: str, seq: int, time_s: float, model: str, people: Sequence[Mapping] = ()) -> dict:
    """A checked ``cavatar.bodies/1`` record; ``people`` made by :func:`make_person` (empty: heartbeat)."""
    rec = {
        "schema": SCHEMA_ID,
        "device": device,
        "seq": _int(seq, "seq", 0, MAX_SEQ),
        "time": round(_number(time_s, "time"), TIME_DECIMALS),
        "model": model,
        "people": [dict(p) for p in people],
    }
    check_record(rec)
    return rec


def heartbeat(device: str, seq: int, time_s: float, model: str) -> dict:
    """The record published when the carpet is empty."""
    return make_record(device, seq, time_s, model, [])


# ----------------------------------------------------------------------------- checking


def _refuse_keys(mapping: Mapping, allowed: Sequence[str], where: str) -> None:
    for key in mapping:
        if not isinstance(key, str):
            raise RecordError(f"{where}: key {key!r} is not a string")
        if key not in allowed:
            if FORBIDDEN_KEY.search(key):
                raise PrivacyError(f"{where}: {key!r} looks like sensor data; pressure, counts and frames are never published")
            raise RecordError(f"{where}: unknown field {key!r} (allowed: {', '.join(allowed)})")
    missing = [k for k in allowed if k not in mapping]
    if missing:
        raise RecordError(f"{where}: missing {', '.join(missing)}")


def _check_floats(values: Any, n: int, name: str) -> None:
    if type(values) is not list or len(values) != n:
        raise RecordError(f"{name} must be a list of {n} numbers")
    for i, v in enumerate(values):
        if type(v) not in (float, int) or not math.isfinite(v):
            raise RecordError(f"{name}[{i}] must be a finite number, got {v!r}")


def check_record(record: Any) -> None:
    """Structural check of a ``cavatar.bodies/1`` record (the runtime's stand-in for the JSON Schema).

    Raises :class:`RecordError` (or :class:`PrivacyError` for sensor-like keys). It checks
    exactly what the schema says: closed key sets, types, lengths, ranges, patterns.
    """
    if not isinstance(record, Mapping):
        raise RecordError(f"a record is a JSON object, got {type(record).__name__}")
    _refuse_keys(record, RECORD_KEYS, "record")
    if record["schema"] != SCHEMA_ID:
        raise RecordError(f"record: schema must be {SCHEMA_ID!r}, got {record['schema']!r}")
    if not isinstance(record["device"], str) or not _DEVICE.match(record["device"]):
        raise RecordError(f"record: device must match {DEVICE_PATTERN}, got {record['device']!r}")
    seq = record["seq"]
    if type(seq) is not int or not 0 <= seq <= MAX_SEQ:
        raise RecordError(f"record: seq must be an integer in [0, {MAX_SEQ}], got {seq!r}")
    t = record["time"]
    if type(t) not in (float, int) or not math.isfinite(t) or t < 0:
        raise RecordError(f"record: time must be a finite number of seconds >= 0, got {t!r}")
    if not isinstance(record["model"], str) or not _MODEL.match(record["model"]):
        raise RecordError(f"record: model must be '<bundle name>@<sha256[:12]>' ({MODEL_PATTERN}), got {record['model']!r}")
    people = record["people"]
    if type(people) is not list or len(people) > MAX_PEOPLE:
        raise RecordError(f"record: people must be a list of at most {MAX_PEOPLE}")
    for i, p in enumerate(people):
        where = f"people[{i}]"
        if not isinstance(p, Mapping):
            raise RecordError(f"{where} must be a JSON object")
        _refuse_keys(p, PERSON_KEYS, where)
        tid = p["track_id"]
        if type(tid) is not int or not 0 <= tid <= MAX_TRACK_ID:
            raise RecordError(f"{where}.track_id must be an integer in [0, {MAX_TRACK_ID}], got {tid!r}")
        _check_floats(p["transl_m"], TRANSL_LEN, f"{where}.transl_m")
        _check_floats(p["pose_aa"], POSE_LEN, f"{where}.pose_aa")
        _check_floats(p["betas"], BETAS_LEN, f"{where}.betas")
        c = p["confidence"]
        if type(c) not in (float, int) or not 0 <= c <= 1:
            raise RecordError(f"{where}.confidence must be a number in [0, 1], got {c!r}")
        if not isinstance(p["activity"], str) or not _ACTIVITY.match(p["activity"]):
            raise RecordError(f"{where}.activity must match {ACTIVITY_PATTERN}, got {p['activity']!r}")


def check_telemetry(payload: Any, where: str = "info") -> None:
    """Guard for free-form payloads (``info``): JSON types only, finite numbers, no
    pressure-like keys, no nested or long arrays, no long strings (nothing that could carry a frame)."""
    if isinstance(payload, Mapping):
        for key, value in payload.items():
            if not isinstance(key, str):
                raise RecordError(f"{where}: key {key!r} is not a string")
            if FORBIDDEN_KEY.search(key):
                raise PrivacyError(f"{where}.{key} looks like sensor data; pressure, counts and frames are never published")
            check_telemetry(value, f"{where}.{key}")
    elif isinstance(payload, (list, tuple)):
        if len(payload) > MAX_TELEMETRY_LIST:
            raise PrivacyError(f"{where} is a list of {len(payload)} (> {MAX_TELEMETRY_LIST}); arrays are never published")
        for i, value in enumerate(payload):
            if isinstance(value, (list, tuple)):
                raise PrivacyError(f"{where}[{i}] is a nested array; arrays are never published")
            check_telemetry(value, f"{where}[{i}]")
    elif isinstance(payload, str):
        if len(payload) > MAX_TELEMETRY_STRING:
            raise PrivacyError(f"{where} is a string of {len(payload)} characters (> {MAX_TELEMETRY_STRING})")
    elif isinstance(payload, bool) or payload is None:
        pass
    elif isinstance(payload, (int, float)):
        if not math.isfinite(payload):
            raise RecordError(f"{where} is {payload} (NaN/Inf are never published)")
    else:
        raise RecordError(f"{where}: {type(payload).__name__} is not a JSON type")


# ----------------------------------------------------------------------------- serialising


def dumps(payload: Any) -> str:
    """Compact one-line JSON (no newline); refuses NaN/Inf as a last guard."""
    try:
        return json.dumps(payload, separators=(",", ":"), ensure_ascii=False, allow_nan=False)
    except ValueError as exc:
        raise RecordError(f"not publishable as JSON: {exc}") from None


def load_schema() -> dict:
    """The JSON Schema (draft 2020-12) of ``cavatar.bodies/1``, shipped as package data."""
    text = resources.files("edge").joinpath("schema", "bodies.schema.json").read_text(encoding="utf-8")
    return json.loads(text)

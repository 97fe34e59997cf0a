"""The runtime's configuration: one TOML file, typed, every key described, unknown keys refused.

    cfg = load_config("/etc/cavatar/cavatar.toml")          # ConfigError lists EVERY problem
    cfg = RuntimeConfig.from_dict({"source": {"url": "sim://?people=1"}})
    cfg = cfg.with_overrides(source="serial:///dev/ttyACM0", seconds=30)   # the CLI flags

Every key described, and the file as TOML: :mod:`edge.runtime.config_docs`.

Sections: ``[device]``, ``[source]``, ``[calibration]`` (and ``[calibration.baseline]``,
handed to :class:`calibration.baseline.BaselineConfig`), ``[model]``, ``[scene]`` (handed to
:class:`edge.scene.SceneConfig`, whose own keys and checks apply), ``[sinks]``, ``[runtime]``.
Every section and key is optional; what is left out takes its default.

Relative paths are relative to the current directory. Secrets never go in the file: the
MQTT password comes from the environment (``CAVATAR_MQTT_PASSWORD``, or the variable a
sink URL names with ``password_env=``); a key that looks like one is refused, saying so.
"""

from __future__ import annotations

import dataclasses
import re
import tomllib
from dataclasses import dataclass, field
from importlib import resources
from pathlib import Path
from typing import Any

from calibration.baseline import BaselineConfig
from cavatar_common.config import at_least_zero, between, described, expected_type, positive
from edge.scene import SceneConfig
from edge.scene.falls import FallConfig

SHIPPED_BUNDLE = "lean-96"
DEFAULT_OUTPUT_DIR = "out/cavatar"
SECRET_KEY = re.compile(r"pass|secret|token|credential", re.I)


def default_bundle_path() -> Path:
    """The model bundle shipped with the package (``edge/models/lean-96``)."""
    return Path(str(resources.files("edge.models").joinpath(SHIPPED_BUNDLE)))


class ConfigError(ValueError):
    """A configuration with problems; ``problems`` lists every one (key path: what is wrong, what to do)."""

    def __init__(self, problems: list[str], source: str = "configuration") -> None:
        self.problems = list(problems)
        self.source = source
        super().__init__(f"{source}: {len(self.problems)} problem(s):\n" + "\n".join(f"  - {p}" for p in self.problems))


# ----------------------------------------------------------------------------- field checks


_f = described  # short: the field tables below are long


def _device_id(v: str) -> str | None:
    from edge.topics import check_level

    try:
        check_level(v, "device id")
    except ValueError as exc:
        return str(exc)
    return None


def _source_url(v: str) -> str | None:
    from edge.sources import SourceError, open_link

    try:
        open_link(v)  # parses the URL and its options; opens nothing
    except (ValueError, SourceError) as exc:
        return str(exc)
    return None


def check_sink_url(url: str) -> str | None:
    """Problem with a sink URL (scheme, options, a password in it), or None. Opens nothing."""
    from edge.sinks import sink_url_problem

    return sink_url_problem(url)


def _sink_urls(v: list[str]) -> str | None:
    if not v:
        return "give at least one sink URL (e.g. jsonl://out/cavatar/bodies.jsonl)"
    problems = [p for p in (check_sink_url(u) for u in v) if p]
    return "; ".join(problems) or None


def _missing_rows(v: str) -> str | None:
    return None if v in ("drop", "flag") else "must be 'drop' or 'flag'"


# ----------------------------------------------------------------------------- sections


@dataclass(frozen=True)
class DeviceSection:
    """Who this board is."""

    id: str = _f("carpet-01", "device id: the <device> level of the MQTT topics and the 'device' of every record "
                              "(1-64 of A-Z a-z 0-9 _ . -)", _device_id)


@dataclass(frozen=True)
class SourceSection:
    """Where frames come from."""

    url: str = _f("sim://?people=2&seed=7", "source URL: serial:///dev/ttyACM0?baud=2000000, usb://1209:CA7A, "
                                            "replay://capture.bin?speed=1, sim://?people=2&seed=7 (the virtual carpet)",
                  _source_url)
    queue_frames: int = _f(4, "frames held between the reader thread and the pipeline; when the pipeline falls behind a "
                              "live board the oldest is dropped (counted), so it always works on the newest frame",
                           between(1, 1024))
    missing_rows: str = _f("drop", "a frame with rows lost on the link: 'drop' it, or 'flag' (repair up to 4 rows from "
                                   "the last good frame)", _missing_rows)
    board_timeout_s: float = _f(5.0, "no good frame from the board for this long → the board is reported unavailable "
                                     "(MQTT board topic \"offline\", presence withdrawn, one WARNING); the first good "
                                     "frame after it → available again (one WARNING)", positive)


@dataclass(frozen=True)
class CalibrationSection:
    """The carpet's calibration (counts → kPa)."""

    file: str = _f("", "calibration file written by `cavatar calibrate`; empty: a sim:// source is calibrated "
                       "automatically (the scripted session, saved beside the status file), a real carpet is refused")
    max_age_days: float = _f(180.0, "a calibration older than this is reported as due (status, `cavatar doctor`)",
                             positive)
    baseline: BaselineConfig = field(default_factory=BaselineConfig,
                                     metadata={"doc": "runtime baseline tracking: see [calibration.baseline]"})


@dataclass(frozen=True)
class ModelSection:
    """The model bundle (encoder.onnx, head.onnx, manifest.json)."""

    bundle: str = _f("", "model bundle folder; empty: the shipped bundle (edge/models/lean-96)")
    threads: int = _f(1, "onnxruntime intra-op threads per model (1 suits a 2-core board: the reader and "
                         "publisher threads need the other core)", between(1, 64))
    resolve_heading: bool = _f(True, "turn a body the model publishes facing backwards (180° about the vertical) when "
                                     "the feet's pressure says so, per track (edge/infer/heading.py)")
    heading_params: str = _f("", "the heading resolver's fitted parameters (JSON); empty: the shipped "
                                 "edge/infer/heading.json")


@dataclass(frozen=True)
class SinksSection:
    """Where body records go (never pressure)."""

    urls: list[str] = _f([f"jsonl://{DEFAULT_OUTPUT_DIR}/bodies.jsonl"],
                         "sink URLs: jsonl:///path/bodies.jsonl?rotate_mb=100&keep=10, jsonl:- (stdout), "
                         "mqtt://user@host:1883/prefix?qos=1&spool=DIR (password from $CAVATAR_MQTT_PASSWORD)",
                         _sink_urls)
    queue_records: int = _f(256, "records held between the pipeline and the publisher thread; when full the oldest "
                                 "is dropped (counted)", between(1, 100_000))


@dataclass(frozen=True)
class RuntimeSection:
    """The run itself: how long, health reporting, heartbeats."""

    status_file: str = _f(f"{DEFAULT_OUTPUT_DIR}/status.json", "health counters written here (atomically) every "
                                                                "status_s; `cavatar status` reads it")
    seconds: float = _f(0.0, "stop after this long; 0 = run until stopped (SIGTERM, Ctrl-C)", at_least_zero)
    summary_s: float = _f(1.0, "period of the one-line live summary on stderr; 0 = none", at_least_zero)
    status_s: float = _f(1.0, "period of the status file", positive)
    info_s: float = _f(10.0, "period of the health/info payload published to the sinks (MQTT: retained info topic)",
                       positive)
    heartbeat_s: float = _f(1.0, "while nobody is on the carpet, a heartbeat record (people: []) this often "
                                 "(and at once when the carpet becomes empty)", positive)
    timing_window: int = _f(512, "per-stage milliseconds are median / p99 over this many recent frames", between(1, 100_000))


SECTIONS: dict[str, type] = {
    "device": DeviceSection,
    "source": SourceSection,
    "calibration": CalibrationSection,
    "model": ModelSection,
    "scene": SceneConfig,
    "sinks": SinksSection,
    "runtime": RuntimeSection,
    "events": FallConfig,
}
DELEGATED = {"scene": SceneConfig, "calibration.baseline": BaselineConfig}  # typed configs owned elsewhere


@dataclass(frozen=True)
class RuntimeConfig:
    """The whole configuration of `cavatar run`."""

    device: DeviceSection = field(default_factory=DeviceSection)
    source: SourceSection = field(default_factory=SourceSection)
    calibration: CalibrationSection = field(default_factory=CalibrationSection)
    model: ModelSection = field(default_factory=ModelSection)
    scene: SceneConfig = field(default_factory=SceneConfig)
    sinks: SinksSection = field(default_factory=SinksSection)
    runtime: RuntimeSection = field(default_factory=RuntimeSection)
    events: FallConfig = field(default_factory=FallConfig)

    @classmethod
    def from_dict(cls, values: Any, source: str = "configuration") -> "RuntimeConfig":
        """Build from a parsed TOML mapping; ConfigError listing every problem."""
        problems: list[str] = []
        if not isinstance(values, dict):
            raise ConfigError([f"the configuration must be a table of sections, got {type(values).__name__}"], source)
        _unknown(values, SECTIONS, "", problems)
        built: dict[str, Any] = {}
        for name, kind in SECTIONS.items():
            raw = values.get(name, {})
            if not isinstance(raw, dict):
                problems.append(f"{name}: must be a table ([{name}]), got {_type_name(raw)}")
                continue
            if name == "scene":
                built[name] = _delegated(SceneConfig, raw, "scene", problems)
            else:
                built[name] = _section(kind, raw, name, problems)
        if problems:
            raise ConfigError(problems, source)
        return cls(**built)

    def with_overrides(self, *, source: str | None = None, calibration: str | None = None, bundle: str | None = None,
                       sinks: list[str] | None = None, seconds: float | None = None, device: str | None = None,
                       status_file: str | None = None) -> "RuntimeConfig":
        """A copy with the given values replaced (the CLI flags); checked like the file. None = keep."""
        d = self.to_dict()
        for section, key, value in (("source", "url", source), ("calibration", "file", calibration),
                                    ("model", "bundle", bundle), ("sinks", "urls", sinks),
                                    ("runtime", "seconds", seconds), ("device", "id", device),
                                    ("runtime", "status_file", status_file)):
            if value is not None:
                d[section][key] = list(value) if isinstance(value, (list, tuple)) else value
        return RuntimeConfig.from_dict(d, "command line")

    def to_dict(self) -> dict[str, Any]:
        """Plain mapping (TOML types; None values left out, as TOML has no null)."""
        out: dict[str, Any] = {}
        for name in SECTIONS:
            out[name] = _plain(getattr(self, name))
        return out

    # -- derived ----------------------------------------------------------------------------------
    def bundle_path(self) -> Path:
        return Path(self.model.bundle) if self.model.bundle else default_bundle_path()

    def status_path(self) -> Path:
        return Path(self.runtime.status_file)

    def output_dir(self) -> Path:
        """Where run artefacts beside the output go (the automatic sim calibration): the status file's folder."""
        return self.status_path().parent


def load_config(path: str | Path) -> RuntimeConfig:
    """Read and check a TOML file; ConfigError (every problem) when it is missing, not TOML, or wrong."""
    p = Path(path)
    try:
        text = p.read_text(encoding="utf-8")
    except FileNotFoundError:
        raise ConfigError(["no such file; write one from `cavatar config show --toml` or deploy/cavatar.example.toml"],
                          str(p)) from None
    except (OSError, UnicodeDecodeError) as exc:
        raise ConfigError([f"cannot read it: {exc}"], str(p)) from None
    try:
        values = tomllib.loads(text)
    except tomllib.TOMLDecodeError as exc:
        raise ConfigError([f"not valid TOML: {exc}"], str(p)) from None
    except RecursionError:  # a hostile file nested thousands deep
        raise ConfigError(["nested too deeply to be a configuration"], str(p)) from None
    return RuntimeConfig.from_dict(values, str(p))


# ----------------------------------------------------------------------------- building sections


def _type_name(v: Any) -> str:
    return {bool: "a boolean", int: "an integer", float: "a number", str: "a string", list: "an array",
            dict: "a table"}.get(type(v), type(v).__name__)


def _unknown(values: dict, known: Any, prefix: str, problems: list[str]) -> None:
    for key in values:
        if key in known:
            continue
        path = f"{prefix}{key}"
        if SECRET_KEY.search(str(key)):
            problems.append(f"{path}: secrets never go in the configuration file; set the broker password in the "
                            "environment variable CAVATAR_MQTT_PASSWORD (or the one a sink URL names with password_env=)")
        else:
            where = f"[{prefix[:-1]}]" if prefix else "the top level"
            problems.append(f"{path}: unknown key; {where} accepts: {', '.join(sorted(known))}")


def _section(kind: type, raw: dict, name: str, problems: list[str]) -> Any:
    fields = {f.name: f for f in dataclasses.fields(kind)}
    _unknown(raw, fields, f"{name}.", problems)
    kwargs: dict[str, Any] = {}
    for key, f in fields.items():
        if key not in raw:
            continue
        v = raw[key]
        path = f"{name}.{key}"
        if key == "baseline" and kind is CalibrationSection:
            if not isinstance(v, dict):
                problems.append(f"{path}: must be a table ([{path}]), got {_type_name(v)}")
            else:
                kwargs[key] = _delegated(BaselineConfig, v, path, problems)
            continue
        what, ok = expected_type(f)
        if not ok(v):
            problems.append(f"{path}: must be {what}, got {_type_name(v)} {v!r}")
            continue
        if isinstance(v, int) and not isinstance(v, bool) and "float" in str(f.type):
            v = float(v)
        check = f.metadata.get("check")
        msg = check(v) if check else None
        if msg:
            problems.append(f"{path}: {msg}")
            continue
        kwargs[key] = v
    try:
        return kind(**kwargs)
    except (TypeError, ValueError) as exc:  # only when a problem was already found for a key
        if not problems:
            problems.append(f"{name}: {exc}")
        return None


def _delegated(kind: Any, raw: dict, path: str, problems: list[str]) -> Any:
    """A section whose typed config lives in its own package: every key checked on its own, so every problem is named."""
    fields = {f.name for f in dataclasses.fields(kind)}
    _unknown(raw, fields, f"{path}.", problems)
    good: dict[str, Any] = {}
    for key in fields & set(raw):
        try:
            kind.from_dict({key: raw[key]})
            good[key] = raw[key]
        except (TypeError, ValueError) as exc:
            problems.append(f"{path}.{key}: {exc} (got {_type_name(raw[key])} {raw[key]!r})")
    try:
        return kind.from_dict(good)
    except (TypeError, ValueError) as exc:  # keys that are fine alone but not together
        problems.append(f"{path}: {exc}")
        return None


def _plain(obj: Any) -> Any:
    if dataclasses.is_dataclass(obj):
        return {f.name: _plain(getattr(obj, f.name)) for f in dataclasses.fields(obj) if getattr(obj, f.name) is not None}
    if isinstance(obj, tuple):
        return [_plain(x) for x in obj]
    if isinstance(obj, list):
        return [_plain(x) for x in obj]
    return obj


__all__ = ["ConfigError", "RuntimeConfig", "check_sink_url", "default_bundle_path", "load_config"]

"""`cavatar doctor`: is this board ready for `cavatar run`? One finding per check, each saying what to do.

    findings = diagnose("/etc/cavatar/cavatar.toml")      # list[Finding]: ok / warn / FAIL
    findings = diagnose(None, open_board=False)           # the built-in defaults; the board left closed
    print("\\n".join(f.line() for f in findings))

The checks, in order (a check that needs an earlier result it could not get is left out):

- ``python``, ``packages``: versions; every runtime dependency imports;
- ``onnxruntime``: imports, has the CPU provider; ``torch``: not required by the installed package and
  not imported by the runtime's modules (the board never needs it);
- ``config``: the file loads and validates (every problem listed); a bad configuration ends the checks;
- ``source``: serial:// the port exists and this user may read and write it; usb:// the device is
  present (pyusb) and its node accessible; replay:// the capture is readable; sim:// nothing to check;
- ``board``: serial/usb/replay opened and asked for its INFO packet (≤ ``timeout_s``), through the
  runtime's own source code; not while a `cavatar run` with this status file is alive (its status
  file names the board instead); ``open_board=False`` skips it;
- ``calibration``: present, loads, its SHA-256 verifies; ``calibration age`` against
  ``calibration.max_age_days``; ``calibration vs board``: device id, grid, ADC bits (sign and
  firmware when the board answered);
- ``model bundle``: every file's SHA-256, onnxruntime loads both graphs; ``body model``: the one the
  bundle was trained with; ``model vs carpet``: grid and pitch against the calibration and board;
- ``sink URL``: jsonl:// folder writable, free disk space (warn under 1 GB); mqtt:// broker reachable
  over TCP, then an MQTT CONNECT with the configured user and the password from the environment
  (never printed); its spool folder writable;
- ``status file``: its folder writable.

Paths are checked for the user running the doctor: run it as the service user to see what the
service sees (docs/install-pi.md). Folders systemd creates for the service at start
(``/run/cavatar``, ``/var/lib/cavatar``) are fine when missing.
"""

from __future__ import annotations

import importlib
import importlib.metadata
import importlib.util
import os
import shutil
import socket
import sys
import time
from dataclasses import asdict, dataclass
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Mapping

OK, WARN, FAIL = "ok", "warn", "FAIL"
SCHEMA = "cavatar.doctor/1"
SERVICE_USER = "cavatar"
SERVICE_CONFIG = "/etc/cavatar/cavatar.toml"
SERVICE_DIRS = {"/run/cavatar": "RuntimeDirectory=cavatar", "/var/lib/cavatar": "StateDirectory=cavatar"}
MIN_FREE_BYTES = 1_000_000_000
RUNTIME_MODULES = ("edge.runtime.loop", "edge.infer", "edge.sinks.mqtt", "edge.sinks.jsonl",
                   "edge.sources.serial_port", "edge.sources.usb_bulk")
DEPENDENCIES = (("numpy", "numpy"), ("scipy", "scipy"), ("pyserial", "serial"), ("pyusb", "usb"),
                ("smbus2", "smbus2"), ("paho-mqtt", "paho.mqtt.client"))


@dataclass(frozen=True)
class Finding:
    """One check's outcome: ``level`` is ok, warn or FAIL; a non-ok ``message`` says what to do."""

    check: str
    level: str
    message: str

    def line(self) -> str:
        return f"{self.level:<4}  {self.check}: {self.message}"


@dataclass
class Board:
    """What is known of the carpet's readout board, and from where (INFO packet, status file, sim:// URL)."""

    origin: str
    device_id: str | None = None
    rows: int | None = None
    cols: int | None = None
    adc_bits: int | None = None
    info: Any = None  # the INFO packet itself, when the board answered


def diagnose(config_path: str | Path | None, *, open_board: bool = True, timeout_s: float = 2.0,
             env: Mapping[str, str] | None = None, now: datetime | None = None, usb_backend: Any = None,
             config_reason: str = "--config") -> list[Finding]:
    """Every check (see the module doc) for the configuration at ``config_path`` (None: the built-in defaults);
    ``config_reason``: why that one (edge.runtime.config_choice), said in the config finding."""
    env = os.environ if env is None else env
    now = now or datetime.now(timezone.utc)
    out = check_python() + check_onnxruntime()
    cfg, finding = load(config_path, config_reason)
    out.append(finding)
    if cfg is None:
        return out
    board, findings = check_source(cfg, open_board, timeout_s, usb_backend)
    out += findings
    cal, findings = check_calibration(cfg, board, now)
    out += findings
    out += check_model(cfg, cal, board)
    for url in cfg.sinks.urls:
        out += check_sink(url, env, timeout_s)
    out.append(check_status_file(cfg))
    return out


def exit_code(findings: list[Finding]) -> int:
    return 1 if any(f.level == FAIL for f in findings) else 0


def as_json(findings: list[Finding], config_path: str | Path | None) -> dict[str, Any]:
    counts = {level: sum(f.level == level for f in findings) for level in (OK, WARN, FAIL)}
    return {"schema": SCHEMA, "config": str(config_path) if config_path else None, "user": _user(),
            "ok": counts[FAIL] == 0, "counts": counts, "findings": [asdict(f) for f in findings]}


# ----------------------------------------------------------------------------- environment


def check_python() -> list[Finding]:
    from edge import __version__

    v = sys.version_info
    out = [Finding("python", OK if v >= (3, 11) else FAIL,
                   f"Python {v.major}.{v.minor}.{v.micro} ({sys.executable})" if v >= (3, 11) else
                   f"Python {v.major}.{v.minor} ({sys.executable}); CAvatar Edge needs 3.11 or newer: install it "
                   "(Debian bookworm has 3.11) and reinstall with deploy/install.sh")]
    found, missing = [f"cavatar-edge {__version__}"], []
    for dist, module in DEPENDENCIES:
        try:
            importlib.import_module(module)
            found.append(f"{dist} {_version(dist)}")
        except ImportError as exc:
            missing.append(f"{dist} ({exc})")
    if missing:
        out.append(Finding("packages", FAIL, f"cannot import {', '.join(missing)}: reinstall the package "
                           "(sudo deploy/install.sh, or pip install cavatar-edge in this environment)"))
    else:
        out.append(Finding("packages", OK, ", ".join(found)))
    return out


def check_onnxruntime() -> list[Finding]:
    out = []
    try:
        import onnxruntime as ort

        providers = ort.get_available_providers()
        if "CPUExecutionProvider" in providers:
            out.append(Finding("onnxruntime", OK, f"{ort.__version__}, providers {', '.join(providers)}"))
        else:
            out.append(Finding("onnxruntime", FAIL, f"{ort.__version__} has no CPUExecutionProvider ({providers}): "
                               "install the PyPI wheel (pip install --force-reinstall onnxruntime)"))
    except ImportError as exc:
        out.append(Finding("onnxruntime", FAIL, f"cannot import it ({exc}): pip install onnxruntime (a 64-bit "
                           "system is needed: onnxruntime has no 32-bit ARM wheels)"))
    requires = [r for r in (_requires("cavatar-edge") or []) if r.split(";")[0].strip().startswith("torch")
                and "extra" not in r]
    loaded_before = "torch" in sys.modules
    failed = []
    for name in RUNTIME_MODULES:
        try:
            importlib.import_module(name)
        except ImportError as exc:
            failed.append(f"{name} ({exc})")
    try:
        installed = importlib.util.find_spec("torch") is not None
    except ImportError:  # an import hook that refuses torch outright
        installed = False
    if failed:
        out.append(Finding("runtime modules", FAIL, f"cannot import {'; '.join(failed)}: reinstall the package "
                           "(sudo deploy/install.sh)"))
    if requires:
        out.append(Finding("torch", FAIL, f"the installed package requires torch ({'; '.join(requires)}), which only "
                           "the export extra needs: reinstall it from an intact release"))
    elif any("torch" in f for f in failed) or (not loaded_before and "torch" in sys.modules):
        out.append(Finding("torch", FAIL, "the runtime's modules import torch, which the board never has: a bug, "
                           "report it with the output of `cavatar doctor --json`"))
    else:
        out.append(Finding("torch", OK, "not required" + (" (installed here, unused by the runtime)" if installed
                                                          else " (not installed)")))
    return out


def load(config_path: str | Path | None, reason: str = "--config") -> tuple[Any, Finding]:
    """(configuration or None, the ``config`` finding)."""
    from edge.runtime.config import ConfigError, RuntimeConfig, load_config

    if config_path is None:
        cfg = RuntimeConfig()
        if Path(SERVICE_CONFIG).exists():
            return cfg, Finding("config", WARN, "no --config: checking the built-in defaults of `cavatar run`, but the "
                                f"service reads {SERVICE_CONFIG}: run `cavatar doctor --config {SERVICE_CONFIG}`")
        return cfg, Finding("config", OK, "no --config: the built-in defaults of `cavatar run` (cavatar config show)")
    try:
        cfg = load_config(config_path)
    except ConfigError as exc:
        return None, Finding("config", FAIL, f"{exc.source}: {'; '.join(exc.problems)}. Fix it (`cavatar config "
                             "validate FILE`, `cavatar config show` describes every key), then run doctor again: "
                             "the other checks need a valid configuration")
    return cfg, Finding("config", OK, f"{config_path} ({reason}) is valid (device {cfg.device.id})")


# ----------------------------------------------------------------------------- source and board


def check_source(cfg: Any, open_board: bool, timeout_s: float,
                 usb_backend: Any = None) -> tuple[Board | None, list[Finding]]:
    from edge.sinks import redact

    url = cfg.source.url
    scheme, _, _ = url.partition("://")
    shown = redact(url)
    if scheme == "sim":
        o = _sim_options(url)
        board = Board(f"the options of {shown}", f"sim-{o['seed']}", o["grid"], o["grid"], o["bits"])
        return board, [Finding("source", OK, f"{shown}: the virtual carpet, no hardware to check")]
    if scheme == "serial":
        finding = _check_serial_port(url)
    elif scheme == "usb":
        finding = _check_usb_device(url, usb_backend)
    elif scheme == "replay":
        finding = _check_replay(url)
    else:
        return None, [Finding("source", FAIL, f"{shown}: unknown scheme; use serial://, usb://, replay:// or sim://")]
    out = [finding]
    if finding.level == FAIL:
        return None, out
    if not open_board:
        out.append(Finding("board", OK, "not opened (--no-open): the calibration is not compared with the board"))
        return None, out
    status = cfg.status_path()
    if status.exists() and not os.access(status, os.R_OK):  # a runtime may hold the board: never probe blindly
        out.append(Finding("board", WARN, f"not opened: {status} ({_owner(status)}) is not readable by user {_user()}, "
                           "so whether `cavatar run` is using the board cannot be told; run doctor as the service "
                           "runs (docs/install-pi.md), or stop the service (sudo systemctl stop cavatar)"))
        return None, out
    running = _running_runtime(status)
    if running is not None:
        pid, b = running
        board = Board(f"the status file of `cavatar run` (pid {pid})", b.get("device_id"), b.get("rows"), b.get("cols"),
                      b.get("adc_bits")) if b else None
        out.append(Finding("board", OK, f"not opened: `cavatar run` (pid {pid}) is using it"
                           + (f"; it reports board {b.get('device_id')} {b.get('rows')}×{b.get('cols')}, "
                              f"{b.get('adc_bits')}-bit" if b else "")
                           + " (stop the service to let doctor probe the board itself)"))
        return board, out
    board, finding = _probe_board(url, timeout_s, usb_backend)
    return board, out + [finding]


def _check_serial_port(url: str) -> Finding:
    from edge.sources.serial_port import available_ports, open_link

    path = open_link(url).port
    if not os.path.exists(path):
        ports = ", ".join(available_ports()) or "none"
        return Finding("source", FAIL, f"serial port {path} does not exist (ports found: {ports}). Plug the board in "
                       "and run `cavatar devices`; with deploy/99-cavatar.rules installed it appears as "
                       "/dev/cavatar-carpet (serial:///dev/cavatar-carpet)")
    real = os.path.realpath(path)
    where = path if real == path else f"{path} → {real}"
    if not os.access(path, os.R_OK | os.W_OK):
        return Finding("source", FAIL, f"{where} ({_owner(real)}) is not readable and writable by user {_user()}: "
                       f"{_group_hint(real)}; install deploy/99-cavatar.rules, which gives the board to the group "
                       "dialout (mode 0660), and run as a member of it (the service user is)")
    return Finding("source", OK, f"{where} exists, readable and writable by user {_user()}")


def _check_usb_device(url: str, backend: Any) -> Finding:
    from edge.sources.usb_bulk import list_devices, open_link

    link = open_link(url)
    vid_pid = f"{link.vid:04x}:{link.pid:04x}"
    try:
        import usb.core

        devices = list(usb.core.find(find_all=True, idVendor=link.vid, idProduct=link.pid, backend=backend))
    except ImportError as exc:
        return Finding("source", FAIL, f"pyusb is not importable ({exc}): reinstall the package")
    except usb.core.NoBackendError:
        return Finding("source", FAIL, "pyusb found no libusb backend: install it (sudo apt-get install libusb-1.0-0)")
    if not devices:
        present = ", ".join(list_devices(backend)) or "none"
        return Finding("source", FAIL, f"no USB device {vid_pid} (USB devices present: {present}). Plug the board in "
                       "and run `cavatar devices` (or lsusb); another VID:PID goes in the URL, usb://VID:PID")
    nodes = [f"/dev/bus/usb/{d.bus:03d}/{d.address:03d}" for d in devices if d.bus is not None and d.address is not None]
    blocked = [n for n in nodes if os.path.exists(n) and not os.access(n, os.R_OK | os.W_OK)]
    if blocked:
        return Finding("source", FAIL, f"USB device {vid_pid} at {blocked[0]} ({_owner(blocked[0])}) is not readable and "
                       f"writable by user {_user()}: {_group_hint(blocked[0])}; install deploy/99-cavatar.rules, which "
                       "gives the board to the group plugdev (mode 0660), and run as a member of it (the service user is)")
    serial = f"; serial={link.serial} is checked when the board is opened" if link.serial else ""
    return Finding("source", OK, f"USB device {vid_pid} present ({len(devices)} found"
                   + (f", {', '.join(nodes)}" if nodes else "") + f"){serial}")


def _check_replay(url: str) -> Finding:
    from edge.sources.replay import FORM, OPTIONS, SCHEME
    from edge.urls import parse_url

    location, _ = parse_url(url, SCHEME, FORM, OPTIONS)
    if not os.path.isfile(location):
        return Finding("source", FAIL, f"no capture {location}: record one with "
                       "`cavatar record --source URL --frames N FILE`")
    if not os.access(location, os.R_OK):
        return Finding("source", FAIL, f"{location} ({_owner(location)}) is not readable by user {_user()}")
    return Finding("source", OK, f"capture {location} is readable")


def _probe_board(url: str, timeout_s: float, usb_backend: Any) -> tuple[Board | None, Finding]:
    """Open the source as the runtime does, wait ≤ timeout_s for its INFO packet, close it."""
    from edge.sources import SourceError, open_source
    from firmware_protocol.codec import ProtocolError

    try:
        source = open_source(url, usb_backend=usb_backend, handshake_timeout_s=timeout_s)
        source.start()
    except (SourceError, ProtocolError, OSError, ValueError) as exc:
        return None, Finding("board", FAIL, f"no INFO from the board: {exc}")
    try:
        info = source.info
    finally:
        source.stop()
    fw = f"{info.fw_major}.{info.fw_minor}.{info.fw_patch}"
    board = Board("the board's INFO packet", info.device_id, int(info.rows), int(info.cols), int(info.adc_bits), info)
    return board, Finding("board", OK, f"{info.device_id} answered: {info.rows}×{info.cols}, {info.adc_bits}-bit, "
                          f"{info.rate_mhz / 1000:g} Hz, firmware {fw}, protocol v{info.protocol_version}")


def _running_runtime(path: Path) -> tuple[int, dict[str, Any]] | None:
    """(pid, board) of a live `cavatar run` that writes the status file ``path``, or None."""
    from edge.runtime.status import StatusFileError, read_status

    try:
        status = read_status(path)
    except StatusFileError:
        return None
    pid = status.get("pid")
    if status.get("state") not in ("running", "stopping") or not isinstance(pid, int) or not _alive(pid):
        return None
    return pid, (status.get("source") or {}).get("board") or {}


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process (the service's): alive
        return True
    return pid != os.getpid()


# ----------------------------------------------------------------------------- calibration


def check_calibration(cfg: Any, board: Board | None, now: datetime) -> tuple[Any, list[Finding]]:
    from calibration.file import Calibration, CalibrationError
    from edge.runtime.carpet_calibration import choose_calibration, sim_calibration_path
    from edge.runtime.errors import SetupError

    url = cfg.source.url
    path = Path(cfg.calibration.file) if cfg.calibration.file else None
    automatic = ""
    if path is None:
        if not url.startswith("sim://"):
            try:
                choose_calibration("", url, cfg.output_dir(), say=lambda text: None)
            except SetupError as exc:  # a real carpet without a calibration: the runtime's own refusal
                return None, [Finding("calibration", FAIL, f"[calibration] file is empty. {exc}")]
        o = _sim_options(url)
        if o["world"] != "bodies":
            return None, [Finding("calibration", FAIL, f"[calibration] file is empty and {url} is the footsteps world, "
                                  "which `cavatar run` cannot calibrate by itself: use world=bodies or set "
                                  "[calibration] file")]
        path = sim_calibration_path(cfg.output_dir(), o["seed"], o["grid"])
        if not path.exists():
            return None, [Finding("calibration", OK, f"none configured: `cavatar run` calibrates the virtual carpet "
                                  f"at start (≈10 s at 96×96) and saves it as {path}")]
        automatic = " (the virtual carpet's automatic calibration)"
    if not path.exists():
        return None, [Finding("calibration", FAIL, f"no calibration file {path}. Calibrate this carpet: `cavatar "
                              f"calibrate --source '{url}' --mass KG --out calibration.npz` (docs/calibration.md), then "
                              f"put the file at {path} or set [calibration] file")]
    if not os.access(path, os.R_OK):
        return None, [_not_yours("calibration", path, "readable", f"sudo chown {SERVICE_USER}:{SERVICE_USER} {path}; "
                                 f"sudo chmod 0640 {path}")]
    try:
        cal = Calibration.load(path)
    except CalibrationError as exc:
        return None, [Finding("calibration", FAIL, f"{exc}")]
    d = cal.device
    out = [Finding("calibration", OK, f"{path}{automatic}: carpet {d.get('device_id')}, {d.get('rows')}×{d.get('cols')}, "
                   f"{d.get('adc_bits')}-bit, pitch {cal.pitch_m * 1e3:.2f} mm, created {cal.created}, "
                   f"SHA-256 {cal.sha256[:12]} verified")]
    age_days = cal.age_s(now) / 86400.0
    max_days = cfg.calibration.max_age_days
    if age_days < -1.0:
        out.append(Finding("calibration age", WARN, f"created {-age_days:.0f} days in the future: this board's clock "
                           "is wrong (a Raspberry Pi has no battery clock before the 5: check `timedatectl`, NTP)"))
    elif age_days > max_days:
        out.append(Finding("calibration age", WARN, f"{age_days:.0f} days old, more than calibration.max_age_days "
                           f"({max_days:g}): the carpet is due for recalibration (`cavatar calibrate`, "
                           "docs/calibration.md)"))
    else:
        out.append(Finding("calibration age", OK, f"{max(age_days, 0.0):.1f} days old (due after {max_days:g})"))
    if board is not None:
        out.append(_calibration_vs_board(cal, board))
    return cal, out


def _calibration_vs_board(cal: Any, board: Board) -> Finding:
    from calibration.file import CalibrationError

    if board.info is not None:
        try:
            cal.check_device(board.info)
        except CalibrationError as exc:
            return Finding("calibration vs board", FAIL, str(exc))
        return Finding("calibration vs board", OK, f"matches {board.origin} (device id, grid, ADC bits, sign, firmware)")
    d = cal.device
    known = {key: getattr(board, key) for key in ("device_id", "rows", "cols", "adc_bits") if getattr(board, key) is not None}
    diffs = [f"{key} {d.get(key)!r} in the file, {theirs!r} in {board.origin}"
             for key, theirs in known.items() if d.get(key) != theirs]
    if diffs:
        return Finding("calibration vs board", FAIL, "this calibration belongs to another carpet: " + "; ".join(diffs)
                       + ". Run `cavatar calibrate` on this carpet (or set [calibration] file to the one made for it)")
    return Finding("calibration vs board", OK, f"matches {board.origin} (device id, grid, ADC bits)")


# ----------------------------------------------------------------------------- model


def check_model(cfg: Any, cal: Any, board: Board | None) -> list[Finding]:
    from edge.infer.bundle import BundleError, ModelBundle, check_body, verify

    folder = cfg.bundle_path()
    fix = ("reinstall the package for the shipped bundle (sudo deploy/install.sh), or point [model] bundle at an "
           "intact bundle folder written by `cavatar bundle`")
    try:
        manifest = verify(folder)
    except BundleError as exc:
        return [Finding("model bundle", FAIL, f"{exc}: {fix}")]
    except (KeyError, TypeError, ValueError) as exc:
        return [Finding("model bundle", FAIL, f"{folder}/manifest.json is incomplete ({exc!r}): {fix}")]
    try:
        bundle = ModelBundle(folder, manifest, threads=cfg.model.threads)
    except Exception as exc:  # onnxruntime raises its own exception types for a graph it cannot load
        return [Finding("model bundle", FAIL, f"onnxruntime cannot load {folder}: {exc}: {fix}")]
    out = [Finding("model bundle", OK, f"{bundle.version} ({folder}): {bundle.grid[0]}×{bundle.grid[1]}, window "
                   f"{bundle.window}, every file's SHA-256 verified, onnxruntime loads both graphs")]
    try:
        check_body(manifest, folder)
        body = manifest.get("body_model") or {}
        out.append(Finding("body model", OK, f"{body.get('name')} (SHA-256 {str(body.get('sha256'))[:12]}), the one "
                           "the bundle was trained with"))
    except BundleError as exc:
        out.append(Finding("body model", FAIL, f"{exc}: reinstall the package (its body model) or use a bundle "
                           "trained with this body model"))
    grids = []  # (what, (rows, cols)) the bundle's grid must equal
    if cal is not None:
        grids.append(("the calibration", tuple(int(n) for n in cal.shape)))
    if board is not None and board.rows is not None:
        grids.append((board.origin, (int(board.rows), int(board.cols))))
    problems = [f"the bundle is for a {bundle.grid[0]}×{bundle.grid[1]} carpet, {what} says {g[0]}×{g[1]}"
                for what, g in grids if g != tuple(bundle.grid)]
    against = [what for what, _ in grids]
    if cal is not None and abs(cal.pitch_m - bundle.pitch_m) > 0.05 * bundle.pitch_m:
        problems.append(f"the carpet's pitch is {cal.pitch_m * 1e3:.2f} mm (calibration), the bundle was trained at "
                        f"{bundle.pitch_m * 1e3:.2f} mm")
    if problems:
        out.append(Finding("model vs carpet", FAIL, "; ".join(problems) + ": use a bundle exported for this carpet "
                           "([model] bundle), or the calibration made for it"))
    elif against:
        out.append(Finding("model vs carpet", OK, f"grid {bundle.grid[0]}×{bundle.grid[1]} and pitch "
                           f"{bundle.pitch_m * 1e3:.2f} mm fit {' and '.join(against)}"))
    return out


# ----------------------------------------------------------------------------- sinks and files


def check_sink(url: str, env: Mapping[str, str], timeout_s: float) -> list[Finding]:
    from edge.sinks import redact

    name = f"sink {redact(url)}"
    if url.startswith("jsonl:-") or url.startswith("jsonl://-"):
        return [Finding(name, OK, "standard output (under systemd: the journal)")]
    if url.startswith("jsonl:"):
        from urllib.parse import unquote

        from edge.sinks.base import parse_sink_url
        from edge.sinks.jsonl import FORM, OPTIONS, SCHEME

        location, _ = parse_sink_url(url, SCHEME, FORM, OPTIONS)
        return [_writable_file(name, Path(unquote(location)), free_space=True)]
    if url.startswith("mqtt:"):
        return _check_mqtt(name, url, env, timeout_s)
    return [Finding(name, FAIL, "unknown sink scheme; use jsonl:// or mqtt://")]


def _check_mqtt(name: str, url: str, env: Mapping[str, str], timeout_s: float) -> list[Finding]:
    import ssl

    from edge.sinks.mqtt import parse

    c = parse(url)
    out = []
    if c.spool:
        out.append(_writable_file(f"{name} spool", Path(c.spool) / "segment", free_space=True, folder_only=True))
    where = f"{c.host}:{c.port}"
    try:
        socket.create_connection((c.host, c.port), timeout=timeout_s).close()
    except socket.gaierror as exc:
        return [Finding(name, FAIL, f"cannot resolve the broker host {c.host!r} ({exc.strerror}): check the host in "
                        "the URL, DNS or /etc/hosts")] + out
    except OSError as exc:
        return [Finding(name, FAIL, f"broker {where} not reachable over TCP within {timeout_s:g} s "
                        f"({exc.strerror or exc}): is the broker running (`systemctl status mosquitto` on its host), "
                        "the port right, a firewall in the way?")] + out
    import paho.mqtt.client as mqtt

    client = mqtt.Client(mqtt.CallbackAPIVersion.VERSION2, client_id=f"cavatar-doctor-{os.getpid()}",
                         protocol=mqtt.MQTTv311, clean_session=True)
    client.connect_timeout = timeout_s
    password = env.get(c.password_env)
    who = f"user {c.username!r}" if c.username else "anonymous"
    if c.username:
        client.username_pw_set(c.username, password)
    if c.tls:
        try:
            ctx = ssl.create_default_context(cafile=c.ca or None)
            if c.cert:
                ctx.load_cert_chain(c.cert, c.key or None)
        except (ssl.SSLError, OSError) as exc:
            return [Finding(name, FAIL, f"TLS files unusable ({exc}): check ca=, cert=, key= in the URL")] + out
        client.tls_set_context(ctx)
    answer: dict[str, Any] = {}
    client.on_connect = lambda client, userdata, flags, reason_code, properties: answer.setdefault("rc", reason_code)
    try:
        client.connect(c.host, c.port, keepalive=max(5, int(timeout_s * 2)))
        deadline = time.monotonic() + timeout_s
        while "rc" not in answer and time.monotonic() < deadline:
            client.loop(timeout=0.05)
    except (OSError, ssl.SSLError) as exc:
        hint = ": check tls=, ca= and the broker's certificate" if c.tls else " (a TLS port needs tls=1)"
        return [Finding(name, FAIL, f"MQTT connection to {where} failed ({exc}){hint}")] + out
    finally:
        try:
            client.disconnect()
        except Exception:  # the connection may already be gone; nothing to release then
            pass
    rc = answer.get("rc")
    if rc is None:
        return [Finding(name, FAIL, f"{where} accepts TCP but sent no MQTT CONNACK within {timeout_s:g} s: is it an "
                        "MQTT port? (a TLS listener needs tls=1; 8883 is the usual TLS port)")] + out
    if rc.is_failure:
        if c.username and str(rc) in ("Bad user name or password", "Not authorized"):
            state = "set" if password else "NOT set"
            fix = (f"check the user in the URL and the password in ${c.password_env} ({state} here; the service "
                   "reads it from /etc/cavatar/cavatar.env)")
        elif str(rc) in ("Bad user name or password", "Not authorized"):
            fix = (f"the broker wants a login: put the user in the URL (mqtt://USER@{where}/...) and the password in "
                   f"${c.password_env}")
        else:
            fix = "see the broker's log"
        return [Finding(name, FAIL, f"broker {where} refused the MQTT login of {who}: {rc}; {fix}")] + out
    note, level = "", OK
    if c.username and password is None:
        note = f" (without a password: ${c.password_env} is not set here)"
    elif not c.username and password:
        level, note = WARN, (f"; ${c.password_env} is set but the URL names no user, so it is unused: "
                             "mqtt://USER@host/... to log in")
    return [Finding(name, level, f"broker {where} reachable, MQTT login accepted ({who}{', TLS' if c.tls else ''})"
                    f"{note}")] + out


def check_status_file(cfg: Any) -> Finding:
    return _writable_file("status file", cfg.status_path(), free_space=False)


def _writable_file(check: str, path: Path, free_space: bool, folder_only: bool = False) -> Finding:
    """Can this user create or rewrite ``path`` (its folder created as needed)? Free space when asked."""
    folder = path.parent
    shown = folder if folder_only else path
    rel = "" if path.is_absolute() else f" (relative to {os.getcwd()}; the service's is /var/lib/cavatar)"
    existing = folder  # the nearest folder that exists: the runtime creates the rest
    while not existing.exists() and existing != existing.parent:
        existing = existing.parent
    if not existing.is_dir():
        return Finding(check, FAIL, f"{existing} is not a folder, so {shown} cannot be written{rel}")
    service_dir = next((d for d in SERVICE_DIRS if _under(folder.absolute(), Path(d))), None)
    if service_dir and not Path(service_dir).exists():
        return Finding(check, OK, f"{shown}: systemd creates {service_dir} for the service when it starts "
                       f"({SERVICE_DIRS[service_dir]})")
    blocked = None
    if not os.access(existing, os.W_OK | os.X_OK):
        blocked = existing
    elif not folder_only and path.exists() and not os.access(path, os.W_OK):
        blocked = path
    if blocked is not None:
        return _not_yours(check, blocked, "writable", f"give the user write access (chown/chmod) or choose a writable "
                          f"place in the configuration{rel}")
    made = "" if folder.exists() else f" ({folder} will be created)"
    if not free_space:
        return Finding(check, OK, f"{shown} writable{made}{rel}")
    free = shutil.disk_usage(existing).free
    if free < MIN_FREE_BYTES:
        return Finding(check, WARN, f"{shown} writable{made}, but only {free / 1e6:.0f} MB free there: free space, or "
                       "lower rotate_mb / keep= (jsonl) or spool_mb= (mqtt)")
    return Finding(check, OK, f"{shown} writable{made}, {free / 1e9:.1f} GB free{rel}")


# ----------------------------------------------------------------------------- helpers


def _sim_options(url: str) -> dict[str, Any]:
    from edge.sources import source_options

    return source_options(url)


def _under(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents


def _user() -> str:
    import pwd

    try:
        return pwd.getpwuid(os.geteuid()).pw_name
    except KeyError:
        return str(os.geteuid())


def _owner(path: str | Path) -> str:
    import grp
    import pwd

    try:
        st = os.stat(path)
    except OSError as exc:
        return f"unreadable: {exc.strerror}"
    try:
        user = pwd.getpwuid(st.st_uid).pw_name
    except KeyError:
        user = str(st.st_uid)
    try:
        group = grp.getgrgid(st.st_gid).gr_name
    except KeyError:
        group = str(st.st_gid)
    return f"{user}:{group}, mode {st.st_mode & 0o777:04o}"


def _not_yours(check: str, path: str | Path, how: str, fix: str) -> Finding:
    """FAIL: ``path`` is not ``how`` (readable / writable) by this user; only a warning when it is the service user's."""
    owner = _owner(path)
    if _user() != SERVICE_USER and owner.startswith(f"{SERVICE_USER}:"):
        return Finding(check, WARN, f"{path} ({owner}) is not {how} by user {_user()}, but belongs to the service user "
                       f"{SERVICE_USER}: run doctor as the service runs (docs/install-pi.md) to check it")
    return Finding(check, FAIL, f"{path} ({owner}) is not {how} by user {_user()}: {fix}")


def _group_hint(path: str | Path) -> str:
    import grp

    try:
        group = grp.getgrgid(os.stat(path).st_gid).gr_name
    except (KeyError, OSError):
        group = "root"
    if group == "root":
        return "it is root's alone"
    return f"add the user to the group {group} (sudo usermod -aG {group} {_user()}, then log in again)"


def _version(dist: str) -> str:
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return "(version unknown)"


def _requires(dist: str) -> list[str] | None:
    try:
        return importlib.metadata.requires(dist)
    except importlib.metadata.PackageNotFoundError:
        return None


__all__ = ["FAIL", "Finding", "OK", "WARN", "as_json", "diagnose", "exit_code"]

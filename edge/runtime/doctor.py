"""`cavatar doctor`: is this board ready for `cavatar run`? One finding per check, each saying what to do.

    findings = diagnose("/etc/cavatar/cavatar.toml")      # list[Finding]: ok / warn / FAIL
    findings = diagnose(None, open_board=False)           # the built-in defaults; the board left closed
    print("\\n".join(f.line() for f in findings))

The checks, in order (a check that needs an earlier result it could not get is left out):

- ``python``, ``packages``, ``onnxruntime``, ``torch``: the installation (edge.runtime.install_check);
- ``config``: the file loads and validates (every problem listed); a bad configuration ends the checks;
- ``source``: the source scheme's own ``check`` (edge.sources: serial:// the port exists and this user may
  read and write it; usb:// the device is present and its node accessible; replay:// the capture is
  readable; a virtual carpet such as sim:// nothing, its board follows from the URL's options);
- ``board``: a board not known from the URL is opened and asked for its INFO packet (≤ ``timeout_s``),
  through the runtime's own source code (edge.sources.probe); not while a `cavatar run` with this status
  file is alive (its status file names the board instead); ``open_board=False`` skips it;
- ``calibration``: present, loads, its SHA-256 verifies; ``calibration age`` against
  ``calibration.max_age_days``; ``calibration vs board``: device id, grid, ADC bits (sign and
  firmware when the board answered);
- ``model bundle``: every file's SHA-256, onnxruntime loads both graphs; ``body model``: the one the
  bundle was trained with; ``model vs carpet``: grid and pitch against the calibration and board;
- ``sink URL``: each sink scheme's own ``check`` (edge.sinks: jsonl:// folder writable, free disk space;
  mqtt:// broker reachable, the login accepted, its spool folder writable);
- ``status file``: its folder writable.

Each scheme's check lives in its scheme module and is reached through the scheme registry
(edge.urls.Schemes); the findings and the shared access checks are edge.health's.

Paths are checked for the user running the doctor: run it as the service user to see what the
service sees (docs/install-pi.md). Folders systemd creates for the service at start
(``/run/cavatar``, ``/var/lib/cavatar``) are fine when missing.
"""

from __future__ import annotations

import os
from dataclasses import asdict
from datetime import datetime, timezone
from pathlib import Path
from typing import Any, Mapping

from edge.health import (
    FAIL,
    OK,
    SERVICE_USER,
    WARN,
    Board,
    CheckContext,
    Finding,
    not_yours,
    owner,
    user,
    writable_file,
)
from edge.runtime.install_check import check_onnxruntime, check_python

SCHEMA = "cavatar.doctor/1"
SERVICE_CONFIG = "/etc/cavatar/cavatar.toml"


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
    ctx = CheckContext(timeout_s, env, usb_backend)
    board, findings = check_source(cfg, open_board, ctx)
    out += findings
    cal, findings = check_calibration(cfg, board, now)
    out += findings
    out += check_model(cfg, cal, board)
    for url in cfg.sinks.urls:
        out += check_sink(url, ctx)
    out.append(check_status_file(cfg))
    return out


def exit_code(findings: list[Finding]) -> int:
    return 1 if any(f.level == FAIL for f in findings) else 0


def as_json(findings: list[Finding], config_path: str | Path | None) -> dict[str, Any]:
    counts = {level: sum(f.level == level for f in findings) for level in (OK, WARN, FAIL)}
    return {"schema": SCHEMA, "config": str(config_path) if config_path else None, "user": user(),
            "ok": counts[FAIL] == 0, "counts": counts, "findings": [asdict(f) for f in findings]}


# ----------------------------------------------------------------------------- configuration


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


def check_source(cfg: Any, open_board: bool, ctx: CheckContext) -> tuple[Board | None, list[Finding]]:
    """The source scheme's own check, then the board: known from the URL, named by a running `cavatar run`, or asked."""
    from edge.sources import SourceError
    from edge.sources import check_source as check_scheme
    from edge.sources.probe import probe_board
    from edge.urls import redact

    url = cfg.source.url
    try:
        finding, board = check_scheme(url, ctx)
    except (ValueError, SourceError) as exc:
        return None, [Finding("source", FAIL, f"{redact(url)}: {exc}")]
    if finding.level == FAIL or board is not None:
        return (board if finding.level != FAIL else None), [finding]
    out = [finding]
    if not open_board:
        out.append(Finding("board", OK, "not opened (--no-open): the calibration is not compared with the board"))
        return None, out
    status = cfg.status_path()
    if status.exists() and not os.access(status, os.R_OK):  # a runtime may hold the board: never probe blindly
        out.append(Finding("board", WARN, f"not opened: {status} ({owner(status)}) is not readable by user {user()}, "
                           "so whether `cavatar run` is using the board cannot be told; run doctor as the service "
                           "runs (docs/install-pi.md), or stop the service (sudo systemctl stop cavatar)"))
        return None, out
    running = _running_runtime(status)
    if running is not None:
        board, finding = _board_in_use(*running)
        return board, out + [finding]
    board, finding = probe_board(url, ctx.timeout_s, ctx.usb_backend)
    return board, out + [finding]


def _board_in_use(pid: int, b: dict[str, Any]) -> tuple[Board | None, Finding]:
    """The board as the status file of a running `cavatar run` describes it, and the ``board`` finding."""
    board = Board(f"the status file of `cavatar run` (pid {pid})", b.get("device_id"), b.get("rows"), b.get("cols"),
                  b.get("adc_bits")) if b else None
    return board, Finding("board", OK, f"not opened: `cavatar run` (pid {pid}) is using it"
                          + (f"; it reports board {b.get('device_id')} {b.get('rows')}×{b.get('cols')}, "
                             f"{b.get('adc_bits')}-bit" if b else "")
                          + " (stop the service to let doctor probe the board itself)")


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
    """``calibration`` (present, loads, hash), ``calibration age`` and ``calibration vs board``; the calibration too."""
    from calibration.file import Calibration, CalibrationError

    url = cfg.source.url
    path = Path(cfg.calibration.file) if cfg.calibration.file else None
    automatic = ""
    if path is None:
        path, finding = _automatic_calibration(cfg, url)
        if finding is not None:
            return None, [finding]
        automatic = " (the virtual carpet's automatic calibration)"
    if not path.exists():
        return None, [Finding("calibration", FAIL, f"no calibration file {path}. Calibrate this carpet: `cavatar "
                              f"calibrate --source '{url}' --mass KG --out calibration.npz` (docs/calibration.md), then "
                              f"put the file at {path} or set [calibration] file")]
    if not os.access(path, os.R_OK):
        return None, [not_yours("calibration", path, "readable", f"sudo chown {SERVICE_USER}:{SERVICE_USER} {path}; "
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


def _automatic_calibration(cfg: Any, url: str) -> tuple[Path, Finding | None]:
    """Where `cavatar run` keeps the automatic calibration of a virtual carpet (edge.runtime.carpet_calibration), and
    the finding that ends the calibration checks (None: that file exists, check it)."""
    from edge.runtime.carpet_calibration import choose_calibration, sim_calibration_path
    from edge.runtime.errors import SetupError
    from edge.sources import SourceError, source_options, source_plugin

    try:
        plugin = source_plugin(url)
        if plugin is None:  # a real carpet without a calibration: the runtime's own refusal
            choose_calibration("", url, cfg.output_dir(), say=lambda text: None)
        o = source_options(url)
    except (SetupError, SourceError, ValueError) as exc:
        return Path(), Finding("calibration", FAIL, f"[calibration] file is empty. {exc}")
    if not hasattr(plugin.module, "calibration_sensor"):
        return Path(), Finding("calibration", FAIL, f"[calibration] file is empty and {url} offers no sensor model "
                               "that `cavatar run` could calibrate by itself: set [calibration] file")
    if o.get("world", "bodies") != "bodies":
        return Path(), Finding("calibration", FAIL, f"[calibration] file is empty and {url} is the footsteps world, "
                               "which `cavatar run` cannot calibrate by itself: use world=bodies or set "
                               "[calibration] file")
    path = sim_calibration_path(cfg.output_dir(), o["seed"], o["grid"], plugin.scheme)
    if not path.exists():
        return path, Finding("calibration", OK, f"none configured: `cavatar run` calibrates the virtual carpet at start "
                             f"(≈10 s at 96×96) and saves it as {path}")
    return path, None


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


def check_sink(url: str, ctx: CheckContext) -> list[Finding]:
    """The sink scheme's own check (edge.sinks)."""
    from edge.sinks import SinkError
    from edge.sinks import check_sink as check_scheme
    from edge.urls import redact

    try:
        return check_scheme(url, ctx)
    except (ValueError, SinkError) as exc:
        return [Finding(f"sink {redact(url)}", FAIL, str(exc))]


def check_status_file(cfg: Any) -> Finding:
    return writable_file("status file", cfg.status_path(), free_space=False)


__all__ = ["FAIL", "Finding", "OK", "WARN", "as_json", "diagnose", "exit_code"]

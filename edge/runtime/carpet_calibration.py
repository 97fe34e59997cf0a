"""Which calibration the runtime applies: the configured file, or — on the virtual carpet only — a fresh one.

- ``[calibration] file`` given: it is loaded (its SHA-256 checked) and must belong to the
  board that answered the handshake (device id, grid, ADC bits, sign, firmware); otherwise
  :class:`SetupError`.
- no file, a virtual carpet (a source plug-in with a sensor model, e.g. ``sim://``, world=bodies):
  the scripted calibration session is run on the sensor the plug-in gives for the same seed,
  grid, ADC bits and pitch, as an installer would run `cavatar calibrate --sim`, and saved as
  ``calibration-<scheme>-<seed>-<grid>.npz`` beside the status file (the output folder). A later
  run with the same output folder finds it and uses it again (if it still matches the board).
- no file, a real carpet (serial://, usb://, replay://): refused, saying how to calibrate.
"""

from __future__ import annotations

import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

from calibration.file import Calibration, CalibrationError
from cavatar_common.errors import SourceError
from edge.runtime.errors import SetupError


@dataclass
class ChosenCalibration:
    calibration: Calibration
    path: Path
    automatic: bool


def sim_calibration_path(out_dir: Path, seed: int, grid: int, scheme: str = "sim") -> Path:
    return Path(out_dir) / f"calibration-{scheme}-{seed}-{grid}.npz"


def choose_calibration(file: str, source_url: str, out_dir: Path, say: Callable[[str], None] = print) -> ChosenCalibration:
    """The calibration to apply (see the module doc), BEFORE the source starts (the virtual carpet's session
    would otherwise run while the board streams); SetupError when there is none. Check it against the board
    with :func:`check_board` once the handshake is done."""
    if file:
        path = Path(file)
        try:
            return ChosenCalibration(Calibration.load(path), path, False)
        except CalibrationError as exc:
            raise SetupError(f"calibration {path}: {exc}") from None
    from edge.sources import source_plugin

    scheme = source_url.partition("://")[0]
    try:
        plugin = source_plugin(source_url)
    except (ValueError, SourceError) as exc:
        raise SetupError(f"source {source_url}: {exc}") from None
    if plugin is None:
        raise SetupError(_how_to_calibrate(scheme, source_url))
    return _virtual_calibration(plugin, source_url, Path(out_dir), say)


def check_board(chosen: ChosenCalibration, board_info: Any) -> None:
    """SetupError unless the calibration belongs to the board that answered the handshake."""
    try:
        chosen.calibration.check_device(board_info)
    except CalibrationError as exc:
        if chosen.automatic:  # the virtual board and its own sensor model disagree: a bug, said plainly
            raise SetupError(f"the automatic calibration {chosen.path} does not fit its own virtual board: {exc}") from None
        raise SetupError(f"calibration {chosen.path}: {exc}") from None


def _how_to_calibrate(scheme: str, url: str) -> str:
    if scheme == "replay":
        how = ("calibrate from recordings of the same carpet: `cavatar calibrate --empty empty.bin --walk walk.bin "
               "--board board.bin --stance stance.bin --holdout holdout.bin --mass KG --out calibration.npz` "
               "(record each step with `cavatar record`)")
    else:
        how = ("run the guided calibration on this carpet once, as the service user who owns /var/lib/cavatar and "
               "with the service stopped (it holds the port): `sudo systemctl stop cavatar; sudo -u cavatar cavatar "
               f"calibrate --source '{url}' --mass KG --out /var/lib/cavatar/calibration.npz` (KG: the mass of the "
               "person doing the poses)")
    return (f"no calibration for {url}: a real carpet's readings mean nothing until it is calibrated. To fix it, {how}; "
            "then start again with `cavatar run --calibration /var/lib/cavatar/calibration.npz` (or set "
            "[calibration] file in the configuration).")


def _virtual_calibration(plugin: Any, url: str, out_dir: Path, say: Callable[[str], None]) -> ChosenCalibration:
    from edge.urls import parse_url

    _, opts = parse_url(url, plugin.scheme, plugin.form, plugin.options)
    try:
        sensor = plugin.calibration_sensor(opts)
    except ValueError as exc:
        raise SetupError(f"{url}: {exc}, or pass --calibration FILE.") from None
    path = sim_calibration_path(out_dir, opts["seed"], opts["grid"], plugin.scheme)
    expected = {"device_id": plugin.module.device_id(opts), "rows": opts["grid"], "cols": opts["grid"], "adc_bits": opts["bits"]}
    if path.exists():
        try:
            cal = Calibration.load(path)
            if all(cal.device.get(k) == v for k, v in expected.items()) and abs(cal.pitch_m * 1e3 - opts["pitch_mm"]) < 1e-6:
                say(f"calibration: the virtual carpet's calibration from an earlier run, {path}")
                return ChosenCalibration(cal, path, True)
            say(f"calibration: {path} is for another virtual carpet; calibrating again")
        except CalibrationError as exc:
            say(f"calibration: {path} cannot be used ({exc}); calibrating again")
    try:  # before the 20-s session, not after it
        path.parent.mkdir(parents=True, exist_ok=True)
        if not os.access(path.parent, os.W_OK):
            raise PermissionError("not writable by this user")
    except OSError as exc:
        raise SetupError(f"the virtual carpet's calibration is kept beside the status file, but {path.parent} cannot be "
                         f"written ({exc.strerror or exc}); set [runtime] status_file (--status-file) to a writable place, "
                         "or pass --calibration FILE") from None
    t0 = time.monotonic()
    cal = run_sim_session(sensor, opts["seed"], path)
    say(f"calibration: no calibration file, so the virtual carpet {expected['device_id']} was calibrated as an installer "
        f"would (scripted `cavatar calibrate --sim` session, {time.monotonic() - t0:.0f} s) → {path}")
    return ChosenCalibration(cal, path, True)


def run_sim_session(sensor: Any, seed: int, out_path: Path, mass_kg: float = 72.0) -> Calibration:
    """The scripted calibration session on a virtual carpet's ``sensor`` (its plug-in's ``calibration_sensor``),
    the actor drawn from ``seed``; saves ``out_path``."""
    from calibration.session import SessionError
    from calibration.virtual import calibrate_virtual

    out_path.parent.mkdir(parents=True, exist_ok=True)
    try:
        cal, val = calibrate_virtual(sensor, seed=seed, mass_kg=mass_kg)
    except (SessionError, CalibrationError, ValueError) as exc:
        raise SetupError(f"the automatic calibration of the virtual carpet failed: {exc}") from None
    if val is not None and not val.ok:  # None only for method "truth", which has nothing to validate
        raise SetupError(f"the automatic calibration of the virtual carpet did not validate: {val.summary()}")
    cal.save(out_path)
    return cal


__all__ = ["ChosenCalibration", "SetupError", "check_board", "choose_calibration", "run_sim_session", "sim_calibration_path"]

"""Checks `cavatar calibrate` makes before it asks anything: the destination, the session folder, the board.

A calibration session takes a quarter of an hour of someone walking and posing; it must not end
in "permission denied" on the last step, nor ask for a mass before finding the port missing.
Each check returns nothing or raises :class:`PreflightError` with one line: what is wrong and
what to do. Nothing is left behind (the write test removes its file; the board is closed again).

    check_destination(Path("calibration.npz"))
    check_work_folder(Path("calibration-work"))
    check_board("serial:///dev/ttyACM0", open_source)   # the runtime's opener, passed in
    mass = ask_mass(input)
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Callable

from calibration.capture import OpenFrames
from cavatar_common.errors import LinkLost, SourceError

SERVICE_FOLDER = "/var/lib/cavatar"


class PreflightError(Exception):
    """One line for the installer: the problem and what to do."""


def _unwritable(folder: Path) -> str | None:
    """Why ``folder`` cannot take a new file (None: it can), found by writing one and removing it."""
    if not folder.exists():
        return f"the folder {folder} does not exist"
    if not folder.is_dir():
        return f"{folder} is not a folder"
    try:
        fd, probe = tempfile.mkstemp(prefix=".cavatar-write-test-", dir=folder)
    except OSError as exc:
        return f"this user cannot write in {folder} ({exc.strerror or exc})"
    os.close(fd)
    os.unlink(probe)
    return None


def check_destination(out: Path) -> None:
    """The calibration file and its report (``.png``, ``.txt`` beside it) can be written."""
    out = Path(out)
    why = _unwritable(out.parent if str(out.parent) else Path("."))
    if why is None:
        for path in (out, out.with_suffix(".png"), out.with_suffix(".txt")):
            if path.exists() and (path.is_dir() or not os.access(path, os.W_OK)):
                why = f"{path} exists and this user cannot replace it"
                break
    if why is None:
        return
    service = str(out).startswith(SERVICE_FOLDER)
    hint = (f"run it as the service user, `sudo -u cavatar cavatar calibrate … --out {out}`, or write it where you "
            f"can (--out ~/calibration.npz) and copy it: `sudo install -o cavatar -m 0644 ~/calibration.npz "
            f"{SERVICE_FOLDER}/`") if service else "choose a place you can write with --out FILE"
    raise PreflightError(f"cannot write the calibration to {out}: {why}. Checked before starting, so no session is "
                         f"wasted: {hint}.")


def check_work_folder(work: Path) -> None:
    """The session folder exists or can be made, and can be written (the session is saved after every step)."""
    work = Path(work)
    try:
        (work / "captures").mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise PreflightError(f"cannot use the session folder {work}: {exc.strerror or exc}. Give a folder you can "
                             "write with --work DIR.") from None
    why = _unwritable(work)
    if why is not None:
        raise PreflightError(f"cannot use the session folder {work}: {why}. Give a folder you can write with --work DIR.")


def check_board(url: str, open_frames: OpenFrames) -> None:
    """The live board ``open_frames(url)`` opens and answers (handshake), then is closed again: a missing, busy or
    silent port is said now."""
    try:
        source = open_frames(url)
        source.start()
    except (SourceError, LinkLost, OSError, ValueError) as exc:
        raise PreflightError(f"board {url}: {exc}" + ("" if str(exc).rstrip().endswith(".") else ".")
                             + " Nothing was asked or recorded yet.") from None
    source.stop()


def check_recordings(files: dict[str, str]) -> None:
    """Every recording given exists and is a file."""
    missing = [f"--{step} {path}" for step, path in files.items() if not Path(path).is_file()]
    if missing:
        raise PreflightError(f"no such recording: {', '.join(missing)}. Record each step with `cavatar record`.")


def ask_mass(ask: Callable[[str], str]) -> float:
    """The mass of the person doing the poses, in kg, from the installer; PreflightError on no stdin or a bad answer."""
    try:
        text = ask("The person doing the poses: mass in kg? ")
    except EOFError:
        raise PreflightError("no answer: standard input is closed (not a terminal?). Give the mass of the person doing "
                             "the poses with --mass KG.") from None
    return parse_mass(text)


def parse_mass(text: str) -> float:
    try:
        mass = float(str(text).strip().replace(",", "."))
    except ValueError:
        raise PreflightError(f"the mass must be a number of kilograms, e.g. 72, not {str(text).strip()!r}; "
                             "run again (or give --mass KG).") from None
    if not 20.0 <= mass <= 300.0:
        raise PreflightError(f"a mass of {mass:g} kg is not a person's; give the mass of the person doing the poses "
                             "in kilograms (20–300), e.g. --mass 72.")
    return mass


__all__ = ["PreflightError", "ask_mass", "check_board", "check_destination", "check_recordings", "check_work_folder",
           "parse_mass"]

"""What a health check returns, and the access checks that several schemes share (`cavatar doctor`).

Each source and sink scheme module offers ``check(url, ctx)`` (see :mod:`edge.sources` and
:mod:`edge.sinks`); :mod:`edge.runtime.doctor` calls them through the scheme registry and adds
the checks that belong to no scheme (configuration, calibration, model bundle, status file).

    Finding("source", OK, "/dev/ttyACM0 exists, readable and writable by user pi").line()
    writable_file("status file", Path("/run/cavatar/status.json"), free_space=False)

Paths are checked for the user running the check: run it as the service user to see what the
service sees. Folders systemd creates for the service at start (``SERVICE_DIRS``) are fine when
missing. Standard library only.
"""

from __future__ import annotations

import os
import shutil
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Mapping

OK, WARN, FAIL = "ok", "warn", "FAIL"
SERVICE_USER = "cavatar"
SERVICE_DIRS = {"/run/cavatar": "RuntimeDirectory=cavatar", "/var/lib/cavatar": "StateDirectory=cavatar"}
MIN_FREE_BYTES = 1_000_000_000


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
    """What is known of the carpet's readout board, and from where (INFO packet, status file, the source URL)."""

    origin: str
    device_id: str | None = None
    rows: int | None = None
    cols: int | None = None
    adc_bits: int | None = None
    info: Any = None  # the INFO packet itself, when the board answered


@dataclass(frozen=True)
class CheckContext:
    """What a scheme's ``check`` may use: the time it may wait, the environment (secrets), the USB backend."""

    timeout_s: float = 2.0
    env: Mapping[str, str] = field(default_factory=lambda: dict(os.environ))
    usb_backend: Any = None  # pyusb backend (None: libusb); tests pass a virtual one


def user() -> str:
    """The name of the user running this process (its uid when it has no name)."""
    import pwd

    try:
        return pwd.getpwuid(os.geteuid()).pw_name
    except KeyError:
        return str(os.geteuid())


def owner(path: str | Path) -> str:
    """``user:group, mode 0660`` of ``path``, or why it cannot be read."""
    import grp
    import pwd

    try:
        st = os.stat(path)
    except OSError as exc:
        return f"unreadable: {exc.strerror}"
    try:
        who = pwd.getpwuid(st.st_uid).pw_name
    except KeyError:
        who = str(st.st_uid)
    try:
        group = grp.getgrgid(st.st_gid).gr_name
    except KeyError:
        group = str(st.st_gid)
    return f"{who}:{group}, mode {st.st_mode & 0o777:04o}"


def not_yours(check: str, path: str | Path, how: str, fix: str) -> Finding:
    """FAIL: ``path`` is not ``how`` (readable / writable) by this user; only a warning when it is the service user's."""
    whose = owner(path)
    if user() != SERVICE_USER and whose.startswith(f"{SERVICE_USER}:"):
        return Finding(check, WARN, f"{path} ({whose}) is not {how} by user {user()}, but belongs to the service user "
                       f"{SERVICE_USER}: run doctor as the service runs (docs/install-pi.md) to check it")
    return Finding(check, FAIL, f"{path} ({whose}) is not {how} by user {user()}: {fix}")


def group_hint(path: str | Path) -> str:
    """How this user gets access to the device node ``path`` through its group."""
    import grp

    try:
        group = grp.getgrgid(os.stat(path).st_gid).gr_name
    except (KeyError, OSError):
        group = "root"
    if group == "root":
        return "it is root's alone"
    return f"add the user to the group {group} (sudo usermod -aG {group} {user()}, then log in again)"


def _under(path: Path, folder: Path) -> bool:
    return path == folder or folder in path.parents


def writable_file(check: str, path: Path, free_space: bool, folder_only: bool = False) -> Finding:
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
        return not_yours(check, blocked, "writable", f"give the user write access (chown/chmod) or choose a writable "
                         f"place in the configuration{rel}")
    made = "" if folder.exists() else f" ({folder} will be created)"
    if not free_space:
        return Finding(check, OK, f"{shown} writable{made}{rel}")
    free = shutil.disk_usage(existing).free
    if free < MIN_FREE_BYTES:
        return Finding(check, WARN, f"{shown} writable{made}, but only {free / 1e6:.0f} MB free there: free space, or "
                       "lower rotate_mb / keep= (jsonl) or spool_mb= (mqtt)")
    return Finding(check, OK, f"{shown} writable{made}, {free / 1e9:.1f} GB free{rel}")


__all__ = ["FAIL", "OK", "WARN", "Board", "CheckContext", "Finding", "group_hint", "not_yours", "owner", "user",
           "writable_file"]

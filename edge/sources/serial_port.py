"""``serial://PATH?baud=N`` — a readout board on a serial port (USB CDC-ACM or a UART).

Use a stable path where you can (``/dev/serial/by-id/...`` or a udev symlink): the
kernel's ``/dev/ttyACM0`` may change name after a replug.

The port is taken exclusively (pyserial's ``exclusive=True``, an ``flock``): two readers of one
board each get part of the bytes, so both see bad CRCs and torn frames, and a calibration run
beside the service would calibrate on garbage. A second cavatar process on the same port is
refused with one line that names the holder when /proc shows it (``port_holders``).
"""

from __future__ import annotations

import errno
import os

from edge.health import FAIL, OK, CheckContext, Finding, group_hint, owner, user
from edge.sources.base import Link, LinkLost, Option, SourceError, parse_url

SCHEME = "serial"
FORM = "serial:///dev/ttyACM0?baud=2000000"
OPTIONS = {
    "baud": Option(int, 2_000_000, "bits per second; ignored by USB CDC-ACM boards"),
}


def available_ports() -> list[str]:
    """Serial ports that exist now, stable by-id names first."""
    from serial.tools import list_ports

    by_id = "/dev/serial/by-id"
    ports = sorted(os.path.join(by_id, n) for n in os.listdir(by_id)) if os.path.isdir(by_id) else []
    return ports + sorted(p.device for p in list_ports.comports())


def port_holders(port: str) -> list[tuple[int, str]]:
    """Processes that have ``port`` open, as (pid, command line on one line), from /proc (Linux). Processes of other
    users are invisible without root; an empty list then means "someone we cannot see"."""
    try:
        target = os.path.realpath(port)
    except OSError:
        return []
    found = []
    try:
        pids = [d for d in os.listdir("/proc") if d.isdigit()]
    except OSError:
        return []
    for pid in pids:
        fd_dir = f"/proc/{pid}/fd"
        try:
            fds = os.listdir(fd_dir)
        except OSError:  # gone, or another user's
            continue
        for fd in fds:
            try:
                if os.readlink(f"{fd_dir}/{fd}") == target:
                    break
            except OSError:
                continue
        else:
            continue
        try:
            with open(f"/proc/{pid}/cmdline", "rb") as f:
                cmd = " ".join(f.read().replace(b"\0", b" ").decode(errors="replace").split())
        except OSError:
            cmd = ""
        found.append((int(pid), cmd or "?"))
    return found


def busy_message(port: str) -> str:
    """One line: the port is taken, by whom if visible, what to do."""
    holders = port_holders(port)
    others = [(pid, cmd) for pid, cmd in holders if pid != os.getpid()]
    if others:
        who = "held by " + ", ".join(f"pid {pid} ({cmd[:100]})" for pid, cmd in others)
    elif holders:
        who = f"held by this process, pid {os.getpid()}: another source on the same port"
    else:
        who = f"held by a process this user cannot see (`sudo fuser -v {port}` names it)"
    return (f"serial port {port} is in use by another program ({who}); two readers of one board corrupt each other's "
            "frames. Stop the other program first (the service: `sudo systemctl stop cavatar`).")


class SerialLink(Link):
    def __init__(self, port: str, baud: int) -> None:
        self.port, self.baud = port, baud
        self._ser = None
        self._opened_once = False

    def describe(self) -> str:
        return f"serial://{self.port}"

    def open(self) -> None:
        import serial

        try:
            self._ser = serial.Serial(self.port, self.baud, timeout=0.05, write_timeout=1.0, exclusive=True)
        except (serial.SerialException, OSError) as exc:
            if getattr(exc, "errno", None) in (errno.EAGAIN, errno.EWOULDBLOCK) and "lock" in str(exc):
                if not self._opened_once:
                    raise SourceError(busy_message(self.port)) from None
                raise LinkLost(f"{self.port} is taken by another program") from None
            missing = not os.path.exists(self.port)
            if missing and not self._opened_once:
                ports = ", ".join(available_ports()) or "none"
                raise SourceError(f"serial port {self.port} does not exist. Ports found: {ports}. "
                                  "Run `cavatar devices` to see candidates.") from None
            if not self._opened_once:
                raise SourceError(f"cannot open serial port {self.port}: {exc}") from None
            raise LinkLost(str(exc)) from None
        self._opened_once = True

    def read(self, timeout_s: float) -> bytes:
        import serial

        if self._ser is None:
            raise LinkLost("port closed")
        try:
            self._ser.timeout = timeout_s
            waiting = self._ser.in_waiting
            return self._ser.read(max(1, min(waiting, 1 << 16)))
        except (serial.SerialException, OSError, TypeError) as exc:  # TypeError: pyserial on a vanished fd
            raise LinkLost(str(exc)) from None

    def write(self, data: bytes) -> None:
        import serial

        if self._ser is None:
            raise LinkLost("port closed")
        try:
            self._ser.write(data)
        except (serial.SerialException, OSError) as exc:
            raise LinkLost(str(exc)) from None

    def close(self) -> None:
        if self._ser is not None:
            try:
                self._ser.close()
            except Exception:  # closing a port whose device vanished may fail; it is gone either way
                pass
            self._ser = None


def open_link(url: str, **_: object) -> SerialLink:
    location, opts = parse_url(url, SCHEME, FORM, OPTIONS)
    if not location:
        raise ValueError(f"serial:// needs a port path. Form: {FORM}")
    return SerialLink(location, opts["baud"])


def check(url: str, ctx: CheckContext) -> tuple[Finding, None]:
    """`cavatar doctor`: the port exists and this user may read and write it (the board is asked later)."""
    path = open_link(url).port
    if not os.path.exists(path):
        ports = ", ".join(available_ports()) or "none"
        return Finding("source", FAIL, f"serial port {path} does not exist (ports found: {ports}). Plug the board in "
                       "and run `cavatar devices`; with deploy/99-cavatar.rules installed it appears as "
                       "/dev/cavatar-carpet (serial:///dev/cavatar-carpet)"), None
    real = os.path.realpath(path)
    where = path if real == path else f"{path} → {real}"
    if not os.access(path, os.R_OK | os.W_OK):
        return Finding("source", FAIL, f"{where} ({owner(real)}) is not readable and writable by user {user()}: "
                       f"{group_hint(real)}; install deploy/99-cavatar.rules, which gives the board to the group "
                       "dialout (mode 0660), and run as a member of it (the service user is)"), None
    return Finding("source", OK, f"{where} exists, readable and writable by user {user()}"), None

"""``serial://PATH?baud=N`` — a readout board on a serial port (USB CDC-ACM or a UART).

Use a stable path where you can (``/dev/serial/by-id/...`` or a udev symlink): the
kernel's ``/dev/ttyACM0`` may change name after a replug.
"""

from __future__ import annotations

import os

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
            self._ser = serial.Serial(self.port, self.baud, timeout=0.05, write_timeout=1.0)
        except (serial.SerialException, OSError) as exc:
            missing = not os.path.exists(self.port)
            if missing and not self._opened_once:
                ports = ", ".join(available_ports()) or "none"
                raise SourceError(f"serial port {self.port} does not exist. Ports found: {ports}. Run `cavatar devices` to see candidates.") from None
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

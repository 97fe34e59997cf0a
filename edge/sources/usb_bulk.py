"""``usb://VID:PID`` — a readout board with a vendor-class bulk interface, through pyusb.

Bulk OUT carries commands, bulk IN carries the packet stream. ``usb://1209:CA7A`` finds
the first such board; ``?serial=carpet-01`` picks one by its USB serial number.
pyusb needs libusb-1.0 on the system (Debian: ``apt-get install libusb-1.0-0``).
"""

from __future__ import annotations

import errno
import os

from edge.health import FAIL, OK, CheckContext, Finding, group_hint, owner, user
from edge.sources.base import Link, LinkLost, Option, SourceError, parse_url

SCHEME = "usb"
FORM = "usb://1209:CA7A?serial=carpet-01"
DEFAULT_VID_PID = (0x1209, 0xCA7A)
OPTIONS = {
    "serial": Option(str, "", "USB serial number (the board's device id); empty = the first board"),
    "interface": Option(int, 0, "interface number of the bulk pipe"),
}


def _parse_vid_pid(text: str) -> tuple[int, int]:
    if not text:
        return DEFAULT_VID_PID
    try:
        vid, pid = text.split(":")
        return int(vid, 16), int(pid, 16)
    except ValueError:
        raise ValueError(f"usb:// needs VID:PID in hex, e.g. {FORM}; got {text!r}") from None


def list_devices(backend=None) -> list[str]:
    """``VID:PID`` of every USB device pyusb sees (raises SourceError when libusb is missing)."""
    import usb.core

    try:
        devices = list(usb.core.find(find_all=True, backend=backend))
    except usb.core.NoBackendError:
        raise SourceError("pyusb found no libusb backend; install it (Debian: apt-get install libusb-1.0-0)") from None
    return [f"{d.idVendor:04x}:{d.idProduct:04x}" for d in devices]


class UsbLink(Link):
    def __init__(self, vid: int, pid: int, serial: str = "", interface: int = 0, backend=None) -> None:
        self.vid, self.pid, self.serial, self.interface = vid, pid, serial, interface
        self.backend = backend
        self._dev = self._ep_in = self._ep_out = None
        self._opened_once = False

    def describe(self) -> str:
        return f"usb://{self.vid:04x}:{self.pid:04x}" + (f"?serial={self.serial}" if self.serial else "")

    def _match(self, dev) -> bool:
        if not self.serial:
            return True
        import usb.util

        try:
            return usb.util.get_string(dev, dev.iSerialNumber) == self.serial
        except Exception:  # a device we may not query is not ours
            return False

    def open(self) -> None:
        import usb.core
        import usb.util

        try:
            dev = usb.core.find(idVendor=self.vid, idProduct=self.pid, backend=self.backend, custom_match=self._match)
        except usb.core.NoBackendError:
            raise SourceError("pyusb found no libusb backend; install it (Debian: apt-get install libusb-1.0-0)") from None
        if dev is None:
            if self._opened_once:
                raise LinkLost("device not present")
            found = ", ".join(list_devices(self.backend)) or "none"
            raise SourceError(f"no USB device {self.describe()[6:]} found. USB devices present: {found}. Run `cavatar devices`.")
        try:
            dev.set_configuration()
            usb.util.claim_interface(dev, self.interface)
            intf = dev.get_active_configuration()[(self.interface, 0)]
            is_in = lambda e: usb.util.endpoint_direction(e.bEndpointAddress) == usb.util.ENDPOINT_IN  # noqa: E731
            self._ep_in = usb.util.find_descriptor(intf, custom_match=is_in)
            self._ep_out = usb.util.find_descriptor(intf, custom_match=lambda e: not is_in(e))
        except usb.core.USBError as exc:
            raise (LinkLost(str(exc)) if self._opened_once else SourceError(f"cannot open {self.describe()}: {exc}")) from None
        if self._ep_in is None or self._ep_out is None:
            raise SourceError(f"{self.describe()}: interface {self.interface} has no bulk IN and OUT endpoints")
        self._dev = dev
        self._opened_once = True

    def read(self, timeout_s: float) -> bytes:
        import usb.core

        if self._dev is None:
            raise LinkLost("device closed")
        size = max(self._ep_in.wMaxPacketSize, 64) * 64
        try:
            return bytes(self._ep_in.read(size, timeout=max(1, int(timeout_s * 1000))))
        except usb.core.USBTimeoutError:
            return b""
        except usb.core.USBError as exc:
            if exc.errno == errno.ETIMEDOUT:
                return b""
            raise LinkLost(str(exc)) from None

    def write(self, data: bytes) -> None:
        import usb.core

        if self._dev is None:
            raise LinkLost("device closed")
        try:
            self._ep_out.write(data, timeout=1000)
        except usb.core.USBError as exc:
            raise LinkLost(str(exc)) from None

    def close(self) -> None:
        if self._dev is not None:
            import usb.util

            try:
                usb.util.dispose_resources(self._dev)
            except Exception:  # releasing a vanished device may fail; it is gone either way
                pass
        self._dev = self._ep_in = self._ep_out = None


def open_link(url: str, usb_backend=None, **_: object) -> UsbLink:
    location, opts = parse_url(url, SCHEME, FORM, OPTIONS)
    vid, pid = _parse_vid_pid(location.strip("/"))
    return UsbLink(vid, pid, opts["serial"], opts["interface"], backend=usb_backend)


def check(url: str, ctx: CheckContext) -> tuple[Finding, None]:
    """`cavatar doctor`: the device is present (pyusb, ``ctx.usb_backend``) and its node accessible to this user."""
    link = open_link(url)
    vid_pid = f"{link.vid:04x}:{link.pid:04x}"
    try:
        import usb.core

        devices = list(usb.core.find(find_all=True, idVendor=link.vid, idProduct=link.pid, backend=ctx.usb_backend))
    except ImportError as exc:
        return Finding("source", FAIL, f"pyusb is not importable ({exc}): reinstall the package"), None
    except usb.core.NoBackendError:
        return Finding("source", FAIL, "pyusb found no libusb backend: install it (sudo apt-get install "
                       "libusb-1.0-0)"), None
    if not devices:
        present = ", ".join(list_devices(ctx.usb_backend)) or "none"
        return Finding("source", FAIL, f"no USB device {vid_pid} (USB devices present: {present}). Plug the board in "
                       "and run `cavatar devices` (or lsusb); another VID:PID goes in the URL, usb://VID:PID"), None
    nodes = [f"/dev/bus/usb/{d.bus:03d}/{d.address:03d}" for d in devices if d.bus is not None and d.address is not None]
    blocked = [n for n in nodes if os.path.exists(n) and not os.access(n, os.R_OK | os.W_OK)]
    if blocked:
        return Finding("source", FAIL, f"USB device {vid_pid} at {blocked[0]} ({owner(blocked[0])}) is not readable "
                       f"and writable by user {user()}: {group_hint(blocked[0])}; install deploy/99-cavatar.rules, "
                       "which gives the board to the group plugdev (mode 0660), and run as a member of it (the "
                       "service user is)"), None
    serial = f"; serial={link.serial} is checked when the board is opened" if link.serial else ""
    return Finding("source", OK, f"USB device {vid_pid} present ({len(devices)} found"
                   + (f", {', '.join(nodes)}" if nodes else "") + f"){serial}"), None

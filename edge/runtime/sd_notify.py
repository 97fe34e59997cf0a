"""systemd's notification protocol, spoken directly (no dependency): READY, STATUS, WATCHDOG, STOPPING.

Under ``Type=notify`` systemd passes ``$NOTIFY_SOCKET`` (a Unix datagram socket; a leading
"@" means the abstract namespace) and, with ``WatchdogSec=``, ``$WATCHDOG_USEC`` (and
``$WATCHDOG_PID``). Each message is one datagram of ``KEY=value`` lines (sd_notify(3)).
Outside systemd there is no socket and every call does nothing.

    n = Notifier.from_environment()
    n.ready("running: 14.0 fps")
    n.watchdog()          # as often as you like: sent at most every WATCHDOG_USEC / 4
    n.stopping()

The runtime pings the watchdog from its pipeline loop, which turns at least every 0.2 s whether
frames arrive or not: a hung pipeline stops the pings and systemd restarts the service. An
unplugged board does not — restarting would not plug the cable back; board health reports it
(docs/runtime.md, "Board health").
"""

from __future__ import annotations

import logging
import os
import socket
import time
from typing import Mapping

log = logging.getLogger(__name__)


class Notifier:
    def __init__(self, address: str | None, watchdog_s: float | None = None) -> None:
        self.address = address
        self.watchdog_s = watchdog_s
        self._last_ping = -1e18
        self._failed = False
        self._ready = False  # pings start after READY=1, so systemd hears the start first

    @classmethod
    def from_environment(cls, env: Mapping[str, str] | None = None) -> "Notifier":
        env = os.environ if env is None else env
        address = env.get("NOTIFY_SOCKET") or None
        watchdog_s = None
        usec = env.get("WATCHDOG_USEC", "")
        pid = env.get("WATCHDOG_PID", "")
        if usec.isdigit() and int(usec) > 0 and (not pid or pid == str(os.getpid())):
            watchdog_s = int(usec) / 1e6
        return cls(address, watchdog_s)

    @property
    def active(self) -> bool:
        return self.address is not None

    def send(self, *lines: str) -> bool:
        """One datagram; False (logged once) when it cannot be sent. Never raises."""
        if self.address is None:
            return False
        target = "\0" + self.address[1:] if self.address.startswith("@") else self.address
        try:
            with socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM) as s:
                s.connect(target)
                s.sendall("\n".join(lines).encode())
            return True
        except OSError as exc:
            if not self._failed:
                self._failed = True
                log.warning("systemd notification socket %s: %s (the watchdog may restart the service)", self.address, exc)
            return False

    def ready(self, status: str = "") -> bool:
        self._ready = True
        return self.send("READY=1", *([f"STATUS={status}"] if status else []))

    def status(self, text: str) -> bool:
        return self.send(f"STATUS={text}")

    def stopping(self, status: str = "") -> bool:
        return self.send("STOPPING=1", *([f"STATUS={status}"] if status else []))

    def watchdog(self, now_s: float | None = None) -> bool:
        """WATCHDOG=1, at most every quarter of the watchdog period (systemd's advice: well within it)."""
        if self.address is None or self.watchdog_s is None or not self._ready:
            return False
        now = time.monotonic() if now_s is None else now_s
        if now - self._last_ping < self.watchdog_s / 4:
            return False
        self._last_ping = now
        return self.send("WATCHDOG=1")


__all__ = ["Notifier"]

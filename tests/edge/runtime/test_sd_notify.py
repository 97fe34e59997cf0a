"""systemd's notification protocol (issue 17, the unit's Type=notify and WatchdogSec=): the runtime says READY once
started, pings the watchdog while its pipeline loop turns, puts one STATUS line for `systemctl status`, and says
STOPPING on a clean stop — over a real Unix datagram socket, as systemd listens."""

import os
import socket
import threading
import time

import pytest

from edge.runtime import Runtime
from edge.runtime.sd_notify import Notifier


class FakeSystemd:
    """A datagram socket like systemd's notify socket; collects every message."""

    def __init__(self, path: str) -> None:
        self.path = path
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_DGRAM)
        self.sock.bind("\0" + path[1:] if path.startswith("@") else path)
        self.sock.settimeout(0.1)
        self.messages: list[tuple[float, str]] = []
        self._stop = False
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._stop:
            try:
                self.messages.append((time.monotonic(), self.sock.recv(4096).decode()))
            except socket.timeout:
                continue

    def lines(self) -> list[str]:
        return [line for _, m in self.messages for line in m.splitlines()]

    def close(self) -> None:
        self._stop = True
        self._thread.join()
        self.sock.close()


@pytest.fixture
def systemd(tmp_path):
    s = FakeSystemd(str(tmp_path / "notify"))
    yield s
    s.close()


def test_outside_systemd_nothing_is_sent():
    n = Notifier.from_environment({})
    assert not n.active and not n.ready() and not n.watchdog()


def test_the_watchdog_period_comes_from_systemd_and_pings_are_spaced(systemd):
    n = Notifier.from_environment({"NOTIFY_SOCKET": systemd.path, "WATCHDOG_USEC": "2000000",
                                   "WATCHDOG_PID": str(os.getpid())})
    assert n.watchdog_s == 2.0
    assert not n.watchdog(now_s=0.0)  # not before READY
    n.ready()
    sent = [n.watchdog(now_s=t) for t in (0.0, 0.1, 0.49, 0.5, 0.6, 1.0)]
    assert sent == [True, False, False, True, False, True]  # at most every WATCHDOG_USEC / 4
    assert Notifier.from_environment({"NOTIFY_SOCKET": systemd.path, "WATCHDOG_USEC": "2000000",
                                      "WATCHDOG_PID": "1"}).watchdog_s is None  # meant for another process
    time.sleep(0.3)
    assert systemd.lines() == ["READY=1"] + ["WATCHDOG=1"] * 3


def test_the_abstract_namespace_is_understood(tmp_path):
    s = FakeSystemd(f"@cavatar-test-{os.getpid()}")
    try:
        assert Notifier(s.path).ready("up")
        time.sleep(0.3)
        assert s.lines() == ["READY=1", "STATUS=up"]
    finally:
        s.close()


def test_a_runtime_under_systemd_says_ready_pings_and_says_stopping(systemd, monkeypatch, config, tmp_path):
    monkeypatch.setenv("NOTIFY_SOCKET", systemd.path)
    monkeypatch.setenv("WATCHDOG_USEC", "1000000")
    monkeypatch.delenv("WATCHDOG_PID", raising=False)
    rt = Runtime(config(1, source="sim://?people=1&seed=7&speed=1"), say=lambda text: None)
    rt.start()
    try:
        time.sleep(2.5)
    finally:
        rt.stop()
    time.sleep(0.3)
    lines = systemd.lines()
    assert lines[0] == "READY=1" and lines[1].startswith("STATUS=running: sim://")
    pings = [t for t, m in systemd.messages if m == "WATCHDOG=1"]
    gaps = [b - a for a, b in zip(pings, pings[1:])]
    assert len(pings) >= 6 and max(gaps) < 1.0, gaps  # every 0.25 s or so, always within the 1 s period
    assert any(line.startswith("STATUS=") and "fps" in line and "people" in line for line in lines)
    assert "STOPPING=1" in lines and lines.index("STOPPING=1") > lines.index("READY=1")

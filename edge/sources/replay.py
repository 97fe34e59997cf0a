"""``replay://capture.bin?speed=1`` — a byte stream written by ``cavatar record``.

``speed=1`` replays at the pace of the device timestamps, ``speed=4`` four times
faster, ``speed=0`` as fast as the consumer takes frames. Absolute paths take three
slashes: ``replay:///var/lib/cavatar/capture.bin``.
"""

from __future__ import annotations

import os

from edge.health import FAIL, OK, CheckContext, Finding, owner, user
from edge.sources.base import Link, LinkEnded, LinkLost, Option, SourceError, parse_url

SCHEME = "replay"
FORM = "replay://capture.bin?speed=1"
OPTIONS = {
    "speed": Option(float, 1.0, "1 = the device's own pace, 0 = as fast as possible"),
}


class ReplayLink(Link):
    paced = False
    reconnectable = False
    writable = False

    def __init__(self, path: str, chunk_bytes: int = 1 << 14) -> None:
        self.path, self.chunk_bytes = path, chunk_bytes
        self._fh = None

    def describe(self) -> str:
        return f"replay://{self.path}"

    def open(self) -> None:
        if not os.path.isfile(self.path):
            raise SourceError(f"no capture file {self.path!r} (write one with `cavatar record --source URL --frames N {self.path}`)")
        self._fh = open(self.path, "rb")

    def read(self, timeout_s: float) -> bytes:
        if self._fh is None:
            raise LinkLost("file closed")
        data = self._fh.read(self.chunk_bytes)
        if not data:
            raise LinkEnded(self.path)
        return data

    def write(self, data: bytes) -> None:
        raise SourceError("a recording cannot carry commands")

    def close(self) -> None:
        if self._fh is not None:
            self._fh.close()
            self._fh = None


def open_link(url: str, **_: object) -> ReplayLink:
    location, opts = parse_url(url, SCHEME, FORM, OPTIONS)
    if not location:
        raise ValueError(f"replay:// needs a file. Form: {FORM}")
    if opts["speed"] < 0:
        raise ValueError(f"replay:// speed must be ≥ 0. Form: {FORM}")
    link = ReplayLink(location)
    link.speed = opts["speed"]
    return link


def check(url: str, ctx: CheckContext) -> tuple[Finding, None]:
    """`cavatar doctor`: the capture is a readable file (its INFO packet is read later, as a board's)."""
    location = open_link(url).path
    if not os.path.isfile(location):
        return Finding("source", FAIL, f"no capture {location}: record one with "
                       "`cavatar record --source URL --frames N FILE`"), None
    if not os.access(location, os.R_OK):
        return Finding("source", FAIL, f"{location} ({owner(location)}) is not readable by user {user()}"), None
    return Finding("source", OK, f"capture {location} is readable"), None

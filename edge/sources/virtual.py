"""A virtual carpet from a source plug-in (``sim://`` and the like), scanned by a virtual board in-process.

The plug-in (edge/sources/plugins.py) makes the frames; a
:class:`~firmware_protocol.virtual_board.VirtualBoard` scans them and speaks the wire
protocol; this link hands its bytes to the same decoder and frame assembly as a real board,
so the demo exercises the whole path. ``speed=0`` runs as fast as frames can be made (a
virtual clock), ``speed=1`` in real time. Closing the link closes the plug-in's frames
(the live carpet's scene helper process, for ``sim://``).
"""

from __future__ import annotations

import time
from typing import Any

from edge.health import OK, Board, CheckContext, Finding
from edge.sources.base import Link, LinkLost, parse_url
from edge.sources.plugins import Plugin
from edge.urls import redact
from firmware_protocol import codec


def packing_for(bits: int) -> int:
    return codec.PACKING["u8"] if bits <= 8 else codec.PACKING["packed12"] if bits <= 12 else codec.PACKING["u16"]


class VirtualCarpetLink(Link):
    def __init__(self, plugin: Plugin, **opts: Any) -> None:
        self.plugin = plugin
        self.opts = opts
        # speed=0 runs a virtual clock as fast as the consumer takes frames: like a recording,
        # nothing is dropped for a slow consumer (a real-time sim drains to the newest frame)
        self.speed = opts.get("speed", 1.0)
        self.paced = self.speed > 0
        self.rate_hz = 0.0
        self.board = None
        self._t0 = 0.0
        self._virtual_now = 0.0

    def describe(self) -> str:
        return f"{self.plugin.scheme}://"

    def open(self) -> None:
        from firmware_protocol.virtual_board import VirtualBoard

        carpet, board = self.plugin.module.open_carpet(self.opts)
        self.carpet = carpet
        self.rate_hz = float(board["rate_hz"])
        self.board = VirtualBoard(**board, packing=packing_for(board["adc_bits"]), frames=carpet)
        self._t0 = time.monotonic()
        self._virtual_now = 0.0
        self._faults_at = 0

    def _now(self) -> float:
        if self.speed <= 0:
            return self._virtual_now
        return (time.monotonic() - self._t0) * self.speed

    def read(self, timeout_s: float) -> bytes:
        if self.board is None:
            raise LinkLost("closed")
        if self.speed <= 0:
            self._virtual_now += 1.0 / self.rate_hz
            return self._maybe_fault(self.board.read(self._virtual_now))
        deadline = time.monotonic() + timeout_s
        while True:
            data = self.board.read(self._now())
            if data or time.monotonic() >= deadline:
                return self._maybe_fault(data)
            time.sleep(min(0.005, max(0.0, deadline - time.monotonic())))

    def _maybe_fault(self, data: bytes) -> bytes:
        if self.opts.get("faults") and data:
            self._faults_at += 1
            if self._faults_at % 37 == 0:
                self.board.flip_bits(3)
            elif self._faults_at % 53 == 0:
                self.board.garbage(40)
            elif self._faults_at % 97 == 0:
                self.board.tear_next_frame()
        return data

    def write(self, data: bytes) -> None:
        if self.board is None:
            raise LinkLost("closed")
        self.board.receive(data)

    def close(self) -> None:
        self.board = None
        carpet, self.carpet = getattr(self, "carpet", None), None
        if carpet is not None and hasattr(carpet, "close"):
            carpet.close()  # e.g. the live carpet's scene helper process


def open_link(url: str, plugin: Plugin) -> VirtualCarpetLink:
    """The link of ``url`` on ``plugin``'s carpet (not opened); ValueError for an unknown or bad option."""
    _, opts = parse_url(url, plugin.scheme, plugin.form, plugin.options)
    return VirtualCarpetLink(plugin, **opts)


def check(url: str, plugin: Plugin, ctx: CheckContext) -> tuple[Finding, Board | None]:
    """Nothing to check on a virtual carpet. The board it will answer with follows from the URL's options when
    the plug-in states them (``device_id(opts)`` and the options ``grid`` and ``bits``); otherwise None, and the
    board is asked like a real one."""
    _, opts = parse_url(url, plugin.scheme, plugin.form, plugin.options)
    shown = redact(url)
    finding = Finding("source", OK, f"{shown}: the virtual carpet, no hardware to check")
    if not hasattr(plugin.module, "device_id") or "grid" not in opts or "bits" not in opts:
        return finding, None
    board = Board(f"the options of {shown}", plugin.module.device_id(opts), opts["grid"], opts["grid"], opts["bits"])
    return finding, board


class VirtualScheme:
    """A loaded plug-in as a scheme handler, like the built-in scheme modules: SCHEME, FORM, OPTIONS,
    ``open_link`` and ``check`` (see edge/sources/__init__.py)."""

    def __init__(self, plugin: Plugin) -> None:
        self.plugin = plugin
        self.SCHEME, self.FORM, self.OPTIONS = plugin.scheme, plugin.form, plugin.options

    def open_link(self, url: str, **_: Any) -> VirtualCarpetLink:
        return open_link(url, self.plugin)

    def check(self, url: str, ctx: CheckContext) -> tuple[Finding, Board]:
        return check(url, self.plugin, ctx)

"""Helpers of the runtime integration tests: frames of the virtual carpet made once, a board that
streams them through the real protocol, and small measuring tools (see conftest.py)."""

from __future__ import annotations

import json
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable

import numpy as np
from runtime_helpers import GRID, SEED  # the calibration fixture's carpet: sim://?seed=7, 96×96

from edge.sources.base import Link, LinkLost

RATE_HZ = 14.0
SCHEMA_PATH = Path(__file__).resolve().parents[3] / "edge" / "schema" / "bodies.schema.json"


@dataclass(frozen=True)
class Premade:
    """Raw counts of ``sim://?people=P&seed=7`` frames 0..n-1, made once, and the board's ADC bits and sign."""

    counts: tuple[np.ndarray, ...]
    adc_bits: int
    sign: int

    def frame(self, k: int) -> np.ndarray:
        """Frame k of an endless stream that plays the frames forwards then backwards (no jump at the turns)."""
        n = len(self.counts)
        period = 2 * n - 2
        j = k % period
        return self.counts[j if j < n else period - j]


def make_premade(people: int, n: int) -> Premade:
    from sim.live import LiveCarpet

    carpet = LiveCarpet(GRID, GRID, people, SEED)
    return Premade(tuple(carpet(k) for k in range(n)), carpet.adc_bits, carpet.sign)


def premade_board(premade: Premade, **kwargs: Any):
    """A VirtualBoard that answers as ``sim://?seed=7`` (so the seed-7 calibration fits it) and scans ``premade``."""
    from edge.sources.virtual import packing_for
    from firmware_protocol.virtual_board import VirtualBoard

    return VirtualBoard(rows=GRID, cols=GRID, tile_rows=3, tile_cols=3, adc_bits=premade.adc_bits,
                        packing=packing_for(premade.adc_bits), sign=premade.sign, rate_hz=RATE_HZ,
                        device_id=f"sim-{SEED}", frames=premade.frame, **kwargs)


class BoardLink(Link):
    """A :func:`premade_board` in-process. ``speed=0``: a virtual clock, one frame period per read, as fast as the
    reader takes them (not paced: nothing dropped, the reader waits for the pipeline); ``speed=1``: real time."""

    reconnectable = False

    def __init__(self, premade: Premade, speed: float) -> None:
        self.premade, self.speed = premade, speed
        self.paced = speed > 0
        self.board = None
        self._t0 = 0.0
        self._virtual_now = 0.0

    def describe(self) -> str:
        return "premade://"

    def open(self) -> None:
        self.board = premade_board(self.premade)
        self._t0, self._virtual_now = time.monotonic(), 0.0

    def read(self, timeout_s: float) -> bytes:
        if self.board is None:
            raise LinkLost("closed")
        if self.speed <= 0:
            self._virtual_now += 1.0 / RATE_HZ
            return self.board.read(self._virtual_now)
        deadline = time.monotonic() + timeout_s
        while True:
            data = self.board.read((time.monotonic() - self._t0) * self.speed)
            if data or time.monotonic() >= deadline:
                return data
            time.sleep(min(0.005, max(0.0, deadline - time.monotonic())))

    def write(self, data: bytes) -> None:
        if self.board is None:
            raise LinkLost("closed")
        self.board.receive(data)

    def close(self) -> None:
        self.board = None


def runtime_on_board(config, premade: Premade, speed: float, **kwargs: Any):
    """A Runtime (not started) reading ``premade`` through the real reader (decoder, assembly, bounded queue)."""
    from edge.runtime import Runtime
    from edge.runtime.reader import TimedCarpetSource

    rt = Runtime(config, say=lambda text: None, **kwargs)
    rt.source = TimedCarpetSource(BoardLink(premade, speed), times=rt.times, queue_frames=config.source.queue_frames,
                                  speed=speed)
    return rt


def bodies_validator():
    import jsonschema

    schema = json.loads(SCHEMA_PATH.read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    return jsonschema.Draft202012Validator(schema)


def rss_kb() -> int:
    """This process's resident set size now (VmRSS of /proc/self/status), kB."""
    for line in Path("/proc/self/status").read_text().splitlines():
        if line.startswith("VmRSS:"):
            return int(line.split()[1])
    raise RuntimeError("no VmRSS in /proc/self/status")


def wait_until(predicate: Callable[[], Any], timeout_s: float, step_s: float = 0.05) -> bool:
    deadline = time.monotonic() + timeout_s
    while time.monotonic() < deadline:
        if predicate():
            return True
        time.sleep(step_s)
    return bool(predicate())


def seq_report(seqs: list[int], first: int, last: int) -> dict[str, Any]:
    """What a consumer counting by seq sees of the records first..last: missing, duplicates, order of first arrivals."""
    seen: set[int] = set()
    order: list[int] = []
    for q in seqs:
        if q not in seen:
            seen.add(q)
            order.append(q)
    expected = set(range(first, last + 1))
    return {"expected": len(expected), "received": len(seen & expected), "missing": len(expected - seen),
            "duplicates": len(seqs) - len(seen), "in_order": order == sorted(order),
            "missing_seqs": sorted(expected - seen)[:10]}

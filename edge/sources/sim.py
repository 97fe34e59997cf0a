"""``sim://?people=2&seed=7`` — the virtual carpet, in-process, through the real protocol.

A :class:`~firmware_protocol.virtual_board.VirtualBoard` scans frames from the
simulator and speaks the wire protocol; this link hands its bytes to the same decoder
and frame assembly as a real board, so the demo exercises the whole path.
``speed=0`` runs as fast as frames can be made (a virtual clock), ``speed=1`` in real time.
In real time the next scene (every ``scene_s`` seconds the people start other activities
elsewhere) is placed ahead in a helper process (``sim.live.LiveCarpet(prefetch=True)``), so
the stream does not stop while it is placed; closing the link ends the helper.
"""

from __future__ import annotations

import time

from edge.sources.base import Link, LinkLost, Option, parse_bool, parse_url
from firmware_protocol import codec

SCHEME = "sim"
FORM = "sim://?people=2&seed=7&grid=96&rate=14&speed=1&world=bodies&scene_s=10"


def _grid(text: str) -> int:
    value = int(text)
    if not 4 <= value <= 512:
        raise ValueError("grid must be 4..512 sensels per side")
    return value


def _people(text: str) -> int:
    value = int(text)
    if not 0 <= value <= 3:
        raise ValueError("people must be 0..3")
    return value


def _world(text: str) -> str:
    if text not in ("bodies", "footsteps"):
        raise ValueError("world must be 'bodies' (simulated people: motion, contact physics, sensor model) "
                         "or 'footsteps' (walking feet only, cheap)")
    return text


def _bits(text: str) -> int:
    value = int(text)
    if value not in (8, 10, 12, 16):
        raise ValueError("bits must be 8, 10, 12 or 16")
    return value


def _positive_s(text: str) -> float:
    value = float(text)
    if not value > 0:
        raise ValueError("scene_s must be > 0 seconds")
    return value


def _activities(text: str) -> tuple[str, ...]:
    from sim.motion import ACTIVITIES
    from sim.motion.falls import SCENARIOS

    names = tuple(a.strip() for a in text.split(",") if a.strip())
    unknown = [a for a in names if a not in ACTIVITIES and a not in SCENARIOS]
    if unknown or not names:
        raise ValueError(f"activities: unknown {unknown or text!r}; known: {', '.join(ACTIVITIES + SCENARIOS)}")
    return names


OPTIONS = {
    "world": Option(_world, "bodies", "bodies = simulated people doing the paper's activities; footsteps = walking feet only"),
    "people": Option(_people, 1, "people on the carpet, 0..3"),
    "seed": Option(int, 0, "random seed of the scene and the sensor"),
    "grid": Option(_grid, 96, "sensels per side"),
    "pitch_mm": Option(float, 19.05, "sensel pitch in millimetres"),
    "rate": Option(float, 14.0, "frame rate in Hz"),
    "bits": Option(_bits, 12, "ADC bits per sample: 8, 10, 12 or 16 (footsteps world; bodies draws its own)"),
    "speed": Option(float, 1.0, "1 = real time, 0 = as fast as possible"),
    "faults": Option(parse_bool, False, "inject line noise now and then (bit flips, garbage, torn frames)"),
    "scene_s": Option(_positive_s, 10.0, "seconds of each simulated scene (bodies world): then new activities and places"),
    "activities": Option(_activities, "", "comma-separated activities and fall scenarios drawn per "
                         "scene (bodies world; default: the paper's ten and walking), e.g. fall_forward,lie_down"),
}



def packing_for(bits: int) -> int:
    return codec.PACKING["u8"] if bits <= 8 else codec.PACKING["packed12"] if bits <= 12 else codec.PACKING["u16"]


class SimLink(Link):
    def __init__(self, **opts) -> None:
        self.opts = opts
        # speed=0 runs a virtual clock as fast as the consumer takes frames: like a recording,
        # nothing is dropped for a slow consumer (a real-time sim drains to the newest frame)
        self.speed = opts["speed"]
        self.paced = opts["speed"] > 0
        self.board = None
        self._t0 = 0.0
        self._virtual_now = 0.0

    def describe(self) -> str:
        return "sim://"

    def open(self) -> None:
        from firmware_protocol.virtual_board import VirtualBoard

        o = self.opts
        if o["world"] == "footsteps":
            from sim.footsteps import FootstepCarpet

            carpet = FootstepCarpet(o["grid"], o["grid"], o["people"], o["seed"], o["pitch_mm"], o["rate"], o["bits"])
            bits, sign = o["bits"], -1
        else:
            from sim.live import LiveCarpet

            extra = {"activities": o["activities"]} if o["activities"] else {}
            carpet = LiveCarpet(o["grid"], o["grid"], o["people"], o["seed"], o["pitch_mm"], o["rate"], o["bits"],
                                chunk_s=o["scene_s"], prefetch=o["speed"] > 0, **extra)
            bits, sign = carpet.adc_bits, carpet.sign
        self.carpet = carpet
        tiles = 3 if o["grid"] % 3 == 0 else 1
        self.board = VirtualBoard(
            rows=o["grid"], cols=o["grid"], tile_rows=tiles, tile_cols=tiles, adc_bits=bits,
            packing=packing_for(bits), sign=sign, rate_hz=o["rate"], device_id=f"sim-{o['seed']}", frames=carpet,
        )
        self._t0 = time.monotonic()
        self._virtual_now = 0.0
        self._faults_at = 0

    def _now(self) -> float:
        if self.opts["speed"] <= 0:
            return self._virtual_now
        return (time.monotonic() - self._t0) * self.opts["speed"]

    def read(self, timeout_s: float) -> bytes:
        if self.board is None:
            raise LinkLost("closed")
        if self.opts["speed"] <= 0:
            self._virtual_now += 1.0 / self.opts["rate"]
            return self._maybe_fault(self.board.read(self._virtual_now))
        deadline = time.monotonic() + timeout_s
        while True:
            data = self.board.read(self._now())
            if data or time.monotonic() >= deadline:
                return self._maybe_fault(data)
            time.sleep(min(0.005, max(0.0, deadline - time.monotonic())))

    def _maybe_fault(self, data: bytes) -> bytes:
        if self.opts["faults"] and data:
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
            carpet.close()  # the live carpet's scene helper process


def open_link(url: str, **_: object) -> SimLink:
    _, opts = parse_url(url, SCHEME, FORM, OPTIONS)
    if opts["rate"] <= 0:
        raise ValueError(f"sim:// rate must be > 0. Form: {FORM}")
    return SimLink(**opts)

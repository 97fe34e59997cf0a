"""``sim://?people=2&seed=7`` — the virtual carpet, offered to edge as a source plug-in.

Registered in setup.cfg under the entry-point group ``cavatar.sources`` (``sim = sim.source``);
edge finds it through importlib.metadata and never imports sim (the contract is in
edge/sources/plugins.py). edge puts a virtual readout board in front of the carpet made here,
so its frames cross the real wire protocol, decoder and frame assembly.

- ``world=bodies``: simulated people doing the paper's activities (motion, contact physics,
  sensor model); every ``scene_s`` seconds they start other activities elsewhere. In real
  time (speed > 0) the next scene is placed ahead in a helper process
  (``sim.live.LiveCarpet(prefetch=True)``), which closing the carpet ends.
- ``world=footsteps``: walking feet only, cheap.
"""

from __future__ import annotations

from typing import Any

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


def _positive(name: str, unit: str):
    def parse(text: str) -> float:
        value = float(text)
        if not value > 0:
            raise ValueError(f"{name} must be > 0 {unit}")
        return value

    return parse


def _activities(text: str) -> tuple[str, ...]:
    from sim.motion import ACTIVITIES
    from sim.motion.falls import SCENARIOS

    names = tuple(a.strip() for a in text.split(",") if a.strip())
    unknown = [a for a in names if a not in ACTIVITIES and a not in SCENARIOS]
    if unknown or not names:
        raise ValueError(f"activities: unknown {unknown or text!r}; known: {', '.join(ACTIVITIES + SCENARIOS)}")
    return names


# name: (parse the text, default, what it means) — the plug-in contract of edge/sources/plugins.py
# (``bool`` reads 0/1, true/false, yes/no, on/off)
OPTIONS: dict[str, tuple[Any, Any, str]] = {
    "world": (_world, "bodies", "bodies = simulated people doing the paper's activities; footsteps = walking feet only"),
    "people": (_people, 1, "people on the carpet, 0..3"),
    "seed": (int, 0, "random seed of the scene and the sensor"),
    "grid": (_grid, 96, "sensels per side"),
    "pitch_mm": (float, 19.05, "sensel pitch in millimetres"),
    "rate": (_positive("rate", "Hz"), 14.0, "frame rate in Hz"),
    "bits": (_bits, 12, "ADC bits per sample: 8, 10, 12 or 16 (footsteps world; bodies draws its own)"),
    "speed": (float, 1.0, "1 = real time, 0 = as fast as possible"),
    "faults": (bool, False, "inject line noise now and then (bit flips, garbage, torn frames)"),
    "scene_s": (_positive("scene_s", "seconds"), 10.0,
                "least seconds of each simulated scene (bodies world; longer where an activity needs it at the "
                "person's own tempo, e.g. a push-up ~18 s): then new activities and places"),
    "activities": (_activities, "", "comma-separated activities and fall scenarios drawn per scene (bodies world; "
                   "default: the paper's ten and walking), e.g. fall_forward,lie_down"),
}


def open_carpet(opts: dict[str, Any]) -> tuple[Any, dict[str, Any]]:
    """The carpet of ``opts`` (parsed OPTIONS) and the virtual board that scans it.

    Returns ``(frames, board)``: ``frames`` is what the board scans (a FootstepCarpet or a LiveCarpet;
    a LiveCarpet also answers ``truth(k)`` and ``body``), ``board`` the board's rows, cols, tiles,
    ADC bits, sign, rate and device id."""
    o = opts
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
    tiles = 3 if o["grid"] % 3 == 0 else 1
    board = {"rows": o["grid"], "cols": o["grid"], "tile_rows": tiles, "tile_cols": tiles, "adc_bits": bits,
             "sign": sign, "rate_hz": o["rate"], "device_id": device_id(o)}
    return carpet, board


def calibration_sensor(opts: dict[str, Any]) -> Any:
    """The sensor model the automatic calibration acts on (calibration.actor.Actor drives it): the same
    carpet ``open_carpet(opts)`` scans. ValueError for the footsteps world, which has no sensor model."""
    if opts["world"] != "bodies":
        raise ValueError("automatic calibration runs on the simulated bodies world only (world=bodies); the "
                         "footsteps world has no sensor model to calibrate. Use world=bodies")
    from sim.live import live_sensor

    return live_sensor(opts["seed"], opts["grid"], opts["bits"], opts["pitch_mm"])


def device_id(opts: dict[str, Any]) -> str:
    """The device id the virtual board answers with."""
    return f"sim-{opts['seed']}"

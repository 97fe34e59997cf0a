"""Slow I²C peripherals of the host board: a temperature sensor and a gain potentiometer.

The runtime and calibration (auto-range) talk to two small interfaces,
:class:`TemperatureSensor` and :class:`GainControl`; one module per chip implements
them over any object with the smbus2 ``SMBus`` methods (a real bus from
:func:`edge.peripherals.i2c.open_bus`, or :class:`edge.peripherals.fakebus.FakeBus`).
Configuration picks a chip by name through :data:`CHIPS`::

    bus = open_bus(1)
    sensor = open_chip("tmp102", bus)            # TemperatureSensor at 0x48
    gain = open_chip("mcp4018", bus)             # GainControl at 0x2F
    sensor.read_temperature_c(); gain.set_gain_fraction(0.5)

Chip modules are imported on demand: one that fails to import is reported by
:func:`available_chips` and never breaks the others.
"""

from __future__ import annotations

import importlib
import math
from abc import ABC, abstractmethod
from typing import Any


class TemperatureSensor(ABC):
    """A board temperature sensor."""

    @abstractmethod
    def read_temperature_c(self) -> float:
        """Return the temperature in °C (blocks at most one conversion time)."""


class GainControl(ABC):
    """A stepped gain setting (e.g. a digital potentiometer in the front-end).

    The gain fraction is the position of the setting in its range, 0 (step 0) to
    1 (the last step), linear in steps. How it maps to amplifier gain depends on the
    front-end circuit; calibration measures that map.
    """

    step_count: int
    """Number of settable steps (positions 0 .. step_count-1)."""

    @abstractmethod
    def set_step(self, step: int) -> None:
        """Set the position, an integer in 0 .. step_count-1; otherwise ValueError."""

    @abstractmethod
    def step(self) -> int:
        """Read back the position from the chip."""

    def set_gain_fraction(self, fraction: float) -> int:
        """Set the nearest step to ``fraction`` (0..1) of full scale; return that step."""
        if isinstance(fraction, bool) or not isinstance(fraction, (int, float)) \
                or not math.isfinite(fraction) or not 0.0 <= fraction <= 1.0:
            raise ValueError(f"gain fraction must be a number in [0, 1], got {fraction!r}")
        step = round(fraction * (self.step_count - 1))
        self.set_step(step)
        return step

    def gain_fraction(self) -> float:
        """Read back the position as a fraction (0..1) of full scale."""
        return self.step() / (self.step_count - 1)


# chip name -> (interface, "module:Class"). Config and the CLI choose by name.
CHIPS: dict[str, tuple[type, str]] = {
    "tmp102": (TemperatureSensor, "edge.peripherals.tmp102:TMP102"),
    "mcp4018": (GainControl, "edge.peripherals.mcp4018:MCP4018"),
}


def _load(name: str) -> type:
    if name not in CHIPS:
        raise ValueError(f"unknown I²C chip {name!r}; accepted: {', '.join(sorted(CHIPS))}")
    module_name, class_name = CHIPS[name][1].split(":")
    return getattr(importlib.import_module(module_name), class_name)


def available_chips() -> dict[str, str | None]:
    """Map each chip name to None when its driver imports, else to the reason it does not."""
    status: dict[str, str | None] = {}
    for name in CHIPS:
        try:
            _load(name)
            status[name] = None
        except ImportError as exc:
            status[name] = str(exc)
    return status


def open_chip(name: str, bus: Any, address: int | None = None, **options: Any) -> Any:
    """Driver for chip ``name`` on ``bus`` at ``address`` (None: the chip's default).

    Returns a :class:`TemperatureSensor` or :class:`GainControl`; an unknown name is a
    ValueError listing the accepted names.
    """
    cls = _load(name)
    if address is not None:
        options["address"] = address
    return cls(bus, **options)


def chip_kind(name: str) -> type:
    """The interface (TemperatureSensor or GainControl) that chip ``name`` implements."""
    if name not in CHIPS:
        raise ValueError(f"unknown I²C chip {name!r}; accepted: {', '.join(sorted(CHIPS))}")
    return CHIPS[name][0]


__all__ = ["CHIPS", "GainControl", "TemperatureSensor", "available_chips", "chip_kind", "open_chip"]

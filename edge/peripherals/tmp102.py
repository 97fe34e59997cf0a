"""TMP102-class temperature sensor (TI TMP102, TMP112, TMP110 share the map).

Registers, chosen by the pointer byte (P1 P0), 16 bits each, sent MSB first::

    0x00 temperature (read-only)   0x01 configuration   0x02 T_LOW   0x03 T_HIGH

Temperature register, two's complement, 1 LSB = 0.0625 °C; D0 of byte 2 tells the mode::

    normal (EM=0), 12 bit:    byte1 = T11..T4   byte2 = T3 T2 T1 T0 0 0 0 0
    extended (EM=1), 13 bit:  byte1 = T12..T5   byte2 = T4 T3 T2 T1 T0 0 0 1

    e.g. +25.0625 °C -> 19 10;  -25 °C -> E7 00;  +150 °C (extended) -> 4B 01

Configuration register (power-up 0x60A0)::

    byte1: OS R1 R0 F1 F0 POL TM SD     byte2: CR1 CR0 AL EM 0 0 0 0

SD=1 stops conversions; then writing OS=1 runs one conversion and OS reads 1 when it
is done (typ. 26 ms, max 35 ms). smbus2's ``read_word_data`` is little-endian, so
this driver reads and writes registers as 2-byte I²C blocks, MSB first.
"""

from __future__ import annotations

import time
from typing import Any

from edge.peripherals import TemperatureSensor

REG_TEMPERATURE = 0x00
REG_CONFIG = 0x01
REG_T_LOW = 0x02
REG_T_HIGH = 0x03

CONFIG_OS = 1 << 15          # one-shot (write) / conversion ready (read)
CONFIG_SD = 1 << 8           # shutdown
CONFIG_EM = 1 << 4           # extended 13-bit mode

LSB_C = 0.0625
ADDRESSES = (0x48, 0x49, 0x4A, 0x4B)   # ADD0 to GND, V+, SDA, SCL
ONE_SHOT_TIMEOUT_S = 0.1               # datasheet max conversion time is 35 ms
POLL_INTERVAL_S = 0.005


def decode_temperature_c(msb: int, lsb: int) -> float:
    """Temperature in °C from the two register bytes; the format is read from D0 of lsb."""
    raw = (msb << 8) | lsb
    signed = raw - 0x10000 if raw & 0x8000 else raw
    shift = 3 if lsb & 0x01 else 4       # 13-bit extended, else 12-bit normal
    return (signed >> shift) * LSB_C


class TMP102(TemperatureSensor):
    """A TMP102 at ``address`` on ``bus`` (any object with the smbus2 SMBus methods).

    ``extended`` sets the 13-bit mode (range to +150 °C); ``shutdown`` stops continuous
    conversion, and each :meth:`read_temperature_c` then runs one one-shot conversion.
    None leaves the chip's current setting.
    """

    def __init__(self, bus: Any, address: int = 0x48, *, extended: bool | None = None,
                 shutdown: bool | None = None, sleep=time.sleep, clock=time.monotonic):
        if address not in ADDRESSES:
            raise ValueError(f"TMP102 address must be one of "
                             f"{', '.join(hex(a) for a in ADDRESSES)}, got {address!r}")
        self.bus, self.address = bus, address
        self._sleep, self._clock = sleep, clock
        config = self.read_config()
        if extended is not None:
            config = (config | CONFIG_EM) if extended else (config & ~CONFIG_EM)
        if shutdown is not None:
            config = (config | CONFIG_SD) if shutdown else (config & ~CONFIG_SD)
        if extended is not None or shutdown is not None:
            self.write_config(config & ~CONFIG_OS)

    def _read_register(self, register: int) -> tuple[int, int]:
        msb, lsb = self.bus.read_i2c_block_data(self.address, register, 2)
        return msb, lsb

    def read_config(self) -> int:
        """The 16-bit configuration register (byte 1 in the high 8 bits)."""
        msb, lsb = self._read_register(REG_CONFIG)
        return (msb << 8) | lsb

    def write_config(self, config: int) -> None:
        """Write the 16-bit configuration register, MSB first."""
        self.bus.write_i2c_block_data(self.address, REG_CONFIG, [(config >> 8) & 0xFF, config & 0xFF])

    @property
    def extended(self) -> bool:
        return bool(self.read_config() & CONFIG_EM)

    @property
    def shutdown(self) -> bool:
        return bool(self.read_config() & CONFIG_SD)

    def read_temperature_c(self) -> float:
        """Temperature in °C; in shutdown mode, run one conversion first and wait for it."""
        config = self.read_config()
        if config & CONFIG_SD:
            self.write_config(config | CONFIG_OS)
            deadline_s = self._clock() + ONE_SHOT_TIMEOUT_S
            while not self.read_config() & CONFIG_OS:
                if self._clock() > deadline_s:
                    raise TimeoutError(f"TMP102 at {self.address:#04x}: one-shot conversion "
                                       f"not ready after {ONE_SHOT_TIMEOUT_S * 1e3:.0f} ms")
                self._sleep(POLL_INTERVAL_S)
        return decode_temperature_c(*self._read_register(REG_TEMPERATURE))

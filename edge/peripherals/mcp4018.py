"""MCP4018-class 7-bit digital potentiometer (Microchip MCP4017/18/19), front-end gain.

One volatile register, the wiper, 128 steps (0 = terminal B .. 127 = full scale);
power-on value mid-scale, 0x3F. No register address: a write is the address byte and
one data byte, a read returns one data byte::

    write: S 0101111 0 A  x d6..d0 A P      (MSb of the data byte is don't-care)
    read:  S 0101111 1 A  0 d6..d0 N P      (MSb reads 0)

With smbus2 that is ``write_byte(addr, step)`` and ``read_byte(addr)``;
``write_byte_data`` would send two data bytes and leave the second on the wiper.
"""

from __future__ import annotations

import errno
from typing import Any

from edge.peripherals import GainControl

ADDRESS = 0x2F
STEP_MAX = 127


class MCP4018(GainControl):
    """The MCP4018 at ``address`` (fixed 0x2F on the part) on ``bus`` (smbus2 SMBus-like)."""

    step_count = STEP_MAX + 1

    def __init__(self, bus: Any, address: int = ADDRESS):
        if isinstance(address, bool) or not isinstance(address, int) or not 0 <= address <= 0x7F:
            raise ValueError(f"I²C address must be an integer in 0x00..0x7f, got {address!r}")
        self.bus, self.address = bus, address

    def set_wiper(self, step: int) -> None:
        """Set the wiper to ``step``, an integer in 0..127; otherwise ValueError."""
        if isinstance(step, bool) or not isinstance(step, int) or not 0 <= step <= STEP_MAX:
            raise ValueError(f"MCP4018 wiper step must be an integer in 0..{STEP_MAX}, got {step!r}")
        self.bus.write_byte(self.address, step)

    def wiper(self) -> int:
        """Read the wiper step (0..127) back from the chip."""
        value = self.bus.read_byte(self.address)
        if value & 0x80:  # the wiper register is 7 bits: a set MSb is not an MCP4018
            raise OSError(errno.EIO, f"MCP4018 at {self.address:#04x} returned {value:#04x} "
                          f"with bit 7 set; is another chip at that address?")
        return value

    set_step = set_wiper
    step = wiper

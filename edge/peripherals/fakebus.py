"""An emulated I²C bus with emulated chips, for tests and the virtual carpet.

:class:`FakeBus` has the smbus2 ``SMBus`` methods and turns each into the I²C messages
Linux i2c-dev puts on the wire (``read_word_data(a, r)`` = write [r], read 2 bytes,
low byte first; ``write_word_data`` sends the low byte first; block calls keep the
order). Chips see only those messages, so byte order is decided where it is on real
hardware. An address with no chip raises ``OSError(121, 'Remote I/O error')`` as the
kernel does on a NAK.

Emulations: :class:`FakeTMP102` and :class:`FakeMCP4018` (register maps as in the
datasheets, summarised in ``tmp102.py`` and ``mcp4018.py``).
"""

from __future__ import annotations

import collections
import ctypes
import errno
import os
import threading
import time
from abc import ABC, abstractmethod
from typing import Callable, Iterable

I2C_M_RD = 0x0001
BLOCK_MAX = 32


class FakeChip(ABC):
    """A device on the fake bus: it receives write messages and answers read messages."""

    @abstractmethod
    def write(self, data: bytes) -> None:
        """One write message (the bytes after the address byte; empty for a quick write)."""

    @abstractmethod
    def read(self, length: int) -> bytes:
        """One read message of ``length`` bytes."""


class FakeBus:
    """A bus holding chips by 7-bit address; thread-safe, one call = one transaction.

    ``log`` keeps the last 256 messages as ("w" | "r", address, bytes).
    """

    def __init__(self, chips: dict[int, FakeChip] | None = None):
        self.chips: dict[int, FakeChip] = dict(chips or {})
        self.log: collections.deque = collections.deque(maxlen=256)
        self.closed = False
        self._lock = threading.Lock()

    def _chip(self, address: int) -> FakeChip:
        if self.closed:
            raise OSError(errno.EBADF, os.strerror(errno.EBADF))
        if isinstance(address, bool) or not isinstance(address, int) or not 0 <= address <= 0x7F:
            raise OSError(errno.EINVAL, f"{os.strerror(errno.EINVAL)}: I²C address {address!r}")
        if address not in self.chips:
            raise OSError(errno.EREMOTEIO, os.strerror(errno.EREMOTEIO))
        return self.chips[address]

    def _transfer(self, address: int, write: Iterable[int] = (), read_length: int = 0) -> bytes:
        data = bytes(_check_byte(b) for b in write)
        with self._lock:
            chip = self._chip(address)
            if data or not read_length:
                chip.write(data)
                self.log.append(("w", address, data))
            if not read_length:
                return b""
            answer = bytes(chip.read(read_length))
            self.log.append(("r", address, answer))
            return answer

    # smbus2.SMBus methods (``force`` is accepted and ignored)
    def write_quick(self, i2c_addr, force=None):
        self._transfer(i2c_addr)

    def read_byte(self, i2c_addr, force=None):
        return self._transfer(i2c_addr, read_length=1)[0]

    def write_byte(self, i2c_addr, value, force=None):
        self._transfer(i2c_addr, [value])

    def read_byte_data(self, i2c_addr, register, force=None):
        return self._transfer(i2c_addr, [register], 1)[0]

    def write_byte_data(self, i2c_addr, register, value, force=None):
        self._transfer(i2c_addr, [register, value])

    def read_word_data(self, i2c_addr, register, force=None):
        low, high = self._transfer(i2c_addr, [register], 2)
        return low | (high << 8)

    def write_word_data(self, i2c_addr, register, value, force=None):
        if not 0 <= value <= 0xFFFF:
            raise ValueError(f"word value must be in 0..0xffff, got {value!r}")
        self._transfer(i2c_addr, [register, value & 0xFF, value >> 8])

    def read_i2c_block_data(self, i2c_addr, register, length, force=None):
        if not 1 <= length <= BLOCK_MAX:
            raise ValueError(f"block length must be in 1..{BLOCK_MAX}, got {length!r}")
        return list(self._transfer(i2c_addr, [register], length))

    def write_i2c_block_data(self, i2c_addr, register, data, force=None):
        if len(data) > BLOCK_MAX:
            raise ValueError(f"block length must be at most {BLOCK_MAX}, got {len(data)}")
        self._transfer(i2c_addr, [register, *data])

    def i2c_rdwr(self, *i2c_msgs):
        """Combined transaction of smbus2 ``i2c_msg`` objects (read buffers are filled)."""
        for msg in i2c_msgs:
            if msg.flags & I2C_M_RD:
                answer = self._transfer(msg.addr, read_length=msg.len)
                ctypes.memmove(msg.buf, answer, msg.len)
            else:
                self._transfer(msg.addr, bytes(msg))

    def close(self):
        self.closed = True

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


def _check_byte(value: int) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or not 0 <= value <= 0xFF:
        raise ValueError(f"byte value must be an integer in 0..255, got {value!r}")
    return value


class FakeTMP102(FakeChip):
    """TMP102 emulation. Set ``temperature_c`` (the die temperature, °C) from outside.

    Continuous mode converts on every read of the temperature register; shutdown mode
    holds the last result until a one-shot, which takes ``conversion_time_s`` on
    ``clock`` (OS reads 0 until then). The alert comparator is not emulated: AL reads
    inactive. A changed EM bit applies to the next read.
    """

    CONFIG_RESET = 0x60A0
    CONFIG_WRITABLE = 0x1FD0        # F1 F0 POL TM SD | CR1 CR0 EM
    OS, SD, POL, EM, RESOLUTION, AL = 1 << 15, 1 << 8, 1 << 10, 1 << 4, 0x6000, 1 << 5

    def __init__(self, temperature_c: float = 25.0, *, conversion_time_s: float = 0.0,
                 clock: Callable[[], float] = time.monotonic):
        self.temperature_c = temperature_c
        self.conversion_time_s, self.clock = conversion_time_s, clock
        self.pointer = 0
        self.config = self.CONFIG_RESET & self.CONFIG_WRITABLE
        self.limits = {0x02: 0x4B00, 0x03: 0x5000}   # T_LOW 75 °C, T_HIGH 80 °C
        self.held_c = temperature_c                  # last conversion, used in shutdown
        self.one_shot_done_at_s: float | None = None
        self.one_shot_ready = False

    def _convert(self) -> None:
        if self.one_shot_done_at_s is not None and self.clock() >= self.one_shot_done_at_s:
            self.held_c, self.one_shot_done_at_s, self.one_shot_ready = self.temperature_c, None, True
        if not self.config & self.SD:
            self.held_c = self.temperature_c

    def encode(self, temperature_c: float) -> int:
        """Register value for ``temperature_c`` in the current mode (saturating)."""
        bits = 13 if self.config & self.EM else 12
        count = max(-(1 << (bits - 1)), min((1 << (bits - 1)) - 1, round(temperature_c / 0.0625)))
        code = count & ((1 << bits) - 1)
        return (code << 3) | 0x1 if bits == 13 else code << 4

    def register(self, pointer: int) -> int:
        if pointer == 0x00:
            return self.encode(self.held_c)
        if pointer == 0x01:
            os_bit = self.OS if self.one_shot_ready else 0
            al_bit = 0 if self.config & self.POL else self.AL
            return os_bit | self.RESOLUTION | self.config | al_bit
        return self.limits[pointer]

    def write(self, data: bytes) -> None:
        self._convert()
        if not data:
            return
        self.pointer = data[0] & 0x03             # P7..P2 must be 0; only P1 P0 decode
        for index, byte in enumerate(data[1:3]):  # registers update byte by byte, MSB first
            shift = 8 if index == 0 else 0
            if self.pointer == 0x01:
                mask = self.CONFIG_WRITABLE & (0xFF << shift)
                self.config = (self.config & ~mask) | ((byte << shift) & mask)
                if shift == 8 and byte & 0x80 and self.config & self.SD:
                    self.one_shot_ready = False
                    self.one_shot_done_at_s = self.clock() + self.conversion_time_s
                    self._convert()
            elif self.pointer in self.limits:
                low_mask = 0xF8 if self.config & self.EM else 0xF0
                keep = 0x00FF if shift == 8 else 0xFF00
                value = (byte << 8) if shift == 8 else (byte & low_mask)
                self.limits[self.pointer] = (self.limits[self.pointer] & keep) | value

    def read(self, length: int) -> bytes:
        self._convert()
        value = self.register(self.pointer)
        return bytes(((value >> 8) & 0xFF, value & 0xFF)[i % 2] for i in range(length))


class FakeMCP4018(FakeChip):
    """MCP4018 emulation: a 7-bit wiper, power-on mid-scale (0x3F); each data byte
    written sets it (MSb ignored), each byte read returns it (MSb 0)."""

    def __init__(self, wiper_step: int = 0x3F):
        self.wiper_step = wiper_step & 0x7F

    @property
    def fraction(self) -> float:
        """Wiper position, 0 (terminal B) .. 1 (full scale)."""
        return self.wiper_step / 127

    def write(self, data: bytes) -> None:
        for byte in data:
            self.wiper_step = byte & 0x7F

    def read(self, length: int) -> bytes:
        return bytes([self.wiper_step]) * length


def demo_bus(temperature_c: float = 24.5) -> FakeBus:
    """A bus like the host board's: a TMP102 at 0x48 and an MCP4018 at 0x2F."""
    return FakeBus({0x48: FakeTMP102(temperature_c), 0x2F: FakeMCP4018()})

"""Opening a Linux I²C bus (``/dev/i2c-N``) with smbus2, with errors an installer can act on.

smbus2 is imported here only, on demand: without it the drivers and the fake bus
still work, and :func:`open_bus` says what is missing.
"""

from __future__ import annotations

import errno
import os
import re
from typing import Any

DEV_DIR = "/dev"


class I2CBusError(OSError):
    """An I²C bus that cannot be opened; the message names it and what to do."""

    def __str__(self) -> str:
        return self.strerror or super().__str__()


def list_buses(dev_dir: str = DEV_DIR) -> list[str]:
    """Paths of the I²C adapters in ``dev_dir`` (``/dev/i2c-N``), in bus-number order."""
    try:
        names = os.listdir(dev_dir)
    except OSError:
        return []
    numbered = [(int(m.group(1)), n) for n in names if (m := re.fullmatch(r"i2c-(\d+)", n))]
    return [os.path.join(dev_dir, n) for _, n in sorted(numbered)]


def bus_path(bus: int | str, dev_dir: str = DEV_DIR) -> str:
    """The device path of ``bus``: a number (1, "1") or a path ("/dev/i2c-1")."""
    if isinstance(bus, bool) or not isinstance(bus, (int, str)):
        raise ValueError(f"I²C bus must be a number or a path like /dev/i2c-1, got {bus!r}")
    if isinstance(bus, str) and bus.strip().isdigit():
        bus = int(bus)
    if isinstance(bus, int):
        if bus < 0:
            raise ValueError(f"I²C bus number must be >= 0, got {bus}")
        return os.path.join(dev_dir, f"i2c-{bus}")
    return bus


def open_bus(bus: int | str, *, dev_dir: str = DEV_DIR) -> Any:
    """Open I²C bus ``bus`` (number or path) and return an ``smbus2.SMBus``; caller closes it.

    Raises I2CBusError naming the bus, and listing the buses that exist when it is
    missing, not an adapter, or not permitted.
    """
    path = bus_path(bus, dev_dir)
    try:
        import smbus2
    except ImportError as exc:
        raise I2CBusError(f"cannot open I²C bus {path}: smbus2 is not installed ({exc}); "
                          "pip install smbus2") from exc
    smbus = smbus2.SMBus()
    try:
        try:
            smbus.open(path)
        except BaseException:
            smbus.close()  # open() keeps the descriptor when its capability ioctl fails
            raise
        return smbus
    except FileNotFoundError as exc:
        existing = ", ".join(list_buses(dev_dir)) or "none (enable I²C in the board's "\
            "device tree, then `modprobe i2c-dev`)"
        raise I2CBusError(errno.ENOENT, f"I²C bus {path} does not exist; "
                          f"existing I²C buses: {existing}") from exc
    except PermissionError as exc:
        raise I2CBusError(errno.EACCES, f"no permission to open I²C bus {path}; add the user "
                          "to the group that owns it (often 'i2c')") from exc
    except OSError as exc:  # e.g. ENOTTY: the ioctl of smbus2 failed on a non-adapter file
        existing = ", ".join(list_buses(dev_dir)) or "none"
        raise I2CBusError(exc.errno, f"{path} is not a usable I²C bus ({exc.strerror}); "
                          f"existing I²C buses: {existing}") from exc

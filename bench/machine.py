"""What machine a benchmark ran on: recorded in every bench/results/*.json."""

from __future__ import annotations

import os
import platform
from pathlib import Path


def cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def describe() -> dict:
    """Platform, CPU, core count, Python and numpy versions, and the load average now
    (absolute times on a shared machine move with its load)."""
    import numpy as np

    return {"platform": platform.platform(), "cpu_model": cpu_model(), "cpu_count": os.cpu_count(),
            "python": platform.python_version(), "numpy": np.__version__, "load_average_1_5_15_min": list(os.getloadavg())}

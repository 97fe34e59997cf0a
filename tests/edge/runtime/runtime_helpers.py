"""Helpers of the runtime tests (see conftest.py)."""

from __future__ import annotations

import json
import math
import re
from pathlib import Path
from typing import Any, Iterator

SEED = 7
GRID = 96
MARK_COUNT = 3001  # a raw reading written into one sensel of every frame
MARK_KPA = 7.654321  # a calibrated pressure written into the most loaded sensel of every frame


def truth_calibration(folder: Path) -> Path:
    """The calibration a perfect procedure would make for ``sim://?seed=SEED`` (from the simulator's true
    parameters: milliseconds, where the scripted session takes ~10 s at 96×96), saved in ``folder``."""
    from calibration.from_truth import calibration_from_truth
    from sim.live import live_sensor

    path = Path(folder) / f"calibration-sim-{SEED}.npz"
    calibration_from_truth(live_sensor(SEED, 96), device_id=f"sim-{SEED}").save(path)
    return path


def sim_url(people: int, **extra: Any) -> str:
    opts = {"people": people, "seed": SEED, "speed": 0, **extra}
    return "sim://?" + "&".join(f"{k}={v}" for k, v in opts.items())


def make_config(out: Path, calibration: Path, people: int = 2, **overrides: Any):
    from edge.runtime import RuntimeConfig

    values = {"source": sim_url(people), "calibration": str(calibration), "sinks": [f"jsonl://{out}/bodies.jsonl"],
              "status_file": str(out / "status.json")}
    values.update(overrides)
    return RuntimeConfig().with_overrides(**values)


def read_jsonl(path: Path) -> list[dict]:
    text = path.read_text()
    assert text == "" or text.endswith("\n"), "the last line is not complete"
    return [json.loads(line) for line in text.splitlines()]


def walk(obj: Any, path: str = "") -> Iterator[tuple[str, Any]]:
    """Every (path, value) of a JSON document, containers included."""
    yield path, obj
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield from walk(v, f"{path}.{k}")
    elif isinstance(obj, list):
        for i, v in enumerate(obj):
            yield from walk(v, f"{path}[{i}]")


def longest_number_array(obj: Any) -> int:
    """Length of the longest run of numbers in any array (nested arrays counted by their total numbers)."""
    best = 0
    for _, v in walk(obj):
        if isinstance(v, list):
            flat = _flatten(v)
            if flat and all(isinstance(x, (int, float)) and not isinstance(x, bool) for x in flat):
                best = max(best, len(flat))
    return best


def _flatten(v: Any) -> list:
    if isinstance(v, list):
        out = []
        for x in v:
            out.extend(_flatten(x))
        return out
    return [v]


PRESSURE_KEY = re.compile(r"pressure|kpa", re.I)


def pressure_keys(obj: Any) -> list[str]:
    return [f"{p}.{k}" for p, v in walk(obj) if isinstance(v, dict) for k in v if PRESSURE_KEY.search(str(k))]


def finite_numbers(obj: Any) -> bool:
    return all(math.isfinite(v) for _, v in walk(obj) if isinstance(v, float))

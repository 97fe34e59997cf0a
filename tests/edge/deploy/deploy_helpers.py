"""Helpers of the deployment tests (see conftest.py)."""

from __future__ import annotations

import configparser
import re
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[3]
DEPLOY = ROOT / "deploy"
GUIDE = ROOT / "docs" / "install-pi.md"
SIM_DEVICE = {"device_id": "sim-7", "rows": 96, "cols": 96, "adc_bits": 12, "sign": -1, "firmware": [1, 0, 0],
              "protocol_version": 1}


def make_calibration(created: str | None = None, grid: int = 96, **device: Any):
    """A valid calibration of the virtual carpet sim://?seed=7 (96×96, 12 bit), or of ``device`` overrides."""
    from calibration.file import Calibration

    dev = {**SIM_DEVICE, "rows": grid, "cols": grid, **device}
    shape = (grid, grid)
    kwargs = {"created": created} if created else {}
    return Calibration(baseline_counts=np.full(shape, 2048, np.float32), noise_counts=np.ones(shape, np.float32),
                       gain=np.ones(shape, np.float32), fault=np.zeros(shape, np.uint8), device=dev, pitch_m=0.01905,
                       **kwargs)


def write_config(path: Path, values: dict[str, dict[str, Any]]) -> Path:
    from edge.runtime.config_docs import toml_value

    lines = []
    for section, table in values.items():
        lines.append(f"[{section}]")
        lines += [f"{k} = {toml_value(v)}" for k, v in table.items()]
    path.write_text("\n".join(lines) + "\n")
    return path


def read_unit(path: Path = DEPLOY / "cavatar.service") -> configparser.ConfigParser:
    """The systemd unit as INI (keys case-sensitive, no interpolation; systemd allows no duplicates we use)."""
    unit = configparser.ConfigParser(interpolation=None, strict=True, empty_lines_in_values=False)
    unit.optionxform = str  # type: ignore[assignment]
    unit.read_string(path.read_text())
    return unit


def rules(path: Path = DEPLOY / "99-cavatar.rules") -> list[dict[str, str]]:
    """Each udev rule line as {KEY[{attr}] + operator: value}, comments and blanks left out."""
    out = []
    for line in path.read_text().splitlines():
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        pairs = re.findall(r'([A-Z_]+(?:\{[^}]+\})?)\s*(==|!=|\+=|:=|=)\s*"([^"]*)"', line)
        out.append({key + op: value for key, op, value in pairs})
    return out


def run_cli(argv: list[str], capsys) -> tuple[int, str]:
    """``cavatar ARGV`` in-process: (exit code, stdout + stderr)."""
    from edge.cli import main

    try:
        code = main(argv)
    except SystemExit as exc:  # --help and argparse errors
        code = exc.code if isinstance(exc.code, int) else 1
    out = capsys.readouterr()
    return code, out.out + out.err

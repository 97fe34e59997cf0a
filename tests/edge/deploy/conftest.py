"""Fixtures of the deployment tests: cheap calibrations and configurations in tmp dirs, a real mosquitto.

The calibration is built directly from arrays (flat baseline, unit gains): doctor only loads,
hashes, dates and compares it, so it needs no simulated carpet. The broker is the sink tests'
own (tests/edge/sinks/sink_helpers.py), imported, not copied.
"""

from pathlib import Path

import pytest
from deploy_helpers import make_calibration, write_config

from tests.edge.sinks.sink_helpers import brokers


@pytest.fixture
def calibration(tmp_path):
    """``calibration(**device_and_created)`` → the path of a saved calibration of the sim://?seed=7 carpet."""

    def make(name: str = "calibration.npz", **kwargs) -> Path:
        path = tmp_path / name
        make_calibration(**kwargs).save(path)
        return path

    return make


@pytest.fixture
def config(tmp_path, calibration):
    """``config(**sections)`` → a TOML file: sim://?seed=7, a calibration, a jsonl sink and the status file in tmp."""

    def make(**sections) -> Path:
        values = {
            "source": {"url": "sim://?people=1&seed=7"},
            "calibration": {"file": str(calibration())},
            "sinks": {"urls": [f"jsonl://{tmp_path}/out/bodies.jsonl"]},
            "runtime": {"status_file": str(tmp_path / "out" / "status.json")},
        }
        for name, table in sections.items():
            values.setdefault(name, {}).update(table)
        return write_config(tmp_path / "cavatar.toml", values)

    return make


@pytest.fixture
def make_broker(tmp_path):
    yield from brokers(tmp_path)

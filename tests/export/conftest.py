"""Shared fixtures of the export tests: a tiny simulated dataset (32×32, three subjects)."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def tiny_data(tmp_path_factory):
    from sim.dataset.generate import generate

    out = tmp_path_factory.mktemp("tiny32") / "data"
    generate(out, subjects=3, seconds_per_activity=1.5, grid=32, pitch_mm=19.05 * 3, seed=3, workers=1, progress=False,
             activities=("stepping", "squat", "lunge"))
    return out

"""The whole procedure on 48×48 and 32×32 carpets, and on a non-rectangular carpet."""

import numpy as np
import pytest

from calibration.actor import Actor
from calibration.file import FAULT
from calibration.providers import SimProvider
from calibration.session import Session
from sim.sensor import CarpetSensor, FaultConfig


def calibrate(sensor, tmp_path, **opts):
    actor = Actor(sensor, mass_kg=65.0, seed=sensor.seed)
    session = Session(tmp_path / "work")
    session.options.mass_kg = 65.0
    for k, v in opts.items():
        setattr(session.options, k, v)
    session.run(SimProvider(actor, out=lambda s: None))
    cal, val = session.finish(tmp_path / "cal.npz")
    return actor, session, cal, val


@pytest.mark.parametrize("grid", [48, 32])
def test_small_carpets_calibrate_unchanged(grid, tmp_path):
    sensor = CarpetSensor.random(40 + grid, grid=grid, faults=False)
    actor, session, cal, val = calibrate(sensor, tmp_path)
    assert cal.shape == (grid, grid) and cal.device["rows"] == grid
    assert val.ok, val.findings
    assert abs(val.numbers["force_error"]) <= 0.15
    assert session.result("walk").numbers["coverage_fraction"] > 0.85
    assert session.result("board").numbers["frames_used"] >= 10
    assert val.numbers["usable_fraction"] > 0.99


def test_non_rectangular_carpet_mask_from_file_and_from_the_walk(tmp_path):
    mask = np.ones((48, 48), bool)
    mask[:16, 32:] = False  # an L-shaped carpet: a corner cut away
    sensor = CarpetSensor.random(3, grid=48, faults=FaultConfig(mask=mask))
    np.save(tmp_path / "mask.npy", mask)
    actor, session, cal, val = calibrate(sensor, tmp_path, mask_path=str(tmp_path / "mask.npy"))
    assert ((cal.fault & FAULT["outside"]) > 0).sum() == (~mask).sum()
    assert ((cal.fault & FAULT["outside"]) > 0)[~mask].all()
    assert val.numbers["sensels"] == mask.sum()
    assert not (cal.fault[mask] & FAULT["dead"]).any()  # the cut corner is not reported as dead lines
    # without the file: the walk proposes the shape (the corner never responds)
    walk = session.result("walk")
    assert any("never stepped on" in f for f in walk.findings)
    from calibration.walk import coverage_walk
    e = session.result("empty")
    w = coverage_walk(session.capture("walk"), e.arrays["baseline_counts"], e.arrays["noise_counts"],
                      e.arrays["fault"], shape_from_walk=True)
    outside = (w.arrays["fault"] & FAULT["outside"]) > 0
    assert outside[~mask].mean() > 0.9 and outside[mask].mean() < 0.02

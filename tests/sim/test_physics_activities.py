"""Physics on every activity: the issue's criteria, on the motion the dataset really uses.

For each activity (one subject, a short sequence, the generator's own dynamics):
- the total vertical force equals m·(g + a_z) within 2 % wherever the body touches;
- in static moments (COM acceleration < 0.2 m/s²), the centre of pressure lies within
  1.5 cm of the COM's ground projection, and every still pose can balance (the motion keeps
  the COM over the support; before that, up to 30 % of still moments could not);
- no joint below the floor by more than 1 cm (foot slide is tested in test_motion_activities).
"""

import numpy as np
import pytest

from edge.body import BodyModel
from sim.contact import ContactModel, regional_tissue
from sim.contact.track import track_dynamics
from sim.dataset.generate import PAPER_ACTIVITIES
from sim.motion import Subject, person_track

RATE_HZ = 14.0


@pytest.fixture(scope="module")
def world():
    body = BodyModel.load("lite")
    return body, ContactModel(96, 96, pitch_m=0.01905), regional_tissue(body)


@pytest.mark.parametrize("activity", PAPER_ACTIVITIES + ("walking",))
def test_force_balance_and_floor_on_every_activity(world, activity):
    body, carpet, tissue = world
    subject = Subject.random(5, 11)
    track = person_track(subject, [activity], 4.0, RATE_HZ, rng=3, model=body, start_xy=(0.9, 0.9))
    n = len(track)
    out, dyn = track_dynamics(body, track)  # the generator's own mass model and smoothed acceleration
    assert out["joints"][..., 2].min() > -0.01
    mass, com, acc = dyn.mass_kg, dyn.com_m, dyn.acc_m_s2
    static, balanced, checked = 0, 0, 0
    for t in range(2, n - 2, 2):  # every other frame, away from the ends of the finite differences
        a = acc[t]
        still = np.linalg.norm(a) < 0.2
        res = carpet.pressure_kpa(out["vertices"][t], body.faces, mass, acc_z_m_s2=float(a[2]), com_m=com[t],
                                  static=still, tissue_kpa_per_mm=tissue)
        if res.airborne:
            continue
        checked += 1
        assert res.force_total_n == pytest.approx(mass * (9.81 + a[2]), rel=0.02)
        if still:
            static += 1
            if res.balanced or res.cop_error_m < 0.005:  # the audit's "reachable": within 5 mm
                balanced += 1
                assert np.linalg.norm(res.cop_total_m - com[t, :2]) < 0.015
    print(f"{activity}: {checked} frames checked, {static} still, {balanced} balanced")
    assert checked > 0.8 * len(range(2, n - 2, 2))
    if static:
        assert balanced == static, f"{activity}: only {balanced} of {static} still moments can balance"

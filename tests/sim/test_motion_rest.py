"""A body left on the floor comes to rest: its centre of mass over its supports, no lower pose nearby."""

import numpy as np
import pytest
from scipy.spatial import ConvexHull, QhullError

from edge.body import BodyModel
from sim.motion.falls import PRONE, SIDE, SUPINE
from sim.motion.rest import _Heights, _tilted, settle

THIN = np.array([0.28, -3.0, 1.55, 0.05, 0.7, 0.0, -0.45, -0.39, 0.26, 1.04])  # the clip edge of Subject.random


@pytest.fixture(scope="module")
def body():
    return BodyModel.load("lite")


def _com_outside_supports_m(heights, q) -> float:
    """How far the centre of mass's ground projection lies outside the hull of the vertices within 1 cm of the floor."""
    v, com = heights.posed(q[None])
    v, com = v[0], com[0]
    low = v[v[:, 2] < v[:, 2].min() + 0.01, :2]
    try:
        hull = ConvexHull(low)
    except QhullError:  # fewer than three supports that span an area
        return float("inf")
    return float((hull.equations[:, :2] @ com[:2] + hull.equations[:, 2]).max())


@pytest.mark.parametrize("name,p", [("side", SIDE), ("supine", SUPINE), ("prone", PRONE)])
@pytest.mark.parametrize("betas", [None, THIN], ids=["mean", "thin"])
def test_a_settled_body_rests_on_supports_around_its_centre_of_mass(body, name, p, betas):
    heights = _Heights(body, np.zeros(10) if betas is None else betas)
    q = settle(p, body, betas)
    assert _com_outside_supports_m(heights, q) <= 0.0
    h = heights(q[None])[0]
    assert h < heights(p[None])[0]
    # no small rigid tilt lowers it further (a rest, not a balance on an edge)
    for tilt in ((3, 0), (-3, 0), (0, 3), (0, -3)):
        assert heights(_tilted(q, tilt)[None])[0] > h - 1e-3


def test_settle_keeps_the_scripted_posture_when_it_already_rests(body):
    q = settle(SUPINE, body)
    assert np.abs(q[1:] - SUPINE[1:]).max() <= 30.0 + 1e-6  # joints give way by at most 30°
    assert np.array_equal(settle(SUPINE, body), q)  # cached and deterministic

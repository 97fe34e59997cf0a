"""Body mass and centre of mass from the closed mesh (divergence theorem)."""

import numpy as np
import pytest

from edge.body import BodyModel
from edge.body.poses import pose_aa
from sim.contact import body_mass_kg, mesh_centroid_m, mesh_report, mesh_volume_m3, subject_mass_kg


def _box(lo, hi):
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    v = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                  [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]], float)
    f = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                  [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])
    return v, f


@pytest.fixture(scope="module", params=["lite", "full"])
def body(request):
    return BodyModel.load(request.param)


def test_box_volume_centroid_mass_exact():
    v, f = _box((0.1, -0.2, 0.3), (0.5, 0.3, 0.4))
    assert mesh_volume_m3(v, f) == pytest.approx(0.4 * 0.5 * 0.1)
    np.testing.assert_allclose(mesh_centroid_m(v, f), [0.3, 0.05, 0.35], atol=1e-12)
    assert body_mass_kg(v, f, density_kg_m3=1000) == pytest.approx(20.0)
    rep = mesh_report(v, f)
    assert rep.closed and rep.boundary_edges == 0


def test_inward_or_open_meshes_are_caught():
    v, f = _box((0, 0, 0), (1, 1, 1))
    with pytest.raises(ValueError, match="not positive"):
        body_mass_kg(v, f[:, ::-1])
    rep = mesh_report(v, f[:-1])  # one face missing: a hole
    assert not rep.closed and rep.boundary_edges == 3
    flipped = f.copy()
    flipped[0] = flipped[0, ::-1]
    assert mesh_report(v, flipped).inconsistent_edges > 0


def test_body_mesh_is_closed_and_adult(body):
    v = body.forward(np.zeros(72), None, np.zeros(3), vertices=True)["vertices"][0]
    rep = mesh_report(v, body.faces)
    assert rep.closed, rep
    assert rep.adult_mass and 55.0 < rep.mass_kg < 80.0, rep.mass_kg


def test_mass_is_rigid_motion_invariant(body):
    m0 = subject_mass_kg(body)
    pose = np.zeros(72)
    pose[:3] = [0.3, -1.2, 2.0]
    v = body.forward(pose, None, np.array([1.0, 2.0, 0.5]), vertices=True)["vertices"][0]
    assert body_mass_kg(v, body.faces) == pytest.approx(m0, rel=1e-4)


def test_mass_over_random_shapes_is_sane(body):
    rng = np.random.default_rng(3)
    masses = [subject_mass_kg(body, rng.normal(size=10)) for _ in range(25)]
    assert min(masses) > 35.0 and max(masses) < 130.0, (min(masses), max(masses))
    assert np.std(masses) > 5.0  # shape changes mass
    tall = np.zeros(10)
    tall[0] = 2.0
    assert subject_mass_kg(body, tall) > subject_mass_kg(body, -tall) + 15.0


def test_lite_and_full_agree_on_mass():
    lite, full = BodyModel.load("lite"), BodyModel.load("full")
    for b0 in (-1.5, 0.0, 1.5):
        betas = np.zeros(10)
        betas[0] = b0
        assert subject_mass_kg(lite, betas) == pytest.approx(subject_mass_kg(full, betas), rel=0.05)


def test_com_of_upright_body_is_near_pelvis_height(body):
    v = body.forward(pose_aa("t_pose"), None, np.array([0.0, 0.0, 1.0]), vertices=True)["vertices"][0]
    com = mesh_centroid_m(v, body.faces)
    assert abs(com[0]) < 0.01 and abs(com[1]) < 0.05
    assert 0.85 < com[2] < 1.1  # pelvis at 1.0 m

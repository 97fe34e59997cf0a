"""Other grids and pitches, people partly off the carpet, several people."""

import numpy as np
import pytest

from edge.body import BodyModel
from sim.contact import G_M_S2, ContactModel, subject_mass_kg, tissue_stiffness
from sim.contact.scenes import grounded_vertices, scene_pose


@pytest.fixture(scope="module")
def lite():
    m = BodyModel.load("lite")
    return m, subject_mass_kg(m), tissue_stiffness(m)


GRIDS = [(96, 96, 0.01905), (48, 48, 0.0381), (32, 32, 0.05715), (72, 48, 0.025)]


@pytest.mark.parametrize("pose_name", ["t_pose", "sitting_on_floor", "push_up_flat_hands"])
def test_same_force_on_every_grid(lite, pose_name):
    model, mass, tissue = lite
    pose = scene_pose(model, pose_name)
    forces, cops = [], []
    for rows, cols, pitch in GRIDS:
        cm = ContactModel(rows, cols, pitch)
        v = grounded_vertices(model, pose, xy_m=(0.6, 0.9))
        res = cm.pressure_kpa(v, model.faces, mass, tissue_kpa_per_mm=tissue)
        assert res.pressure_kpa.shape == (rows, cols)
        forces.append(res.force_n)
        cops.append(res.cop_m)
        assert abs(res.force_n - mass * G_M_S2) < 0.02 * mass * G_M_S2
        # a crossing samples (0.5 pitch)² of each sensel: small contacts alias at coarse pitch
        tol = 0.05 if pitch < 0.02 else 0.4
        assert abs(res.sensel_force_n - res.force_n) < tol * res.force_n, (rows, res.sensel_force_n)
        whole = ContactModel(rows, cols, pitch, crossing_frac=1.0).pressure_kpa(v, model.faces, mass, tissue_kpa_per_mm=tissue)
        assert whole.sensel_force_n == pytest.approx(whole.force_n, rel=0.002)  # whole-sensel sampling keeps force
    assert np.ptp(forces) < 0.01 * forces[0]
    assert np.ptp(np.array(cops), axis=0).max() < 0.01  # the fine lattice differs slightly per pitch


def test_partly_off_the_carpet_loses_force_and_says_so(lite):
    model, mass, tissue = lite
    cm = ContactModel(96, 96, 0.01905)
    edge_x = 96 * 0.01905
    v = grounded_vertices(model, scene_pose(model, "t_pose"), xy_m=(edge_x, 0.9))  # one foot each side of the edge
    res = cm.pressure_kpa(v, model.faces, mass, tissue_kpa_per_mm=tissue)
    assert res.force_total_n == pytest.approx(mass * G_M_S2, rel=1e-4)
    assert 0.3 < res.off_carpet_fraction < 0.7
    assert res.force_n + res.force_off_carpet_n == pytest.approx(res.force_total_n)
    assert res.cop_m[0] < edge_x and res.cop_total_m[0] == pytest.approx(edge_x, abs=0.015)
    assert abs(res.sensel_force_n - res.force_n) < 0.05 * res.force_n  # the sensels see only the on-carpet foot
    away = cm.pressure_kpa(v + [1.0, 0, 0], model.faces, mass, tissue_kpa_per_mm=tissue)
    assert away.force_n == 0 and away.force_off_carpet_n == pytest.approx(mass * G_M_S2, rel=1e-4)
    assert not away.pressure_kpa.any() and np.isnan(away.cop_m).all()


def test_two_people_add_and_are_labelled(lite):
    model, mass, tissue = lite
    cm = ContactModel(96, 96, 0.01905)
    a = cm.pressure_kpa(grounded_vertices(model, scene_pose(model, "t_pose"), xy_m=(0.5, 0.5)), model.faces, mass, tissue_kpa_per_mm=tissue)
    b = cm.pressure_kpa(grounded_vertices(model, scene_pose(model, "sitting_on_floor"), xy_m=(0.6, 1.2), yaw_deg=90),
                        model.faces, 1.2 * mass, tissue_kpa_per_mm=tissue)
    scene = cm.scene([a, b])
    np.testing.assert_allclose(scene.pressure_kpa, a.pressure_kpa + b.pressure_kpa, rtol=1e-6)
    assert (scene.person_index[a.contact_mask] == 0).all() and (scene.person_index[b.contact_mask] == 1).all()
    assert (scene.person_index[~(a.contact_mask | b.contact_mask)] == -1).all()
    assert b.force_n == pytest.approx(1.2 * a.force_n, rel=1e-4)


def test_rug_blur_widens_and_lowers_peaks(lite):
    model, mass, tissue = lite
    v = grounded_vertices(model, scene_pose(model, "t_pose"))
    sharp = ContactModel(rug_sigma_mm=0.0).pressure_kpa(v, model.faces, mass, tissue_kpa_per_mm=tissue)
    soft = ContactModel(rug_sigma_mm=15.0).pressure_kpa(v, model.faces, mass, tissue_kpa_per_mm=tissue)
    assert soft.pressure_kpa.max() < sharp.pressure_kpa.max()
    assert soft.contact_mask.sum() > sharp.contact_mask.sum()
    assert soft.force_n == pytest.approx(sharp.force_n)


def test_bad_arguments_are_refused():
    with pytest.raises(ValueError):
        ContactModel(crossing_frac=0.0)
    with pytest.raises(ValueError):
        ContactModel(exponent=0.5)
    cm = ContactModel(8, 8, 0.02)
    v = np.zeros((4, 3))
    f = np.array([[0, 1, 2]])
    with pytest.raises(ValueError):
        cm.pressure_kpa(v, f, -1.0)
    with pytest.raises(ValueError):
        cm.pressure_kpa(np.full((4, 3), np.nan), f, 60.0)

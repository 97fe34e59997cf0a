"""Contact physics on the named poses and random poses: force, balance, magnitudes."""

import numpy as np
import pytest

from edge.body import BodyModel
from edge.body.poses import POSES
from sim.contact import G_M_S2, ContactModel, subject_mass_kg, tissue_stiffness
from sim.contact.scenes import SCENE_POSES, grounded_vertices, scene_pose

BALANCEABLE = [p for p in SCENE_POSES if p != "lunge"]


@pytest.fixture(scope="module")
def lite():
    m = BodyModel.load("lite")
    return m, subject_mass_kg(m), tissue_stiffness(m)


@pytest.fixture(scope="module")
def full():
    m = BodyModel.load("full")
    return m, subject_mass_kg(m), tissue_stiffness(m)


@pytest.fixture(scope="module")
def carpet():
    return ContactModel(96, 96, 0.01905)


def _run(carpet, body, pose_name, **kw):
    model, mass, tissue = body
    v = grounded_vertices(model, scene_pose(model, pose_name))
    return carpet.pressure_kpa(v, model.faces, mass, tissue_kpa_per_mm=tissue, keep_fine=True, **kw)


@pytest.mark.parametrize("pose_name", SCENE_POSES)
@pytest.mark.parametrize("acc_z", [0.0, 2.5, -4.0])
def test_force_equals_weight_plus_dynamics(carpet, lite, pose_name, acc_z):
    res = _run(carpet, lite, pose_name, acc_z_m_s2=acc_z, static=acc_z == 0.0)
    target = lite[1] * (G_M_S2 + acc_z)
    assert res.target_force_n == pytest.approx(target)
    assert abs(res.force_total_n - target) < 0.02 * target
    assert abs(res.force_n - target) < 0.02 * target  # whole body on the carpet
    assert res.force_off_carpet_n == pytest.approx(0.0, abs=1e-9)
    assert (res.pressure_kpa >= 0).all() and res.pressure_kpa.dtype == np.float32
    # the sensels see the same force as the fine field within the sampling error
    assert abs(res.sensel_force_n - res.force_n) < 0.05 * res.force_n


@pytest.mark.parametrize("pose_name", BALANCEABLE)
@pytest.mark.parametrize("which", ["lite", "full"])
def test_static_cop_is_under_the_com(carpet, lite, full, pose_name, which):
    res = _run(carpet, lite if which == "lite" else full, pose_name, static=True)
    assert res.balanced
    assert np.hypot(*(res.cop_total_m - res.com_m[:2])) < 0.015
    assert np.hypot(*(res.cop_m - res.com_m[:2])) < 0.015
    assert abs(res.force_total_n - res.target_force_n) < 0.02 * res.target_force_n


def test_lunge_without_static_balance_is_reported(carpet, lite):
    res = _run(carpet, lite, "lunge", static=True)
    assert not res.balanced and res.cop_error_m > 0.02  # COM outside the two feet's support
    assert np.abs(res.slope).max() == pytest.approx(carpet.max_slope)  # as close as the tilt bound allows
    free = _run(carpet, lite, "lunge", static=False)
    assert res.cop_error_m < np.hypot(*(free.cop_total_m - res.com_m[:2])) - 0.1
    assert abs(res.force_total_n - res.target_force_n) < 0.02 * res.target_force_n


def test_dynamic_frames_let_the_cop_leave_the_com(carpet, lite):
    res = _run(carpet, lite, "t_pose", static=False)
    assert res.target_cop_m is None and res.balanced
    assert np.hypot(*(res.cop_total_m - res.com_m[:2])) > 0.015  # uniform indentation: geometric COP
    assert (res.slope == 0).all()


def _fine_stats(res):
    area = (res.fine_pressure_kpa > 0).sum() * res.fine_cell_m ** 2
    return area * 1e4, res.force_total_n / area / 1000.0  # cm², kPa


@pytest.mark.parametrize("which", ["lite", "full"])
def test_standing_magnitudes(carpet, lite, full, which):
    res = _run(carpet, lite if which == "lite" else full, "t_pose")
    area_cm2, mean_kpa = _fine_stats(res)
    assert 200 <= area_cm2 <= 300 and 23 <= mean_kpa <= 34, (area_cm2, mean_kpa)
    # sensel scale (19.05 mm pitch): blur and partial sensels grow the area, lower the mean
    sens_area = res.contact_mask.sum() * carpet.pitch_m ** 2 * 1e4
    sens_mean = float(res.pressure_kpa[res.contact_mask].mean())
    assert area_cm2 < sens_area < 1.6 * area_cm2 and 14 <= sens_mean <= mean_kpa, (sens_area, sens_mean)
    assert 40 <= res.pressure_kpa.max() <= 90  # the note's sensel-scale peaks 60–80 kPa


@pytest.mark.parametrize("which", ["lite", "full"])
def test_sitting_magnitudes(carpet, lite, full, which):
    res = _run(carpet, lite if which == "lite" else full, "sitting_on_floor")
    area_cm2, mean_kpa = _fine_stats(res)
    assert 800 <= area_cm2 <= 1500 and 4.6 <= mean_kpa <= 8.6, (area_cm2, mean_kpa)


@pytest.mark.parametrize("which", ["lite", "full"])
def test_push_up_hands_carry_most_of_the_weight(carpet, lite, full, which):
    res = _run(carpet, lite if which == "lite" else full, "push_up_flat_hands")
    fine = res.fine_pressure_kpa
    ys = (np.arange(fine.shape[0]) + res.fine_origin[0] + 0.5) * res.fine_cell_m
    hands = ys[:, None] < res.com_m[1]  # head toward −y: the hands lie on that side of the COM
    f_hands = (fine * hands).sum() * res.fine_cell_m ** 2 * 1000.0
    share = f_hands / res.force_total_n
    assert 0.64 <= share <= 0.75, share
    hand_area = ((fine > 0) & hands).sum() * res.fine_cell_m ** 2
    hand_mean_kpa = f_hands / hand_area / 1000.0
    assert 22 <= hand_mean_kpa <= 50, hand_mean_kpa  # note: 22–43 kPa


def test_random_poses_shapes_places_and_headings(carpet, lite):
    model, _, tissue = lite
    rng = np.random.default_rng(11)
    bases = ["t_pose", "deep_squat", "arms_raised", "sitting_on_floor"]
    upper = ["spine1", "spine2", "spine3", "neck", "head", "left_shoulder", "right_shoulder",
             "left_elbow", "right_elbow", "left_collar", "right_collar"]
    names = list(model.joint_names)
    balanced = 0
    for k in range(12):
        pose = scene_pose(model, bases[k % len(bases)]).reshape(-1, 3).copy()
        for j in upper:
            pose[names.index(j)] += rng.normal(0, 0.15, 3)
        betas = rng.normal(0, 1, 10)
        mass = subject_mass_kg(model, betas)
        v = grounded_vertices(model, pose.reshape(-1), betas, xy_m=rng.uniform(0.5, 1.3, 2),
                              yaw_deg=rng.uniform(0, 360), sink_m=rng.uniform(0, 0.005))
        acc_z = rng.normal(0, 2.0)
        res = carpet.pressure_kpa(v, model.faces, mass, acc_z_m_s2=acc_z, tissue_kpa_per_mm=tissue)
        target = mass * (G_M_S2 + acc_z)
        assert abs(res.force_n - target) < 0.02 * target
        if res.balanced:
            balanced += 1
            assert np.hypot(*(res.cop_total_m - res.com_m[:2])) < 0.015
    assert balanced >= 10


def test_airborne_and_free_fall_give_no_pressure(carpet, lite):
    model, mass, tissue = lite
    v = grounded_vertices(model, scene_pose(model, "t_pose"))
    up = carpet.pressure_kpa(v + [0, 0, 0.1], model.faces, mass, tissue_kpa_per_mm=tissue)
    assert up.airborne and up.force_n == 0 and not up.pressure_kpa.any()
    fall = carpet.pressure_kpa(v, model.faces, mass, acc_z_m_s2=-G_M_S2, tissue_kpa_per_mm=tissue)
    assert fall.airborne and fall.force_n == 0


def test_pose_list_covers_the_body_models_named_poses():
    assert set(POSES) <= set(SCENE_POSES)

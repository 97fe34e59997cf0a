"""Body model on hard inputs: rotation edge angles, degenerate 6D rotations, extreme shapes.

Documented behaviour (docs/stability.md): every angle gives an exact rotation (2π and 100π the
rest pose); matrix → axis-angle round-trips to round-off next to π; degenerate 6D rotations give
a valid axis-angle (|θ| ≤ π); betas beyond ±5 are clamped with a BodyModelWarning; NaN raises.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from edge.body import SMPL_PARENTS, BodyModel, BodyModelWarning
from edge.body.rotations import axis_angle_to_matrix, matrix_to_axis_angle
from edge.infer.rotations import rot6d_to_axis_angle

AXIS = np.array([1.0, 2.0, -0.5]) / np.linalg.norm([1.0, 2.0, -0.5])
PI = np.pi
EDGE_ANGLES = {"0": 0.0, "1e-12": 1e-12, "pi": PI, "pi-1e-7": PI - 1e-7, "pi+1e-7": PI + 1e-7, "2pi": 2 * PI,
               "100pi": 100 * PI}


def reference_rotation(axis: np.ndarray, angle: float) -> np.ndarray:
    """cos θ·I + sin θ·[a]× + (1 − cos θ)·a aᵀ for a unit axis: no division, exact at every angle."""
    k = np.array([[0, -axis[2], axis[1]], [axis[2], 0, -axis[0]], [-axis[1], axis[0], 0]])
    return np.cos(angle) * np.eye(3) + np.sin(angle) * k + (1 - np.cos(angle)) * np.outer(axis, axis)


@pytest.fixture(scope="module", params=["lite", "full"])
def model(request):
    return BodyModel.load(request.param)


@pytest.mark.parametrize("name", list(EDGE_ANGLES))
def test_axis_angle_to_matrix_is_the_exact_rotation_at_edge_angles(name):
    angle = EDGE_ANGLES[name]
    r = axis_angle_to_matrix(angle * AXIS)
    assert np.isfinite(r).all()
    np.testing.assert_allclose(r @ r.T, np.eye(3), atol=1e-13)
    assert abs(np.linalg.det(r) - 1.0) < 1e-13
    np.testing.assert_allclose(r, reference_rotation(AXIS, angle), atol=1e-13)


@pytest.mark.parametrize("convert", [matrix_to_axis_angle, lambda r: matrix_to_axis_angle(r[None])[0]],
                         ids=["one", "batch"])
@pytest.mark.parametrize("delta", [1e-3, 1e-4, 5e-5, 1e-5, 1e-7, 1e-9, 0.0, -1e-9, -1e-7, -1e-5])
def test_matrix_to_axis_angle_round_trips_next_to_pi(convert, delta):
    angle = PI - delta
    r = axis_angle_to_matrix(angle * AXIS)
    aa = convert(r)
    assert np.isfinite(aa).all() and np.linalg.norm(aa) <= PI + 1e-12  # published angles are in [0, π]
    np.testing.assert_allclose(axis_angle_to_matrix(aa), r, atol=1e-12)
    if delta > 0:  # below π the axis-angle itself is unique
        np.testing.assert_allclose(aa, angle * AXIS, atol=1e-12)
    elif delta < 0:  # past π: the same rotation about the opposite axis, by 2π − angle
        np.testing.assert_allclose(aa, -(2 * PI - angle) * AXIS, atol=1e-12)
    else:  # exactly π: ±axis are the same rotation
        assert min(np.abs(aa - PI * AXIS).max(), np.abs(aa + PI * AXIS).max()) < 1e-12


def test_forward_at_edge_angles_keeps_every_bone_length_and_2pi_is_the_rest_pose(model):
    pose = np.stack([np.tile(angle * AXIS, 24) for angle in EDGE_ANGLES.values()])  # every joint at that angle
    out = model.forward(pose, vertices=True)
    joints = out["joints"]
    assert np.isfinite(joints).all() and np.isfinite(out["vertices"]).all()
    parents = np.array(SMPL_PARENTS[1:])
    bones = np.linalg.norm(joints[:, 1:] - joints[:, parents], axis=-1)
    np.testing.assert_allclose(bones, np.broadcast_to(bones[0], bones.shape), atol=1e-12)  # rigid chain at any angle
    names = list(EDGE_ANGLES)
    rest = joints[names.index("0")]
    for name in ("1e-12", "2pi", "100pi"):
        np.testing.assert_allclose(joints[names.index(name)], rest, atol=1e-11)


@pytest.mark.parametrize("beta", [5.0, -5.0, 50.0, -50.0, 1e6, -1e6])
def test_extreme_betas_are_clamped_to_the_limit_with_a_warning(model, beta):
    betas = np.full(10, beta)
    if abs(beta) <= model.betas_limit:
        with warnings.catch_warnings():
            warnings.simplefilter("error", BodyModelWarning)
            out = model.forward(np.zeros(72), betas, vertices=True)
    else:
        with pytest.warns(BodyModelWarning, match=r"beyond ±5 clamped"):
            out = model.forward(np.zeros(72), betas, vertices=True)
    clamped = model.forward(np.zeros(72), np.clip(betas, -5, 5), vertices=True)
    np.testing.assert_array_equal(out["joints"], clamped["joints"])
    assert np.isfinite(out["vertices"]).all()
    height = np.ptp(out["vertices"][0, :, 1])  # canonical Y-up at zero orientation
    assert 1.0 < height < 2.5, height  # a plausible body, not an 8-12 m inside-out one


def test_non_finite_body_inputs_raise_naming_the_argument(model):
    pose = np.zeros(72)
    pose[5] = np.nan
    with pytest.raises(ValueError, match=r"pose_aa contains 1 non-finite value.*nonfinite='zero'"):
        model.forward(pose)
    with pytest.raises(ValueError, match="betas contains 1 non-finite"):
        model.forward(np.zeros(72), np.array([np.inf] + [0.0] * 9))
    with pytest.warns(BodyModelWarning, match="replaced by 0"):
        out = model.forward(pose, nonfinite="zero")
    np.testing.assert_array_equal(out["joints"], model.forward(np.zeros(72))["joints"])


# 6D rotations as the head emits them: (first column, second column) per joint.
ROT90_Z = np.array([0.0, 1.0, 0.0, -1.0, 0.0, 0.0])  # columns y, −x: 90° about z


def test_zero_6d_is_the_identity():
    aa = rot6d_to_axis_angle(np.zeros((1, 6)))
    np.testing.assert_array_equal(aa, np.zeros((1, 3)))


def test_collinear_6d_columns_keep_the_first_column_and_give_a_valid_rotation():
    rng = np.random.default_rng(0)
    a1 = rng.normal(size=(20, 3))
    six = np.concatenate([a1, a1 * rng.normal(size=(20, 1))], -1)  # second column parallel (or anti-parallel)
    aa = rot6d_to_axis_angle(six)
    assert np.isfinite(aa).all() and (np.linalg.norm(aa, axis=1) <= PI + 1e-6).all()
    first = axis_angle_to_matrix(aa.astype(np.float64))[:, :, 0]
    np.testing.assert_allclose(first, a1 / np.linalg.norm(a1, axis=1, keepdims=True), atol=1e-6)


def test_huge_6d_is_scale_invariant_and_tiny_6d_fades_to_the_identity():
    np.testing.assert_allclose(rot6d_to_axis_angle(1e30 * ROT90_Z[None]), [[0, 0, PI / 2]], atol=1e-6)
    np.testing.assert_allclose(rot6d_to_axis_angle(ROT90_Z[None]), [[0, 0, PI / 2]], atol=1e-6)
    # columns shorter than 1e-6 are divided by 1e-6, not their norm: the rotation shrinks to I
    for scale in (1e-7, 1e-10, 1e-30):
        aa = rot6d_to_axis_angle(scale * ROT90_Z[None])
        assert np.isfinite(aa).all() and np.linalg.norm(aa) < PI / 2
    assert np.abs(rot6d_to_axis_angle(1e-30 * ROT90_Z[None])).max() < 1e-20


def test_nan_6d_stays_nan_here_and_is_refused_by_the_bundle_head():
    """rot6d_to_axis_angle is a pure conversion; ModelBundle.head refuses NaN outputs before it
    (tests/stability/test_infer_stability.py), so a NaN pose is never published."""
    six = np.tile(ROT90_Z, (2, 1))
    six[1, 2] = np.nan
    aa = rot6d_to_axis_angle(six)
    assert np.isfinite(aa[0]).all() and np.isnan(aa[1]).all()

"""Rodrigues hard cases (issue 3). Reference: scipy's Rotation (an independent implementation)."""

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from edge.body.rotations import axis_angle_to_matrix, sinc

AXIS = np.array([0.36, -0.48, 0.8])  # unit


def _is_rotation(r, tol=1e-12):
    return np.abs(r @ r.T - np.eye(3)).max() < tol and abs(np.linalg.det(r) - 1) < tol


def test_angle_exactly_zero_is_identity_exactly():
    """Angle 0 → exactly I (no 0/0; a naive float32 formula gives NaN here)."""
    r = axis_angle_to_matrix(np.zeros(3))
    assert np.array_equal(r, np.eye(3))
    assert np.array_equal(axis_angle_to_matrix(np.zeros(3, np.float32)), np.eye(3))


@pytest.mark.parametrize("v", [np.full(3, 1e-8), np.full(3, -1e-8), np.array([1e-8, 0, 0])])
def test_angle_1e_8_is_first_order(v):
    """|r| ~ 1e-8 → I + K + K²/2 (K = [r]×) to 2 ulp of 1, off-diagonal terms to 1e-22
    (the smplx formula gives NaN at (−1e-8,)*3 in float32)."""
    r = axis_angle_to_matrix(v)
    k = np.array([[0, -v[2], v[1]], [v[2], 0, -v[0]], [-v[1], v[0], 0]])
    expected = np.eye(3) + k + k @ k / 2
    assert np.abs(r - expected).max() <= 2.3e-16
    off = ~np.eye(3, dtype=bool)
    assert np.abs(r[off] - expected[off]).max() < 1e-22
    assert _is_rotation(r)


def test_pi_exactly():
    """θ = π → R = 2nnᵀ − I: a proper rotation that fixes the axis and flips the rest."""
    r = axis_angle_to_matrix(np.pi * AXIS)
    assert np.abs(r - (2 * np.outer(AXIS, AXIS) - np.eye(3))).max() < 1e-15
    assert _is_rotation(r)
    assert np.allclose(r @ AXIS, AXIS, atol=1e-15)


def test_just_under_pi_is_continuous_with_pi():
    """θ = π − 1e-9 differs from θ = π by ~1e-9 (no jump at the branch where axes flip)."""
    a = axis_angle_to_matrix((np.pi - 1e-9) * AXIS)
    b = axis_angle_to_matrix(np.pi * AXIS)
    assert np.abs(a - b).max() < 3e-9
    assert np.allclose(a, Rotation.from_rotvec((np.pi - 1e-9) * AXIS).as_matrix(), atol=1e-14)


@pytest.mark.parametrize("theta", [2 * np.pi + 0.3, 5 * np.pi, 7.0, 100.0])
def test_more_than_two_pi_wraps(theta):
    """θ > 2π is the same rotation as θ mod 2π."""
    r = axis_angle_to_matrix(theta * AXIS)
    wrapped = axis_angle_to_matrix(np.mod(theta, 2 * np.pi) * AXIS)
    assert np.abs(r - wrapped).max() < 1e-13
    assert _is_rotation(r)


def test_huge_angle_1e6_rad():
    """θ = 1e6 rad → a proper rotation equal to the angle reduced mod 2π to ~1e-10."""
    r = axis_angle_to_matrix(1e6 * AXIS)
    assert _is_rotation(r, tol=1e-12)
    wrapped = axis_angle_to_matrix(np.mod(1e6, 2 * np.pi) * AXIS)
    assert np.abs(r - wrapped).max() < 1e-9


def test_random_against_scipy_and_batched_shapes():
    """Arbitrary batches (…,3) agree with scipy to 1e-14."""
    rng = np.random.default_rng(3)
    v = rng.normal(size=(5, 7, 3)) * 2
    r = axis_angle_to_matrix(v)
    assert r.shape == (5, 7, 3, 3) and r.dtype == np.float64
    assert np.abs(r - Rotation.from_rotvec(v.reshape(-1, 3)).as_matrix().reshape(5, 7, 3, 3)).max() < 1e-14


def test_sinc_series_matches_direct_at_the_switch():
    """The Taylor branch below 1e-4 joins sin(x)/x without a step."""
    x = np.array([1e-4 * (1 - 1e-12), 1e-4 * (1 + 1e-12)])
    assert abs(sinc(x)[0] - sinc(x)[1]) < 1e-15
    assert sinc(np.array(0.0)) == 1.0


# ----------------------------------------------------------------------------- matrix → axis-angle, Euler (issue 15:
# the one conversion of the code base, used by edge.infer, edge.body.poses, sim and export)

def test_matrix_to_axis_angle_inverts_rodrigues_over_a_batch_at_every_angle():
    """A batch of every hard angle at once (0, tiny, ½π, the cos θ = 0 branch point, near π, π) gives each back."""
    from edge.body.rotations import matrix_to_axis_angle

    rng = np.random.default_rng(15)
    axes = rng.normal(size=(9, 3))
    axes /= np.linalg.norm(axes, axis=-1, keepdims=True)
    angles = np.array([0.0, 1e-12, 1e-5, 0.5, np.pi / 2 - 1e-9, np.pi / 2 + 1e-9, 2.5, np.pi - 1e-7, np.pi - 1e-3])
    rotvecs = axes * angles[:, None]
    aa = matrix_to_axis_angle(axis_angle_to_matrix(rotvecs).reshape(3, 3, 3, 3))  # leading axes kept
    assert aa.shape == (3, 3, 3)
    np.testing.assert_allclose(aa.reshape(9, 3), rotvecs, atol=1e-12, rtol=0)


def test_matrix_to_axis_angle_agrees_with_scipy_and_keeps_angles_in_0_pi():
    from edge.body.rotations import matrix_to_axis_angle

    r = Rotation.random(500, random_state=3)
    aa = matrix_to_axis_angle(r.as_matrix())
    assert np.linalg.norm(aa, axis=-1).max() <= np.pi + 1e-12
    np.testing.assert_allclose(axis_angle_to_matrix(aa), r.as_matrix(), atol=1e-13)
    np.testing.assert_allclose(aa, r.as_rotvec(), atol=1e-10)


def test_exactly_pi_gives_the_axis_up_to_its_sign():
    from edge.body.rotations import matrix_to_axis_angle

    aa = matrix_to_axis_angle(2 * np.outer(AXIS, AXIS) - np.eye(3))
    assert min(np.abs(aa - np.pi * AXIS).max(), np.abs(aa + np.pi * AXIS).max()) < 1e-15


def test_euler_xyz_is_rx_then_ry_then_rz_and_its_axis_angle_round_trips():
    from edge.body.rotations import euler_xyz_deg_to_axis_angle, euler_xyz_deg_to_matrix

    deg = np.array([[30.0, -45.0, 120.0], [90.0, 0.0, 0.0], [0.0, 0.0, 0.0], [179.0, 10.0, -170.0]])
    x, y, z = (np.radians(deg[:, i]) for i in range(3))
    unit = np.eye(3)
    expected = (axis_angle_to_matrix(x[:, None] * unit[0]) @ axis_angle_to_matrix(y[:, None] * unit[1])
                @ axis_angle_to_matrix(z[:, None] * unit[2]))
    np.testing.assert_allclose(euler_xyz_deg_to_matrix(deg), expected, atol=1e-14)
    np.testing.assert_allclose(euler_xyz_deg_to_matrix(deg), Rotation.from_euler("XYZ", deg, degrees=True).as_matrix(),
                               atol=1e-14)  # scipy's intrinsic XYZ: the same convention
    np.testing.assert_allclose(axis_angle_to_matrix(euler_xyz_deg_to_axis_angle(deg)), expected, atol=1e-13)
    np.testing.assert_allclose(euler_xyz_deg_to_axis_angle(deg[1]), [np.pi / 2, 0, 0], atol=1e-15)  # upright

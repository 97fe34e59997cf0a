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

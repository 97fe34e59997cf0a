"""The indentation-plane solve and the sensel sampling on their own, with known answers."""

import numpy as np
import pytest

from sim.contact.plane import solve_height, solve_plane
from sim.contact.raster import LowestSurface
from sim.contact.sampling import sample_sensels, sampling_kernel


@pytest.mark.parametrize("exponent", [1.0, 1.5])
def test_uniform_indentation_carries_the_target_force(exponent):
    rng = np.random.default_rng(0)
    z = rng.uniform(0.0, 0.02, 500)
    kk = rng.uniform(1e5, 1e6, 500)
    h = solve_height(z, kk, 700.0, exponent)
    assert (kk * np.maximum(h - z, 0.0) ** exponent).sum() == pytest.approx(700.0, rel=1e-6)


def _flat_square(n_cells=40, cell_m=0.005, compliance_mm_per_kpa=0.5):
    z = np.zeros((n_cells, n_cells))
    return LowestSurface(z_m=z, attr=np.full_like(z, compliance_mm_per_kpa), origin=(10, 10), cell_m=cell_m,
                         samples=z.size)


def _cop_and_force(sol):
    jj, ii, z, kk, dx, dy = sol["cells"]
    d = np.maximum(sol["h"] + sol["sx"] * dx + sol["sy"] * dy - z, 0.0)
    f = kk * d
    return np.array([f @ dx, f @ dy]) / f.sum() + sol["ref"], f.sum()


def test_a_cop_target_inside_the_support_is_reached_by_tilting():
    surf = _flat_square()  # x, y ∈ [0.05, 0.25) m
    target = np.array([0.17, 0.12])
    sol = solve_plane(surf, 0.0, 0.05, 600.0, target, 1.0, surf.cell_m, 0.25)
    cop, force = _cop_and_force(sol)
    assert sol["balanced"] and sol["sx"] > 0 and sol["sy"] < 0
    assert force == pytest.approx(600.0, rel=1e-5)
    np.testing.assert_allclose(cop, target, atol=1e-4)


def test_a_cop_target_outside_the_support_stops_at_the_tilt_bound_with_the_force_exact():
    surf = _flat_square()
    sol = solve_plane(surf, 0.0, 0.05, 600.0, np.array([0.40, 0.15]), 1.0, surf.cell_m, 0.05)
    _, force = _cop_and_force(sol)
    assert not sol["balanced"]
    assert sol["sx"] == pytest.approx(0.05)
    assert force == pytest.approx(600.0, rel=1e-9)


def test_without_a_target_the_plane_stays_level():
    surf = _flat_square()
    sol = solve_plane(surf, 0.0, 0.05, 600.0, None, 1.0, surf.cell_m, 0.25)
    assert sol["balanced"] and sol["iterations"] == 0 and sol["sx"] == sol["sy"] == 0.0
    np.testing.assert_allclose(sol["ref"], [0.15, 0.15])


def _kernels(pad=4):
    ky = sampling_kernel(8, 0.02, 0.005, pad, 0.0, 0.02)  # whole-sensel crossings, no blur
    kx = sampling_kernel(6, 0.02, 0.005, pad, 0.0, 0.02)
    return ky, kx, pad


def test_sampling_a_field_on_the_carpet_keeps_its_force():
    ky, kx, pad = _kernels()
    fine = np.random.default_rng(1).uniform(0.0, 10.0, (7, 5))
    sensels = sample_sensels(fine, (9, 3), ky, kx, pad)
    assert sensels.shape == (8, 6)
    assert sensels.sum() * 0.02 ** 2 == pytest.approx(fine.sum() * 0.005 ** 2, rel=1e-12)


def test_sampling_drops_what_lies_beyond_the_carpet():
    ky, kx, pad = _kernels()
    fine = np.ones((4, 4))
    assert not sample_sensels(fine, (-40, 0), ky, kx, pad).any()  # beyond the kernels' reach
    half_off = sample_sensels(fine, (-2, 0), ky, kx, pad)  # two of four rows off the carpet
    assert half_off.sum() * 0.02 ** 2 == pytest.approx(8 * 0.005 ** 2, rel=1e-12)

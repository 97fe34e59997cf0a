"""The contact solve, rasteriser and sensel sampling on shapes with known answers."""

import numpy as np
import pytest

from sim.contact import ContactModel, lowest_surface, sampling_kernel


def _box(lo, hi):
    x0, y0, z0 = lo
    x1, y1, z1 = hi
    v = np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                  [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]], float)
    f = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                  [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])
    return v, f


def _sphere(r, centre, n=40):
    th = np.linspace(0, np.pi, n + 1)[1:-1]
    ph = np.linspace(0, 2 * np.pi, 2 * n, endpoint=False)
    t, p = np.meshgrid(th, ph, indexing="ij")
    pts = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)], -1).reshape(-1, 3)
    v = np.vstack([[0, 0, 1], pts, [0, 0, -1]]) * r + centre
    rings, seg = n - 1, 2 * n
    idx = lambda i, j: 1 + i * seg + (j % seg)  # noqa: E731
    f = [[0, idx(0, j), idx(0, j + 1)] for j in range(seg)]
    for i in range(rings - 1):
        for j in range(seg):
            f += [[idx(i, j), idx(i + 1, j), idx(i + 1, j + 1)], [idx(i, j), idx(i + 1, j + 1), idx(i, j + 1)]]
    last = len(v) - 1
    f += [[idx(rings - 1, j), last, idx(rings - 1, j + 1)] for j in range(seg)]
    return v, np.array(f)


def test_sphere_mesh_orientation_is_outward():
    from sim.contact import mesh_volume_m3
    v, f = _sphere(0.1, np.zeros(3))
    assert mesh_volume_m3(v, f) == pytest.approx(4 / 3 * np.pi * 0.1 ** 3, rel=0.01)


def test_raster_box_bottom_only_and_exact_height():
    v, f = _box((0.1, 0.2, 0.01), (0.3, 0.25, 0.2))
    attr = 10 * v[:, 0] + 3 * v[:, 1] + 100 * v[:, 2]  # affine: interpolation must be exact
    s = lowest_surface(v, f, attr, z_max=0.05, cell_m=0.005)
    ok = np.isfinite(s.z_m)
    assert ok.sum() == 40 * 10  # 20 cm × 5 cm of 5 mm cells, bottom face only
    np.testing.assert_allclose(s.z_m[ok], 0.01)
    xs, ys = s.centres()
    np.testing.assert_allclose(s.attr, 10 * xs[None, :] + 3 * ys[:, None] + 1.0, atol=1e-9)


def test_raster_sphere_follows_the_cap():
    r, c = 0.15, np.array([0.5, 0.5, 0.15])
    v, f = _sphere(r, c, n=60)
    s = lowest_surface(v, f, np.ones(len(v)), z_max=0.03, cell_m=0.004)
    xs, ys = s.centres()
    rho2 = (xs[None, :] - c[0]) ** 2 + (ys[:, None] - c[1]) ** 2
    ok = np.isfinite(s.z_m)
    exact = c[2] - np.sqrt(np.maximum(r * r - rho2, 0))
    assert np.abs(s.z_m[ok] - exact[ok]).max() < 0.002  # chordal error of the tessellation
    inside = rho2 < (0.9 * np.sqrt(2 * r * 0.03 - 0.03 ** 2)) ** 2
    assert ok[inside].all()  # no holes inside the cap


def test_flat_box_gives_uniform_pressure_force_over_area():
    cm = ContactModel(64, 64, 0.02, cell_mm=5.0, rug_sigma_mm=0.0, crossing_frac=1.0, rug_kpa_per_mm=1e9)
    v, f = _box((0.4, 0.4, 0.0), (0.8, 0.6, 0.3))
    res = cm.pressure_kpa(v, f, 50.0, static=False, tissue_kpa_per_mm=3.0, keep_fine=True)
    p_expected = 50 * 9.81 / (0.4 * 0.2) / 1000.0  # kPa
    assert res.force_n == pytest.approx(50 * 9.81, rel=1e-6)
    inner = res.pressure_kpa[21:29, 21:39]
    np.testing.assert_allclose(inner, p_expected, rtol=1e-6)
    assert res.contact_area_m2 == pytest.approx(0.08, rel=1e-6)
    assert res.sensel_force_n == pytest.approx(res.force_n, rel=1e-6)  # whole-sensel sampling keeps force


def test_off_centre_com_tilts_the_plane_and_moves_the_cop():
    cm = ContactModel(64, 64, 0.02, cell_mm=5.0, rug_sigma_mm=0.0, crossing_frac=1.0)
    v, f = _box((0.4, 0.4, 0.0), (0.8, 0.6, 0.3))
    com = np.array([0.7, 0.47, 0.5])
    res = cm.pressure_kpa(v, f, 60.0, com_m=com, static=True, tissue_kpa_per_mm=2.0, keep_fine=True)
    assert res.balanced
    np.testing.assert_allclose(res.cop_total_m, com[:2], atol=1e-4)
    assert res.force_total_n == pytest.approx(60 * 9.81, rel=1e-5)
    fine = res.fine_pressure_kpa
    row = fine[fine.shape[0] // 2]
    row = row[row > 0]
    assert row[-1] > row[0]  # heavier under the COM's side: linear ramp from the tilt
    free = cm.pressure_kpa(v, f, 60.0, com_m=com, static=False, tissue_kpa_per_mm=2.0)
    np.testing.assert_allclose(free.cop_total_m, [0.6, 0.5], atol=1e-3)  # uniform: geometric centre
    assert np.hypot(*(free.cop_total_m - com[:2])) > 0.05


def test_com_outside_support_is_reported_not_hidden():
    cm = ContactModel(64, 64, 0.02, rug_sigma_mm=0.0)
    v, f = _box((0.4, 0.4, 0.0), (0.6, 0.6, 0.3))
    res = cm.pressure_kpa(v, f, 60.0, com_m=np.array([0.9, 0.5, 0.5]), static=True)
    assert not res.balanced and res.cop_error_m > 0.25
    assert np.abs(res.slope).max() == pytest.approx(cm.max_slope)
    np.testing.assert_array_less(res.cop_total_m[0], 0.6 + 1e-9)  # at most the support's edge
    assert res.force_total_n == pytest.approx(60 * 9.81, rel=1e-5)


def test_horizontal_acceleration_moves_the_target_cop():
    cm = ContactModel(64, 64, 0.02, rug_sigma_mm=0.0)
    v, f = _box((0.4, 0.4, 0.0), (0.8, 0.8, 0.3))
    com = np.array([0.6, 0.6, 0.9])
    res = cm.pressure_kpa(v, f, 70.0, com_m=com, acc_xy_m_s2=[1.0, -0.5], acc_z_m_s2=1.0)
    expect = com[:2] - 0.9 * np.array([1.0, -0.5]) / (9.81 + 1.0)
    np.testing.assert_allclose(res.target_cop_m, expect)
    np.testing.assert_allclose(res.cop_total_m, expect, atol=1e-4)
    assert res.force_total_n == pytest.approx(70 * (9.81 + 1.0), rel=1e-5)


@pytest.mark.parametrize("sigma", [0.0, 0.005])
def test_sampling_kernel_whole_sensel_partitions_force(sigma):
    k = sampling_kernel(32, 0.02, 0.005, pad=10, sigma_m=sigma, width_m=0.02)
    # interior cells: their force lands on the sensels exactly (cell width / pitch each)
    col_sums = k.sum(0)[10 + 20:10 + 32 * 4 - 20]
    np.testing.assert_allclose(col_sums, 0.005 / 0.02, rtol=1e-9)
    half = sampling_kernel(32, 0.02, 0.005, pad=10, sigma_m=sigma, width_m=0.01)
    np.testing.assert_allclose(half.sum(1)[2:-2], 1.0, rtol=1e-6)  # a uniform field reads as itself
    assert (half >= 0).all()


@pytest.mark.parametrize("exponent", [1.0, 1.5, 2.0])
def test_sphere_into_foam_force_cop_and_hertz_like_growth(exponent):
    cm = ContactModel(64, 64, 0.02, rug_sigma_mm=0.0, exponent=exponent)
    v, f = _sphere(0.12, np.array([0.64, 0.64, 0.12]), n=60)
    light = cm.pressure_kpa(v, f, 20.0, static=True, tissue_kpa_per_mm=1.0, keep_fine=True)
    heavy = cm.pressure_kpa(v, f, 80.0, static=True, tissue_kpa_per_mm=1.0, keep_fine=True)
    for res, mass in ((light, 20.0), (heavy, 80.0)):
        assert res.force_total_n == pytest.approx(mass * 9.81, rel=1e-4)
        assert res.balanced and res.cop_error_m < 1e-4
        np.testing.assert_allclose(res.cop_total_m, [0.64, 0.64], atol=0.002)  # symmetric body
    assert heavy.contact_area_m2 > light.contact_area_m2 and heavy.indentation_mm > light.indentation_mm
    # Winkler foundation under a sphere: F ∝ d^(n+1), so 4× force → d × 4^(1/(n+1))
    ratio = heavy.indentation_mm / light.indentation_mm
    assert ratio == pytest.approx(4.0 ** (1.0 / (exponent + 1.0)), rel=0.05)


@pytest.mark.parametrize("mass_kg, depth_mm", [
    (5.0, 5 * 9.81 / 0.08 / 1000 / 0.5),  # light: the soft bed alone (d below the 5 mm layer)
    (50.0, (50 * 9.81 / 0.08 / 1000 + 3.0 * 5.0) / 3.5),  # heavy: 0.5·d + 3·(d − 5) = p
])
def test_a_soft_layer_is_a_soft_bed_on_the_skin_over_the_deep_one(mass_kg, depth_mm):
    from sim.contact import Tissue
    cm = ContactModel(64, 64, 0.02, cell_mm=5.0, rug_sigma_mm=0.0, crossing_frac=1.0, rug_kpa_per_mm=1e9)
    v, f = _box((0.4, 0.4, 0.0), (0.8, 0.6, 0.3))
    tissue = Tissue(np.full(len(v), 3.0), np.full(len(v), 5.0), soft_kpa_per_mm=0.5)
    res = cm.pressure_kpa(v, f, mass_kg, static=False, tissue_kpa_per_mm=tissue, keep_fine=True)
    assert res.indentation_mm == pytest.approx(depth_mm, rel=1e-6)
    np.testing.assert_allclose(res.pressure_kpa[21:29, 21:39], mass_kg * 9.81 / 0.08 / 1000, rtol=1e-6)
    assert res.contact_area_m2 == pytest.approx(0.08, rel=1e-6)  # a cell with two beds is one cell
    assert res.force_n == pytest.approx(mass_kg * 9.81, rel=1e-6)


def test_a_soft_layer_spreads_a_round_body_wider_and_keeps_its_peak():
    from sim.contact import Tissue
    cm = ContactModel(64, 64, 0.02, cell_mm=5.0, rug_sigma_mm=0.0, crossing_frac=1.0)
    v, f = _sphere(0.15, (0.64, 0.64, 0.15))
    stiff = cm.pressure_kpa(v, f, 30.0, tissue_kpa_per_mm=2.0)
    soft = cm.pressure_kpa(v, f, 30.0, tissue_kpa_per_mm=Tissue(np.full(len(v), 2.0), np.full(len(v), 20.0), 0.15))
    assert soft.force_n == pytest.approx(stiff.force_n, rel=1e-6) and soft.balanced
    assert soft.contact_area_m2 > 1.5 * stiff.contact_area_m2
    assert soft.pressure_kpa.max() == pytest.approx(stiff.pressure_kpa.max(), rel=0.1)  # the deep bed under the centre
    with pytest.raises(ValueError, match="soft layer"):
        cm.pressure_kpa(v, f, 30.0, tissue_kpa_per_mm=Tissue(np.full(len(v), 2.0), np.full(len(v), -1.0), 0.15))

"""edge.infer's numpy parts: rotations, normalisation, centre of pressure, and no torch on the board."""

from __future__ import annotations

import subprocess
import sys

import numpy as np

from edge.body.rotations import axis_angle_to_matrix, matrix_to_axis_angle
from edge.infer.normalise import center_of_pressure_m, normalise_kpa
from edge.infer.rotations import rot6d_to_axis_angle, rot6d_to_matrix


def test_axis_angle_round_trip_including_zero_and_pi():
    rng = np.random.default_rng(1)
    axes = rng.normal(size=(500, 3))
    aa = axes / np.linalg.norm(axes, axis=1, keepdims=True) * rng.uniform(0, np.pi, (500, 1))
    aa[0], aa[1], aa[2] = 0.0, [np.pi, 0, 0], [0, 1e-9, 0]
    r = np.stack([axis_angle_to_matrix(a) for a in aa])
    back = np.stack([axis_angle_to_matrix(a) for a in matrix_to_axis_angle(r)])
    np.testing.assert_allclose(back, r, atol=1e-9)
    six = np.concatenate([r[:, :, 0], r[:, :, 1]], -1)
    np.testing.assert_allclose(rot6d_to_matrix(six), r, atol=1e-12)
    assert rot6d_to_axis_angle(six.reshape(20, 150)).shape == (20, 75)


def test_normalisation_and_centre_of_pressure():
    assert normalise_kpa(np.array([0.0, -1.0, np.e - 1])).tolist() == [0.0, 0.0, 1.0]
    p = np.zeros((2, 10, 20))
    p[0, 2, 4] = 1.0
    cop = center_of_pressure_m(p, 0.1)
    np.testing.assert_allclose(cop[0], [0.45, 0.25])
    np.testing.assert_allclose(cop[1], [1.0, 0.5])  # empty: the carpet centre


def test_edge_infer_imports_without_torch():
    code = ("import sys, importlib.abc\n"
            "class B(importlib.abc.MetaPathFinder):\n"
            "    def find_spec(self, n, p=None, t=None):\n"
            "        if n == 'torch' or n.startswith('torch.'): raise ModuleNotFoundError('blocked torch')\n"
            "sys.meta_path.insert(0, B())\n"
            "import edge.infer, edge.infer.bundle, edge.infer.normalise, edge.infer.rotations\n"
            "assert 'torch' not in sys.modules\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert proc.returncode == 0, proc.stderr


def test_feature_window_pads_with_the_first_frame_and_slides():
    from edge.infer import FeatureWindow

    win = FeatureWindow(4, 2)
    win.push([1.0, 1.0])
    np.testing.assert_array_equal(win.window()[0, :, 0], [1, 1, 1, 1])
    for v in range(2, 12):
        win.push([v, -v])
        expect = [max(1, x) for x in range(v - 3, v + 1)]
        np.testing.assert_array_equal(win.window()[0, :, 0], expect)
        np.testing.assert_array_equal(win.window()[0, :, 1], [-x if x > 1 else 1 for x in expect])
    assert win.window().shape == (1, 4, 2)

"""Inference inputs on hard cases: a track's first frames, NaN/∞/negative pressure, empty and edge
centres of pressure, and the int8 model at and beyond its calibration range.

Documented behaviour (docs/stability.md): FeatureWindow repeats a track's first frame until it
has T; NaN/∞ are refused with ValueError (check_finite, ModelBundle.normalise/encode/head,
FeatureWindow.push): nothing NaN is published; the int8 encoder saturates at its calibration
maximum (3× and 100× read as 1×) and every output stays finite.
"""

from __future__ import annotations

import numpy as np
import pytest

from edge.infer import FeatureWindow, ModelBundle
from edge.infer.normalise import center_of_pressure_m, check_finite, normalise_kpa

T, F = 40, 3
PITCH_M = 19.05e-3 * 3
GRID = (32, 32)


def feature(i: int) -> np.ndarray:
    return np.array([i, -i, 10 * i], np.float32)


# ------------------------------------------------------------------ FeatureWindow


@pytest.mark.parametrize("pushes", [1, 2, 39, 40, 41, 81])
def test_feature_window_gives_the_last_t_frames_with_the_first_repeated(pushes):
    win = FeatureWindow(T, F)
    for i in range(pushes):
        win.push(feature(i))
    w = win.window()
    assert w.shape == (1, T, F) and w.dtype == np.float32 and w.flags.c_contiguous
    expected = np.stack([feature(max(k, 0)) for k in range(pushes - T, pushes)])
    np.testing.assert_array_equal(w[0], expected)


def test_feature_window_is_right_after_every_push_through_several_ring_turns():
    win = FeatureWindow(T, F)
    for n in range(1, 5 * T + 3):
        win.push(feature(n - 1))
        expected = np.maximum(np.arange(n - T, n), 0)
        np.testing.assert_array_equal(win.window()[0, :, 0], expected)
    win.reset()
    with pytest.raises(ValueError, match="no frame pushed yet"):
        win.window()


def test_feature_window_refuses_nan_and_keeps_its_history():
    win = FeatureWindow(T, F)
    for i in range(45):
        win.push(feature(i))
    before = win.window().copy()
    with pytest.raises(ValueError, match=r"1 NaN/∞ value\(s\) of 3"):
        win.push(np.array([1.0, np.nan, 0.0]))
    with pytest.raises(ValueError, match=r"2 NaN/∞"):
        win.push(np.array([np.inf, -np.inf, 0.0]))
    np.testing.assert_array_equal(win.window(), before)
    assert win.frames == 45


# ------------------------------------------------------------------ normalisation and CoP


def test_normalise_clips_negatives_and_check_finite_refuses_nan_and_inf():
    p = np.array([[-1e30, -3.0, 0.0, np.e - 1, 1e30]], np.float64)
    x = normalise_kpa(check_finite(p))
    assert x.dtype == np.float32 and np.isfinite(x).all()
    np.testing.assert_allclose(x[0, :4], [0.0, 0.0, 0.0, 1.0], atol=1e-7)
    assert x[0, 4] == pytest.approx(np.log1p(1e30))  # float32 log1p: 69, not ∞
    bad = np.zeros((4, 5), np.float32)
    bad[1, 2], bad[3, 0], bad[3, 4] = np.nan, np.inf, -np.inf
    with pytest.raises(ValueError, match=r"pressure_kpa holds 1 NaN and 2 infinite value\(s\) of 20 \(first at index \(1, 2\)\)"):
        check_finite(bad)
    # normalise_kpa itself is a pure transform: NaN and +∞ pass through, which is why the check exists
    assert np.isnan(normalise_kpa(bad)[1, 2]) and np.isinf(normalise_kpa(bad)[3, 0])


@pytest.mark.parametrize("fill", [0.0, -5.0])
def test_centre_of_pressure_of_an_empty_or_negative_frame_is_the_carpet_centre(fill):
    p = np.full((3, 8, 12), fill)
    cop = center_of_pressure_m(p, 0.02)
    np.testing.assert_allclose(cop, np.broadcast_to([0.12, 0.08], (3, 2)))


@pytest.mark.parametrize("where, expected", [((0, 0), (0.5, 0.5)), ((7, 11), (11.5, 7.5)), ((0, 11), (11.5, 0.5)),
                                             ((7, 0), (0.5, 7.5))])
def test_centre_of_pressure_at_a_corner_is_that_sensel_centre(where, expected):
    p = np.zeros((8, 12))
    p[where] = 3.0
    np.testing.assert_allclose(center_of_pressure_m(p, 0.02), np.array(expected) * 0.02)


def test_centre_of_pressure_stays_inside_the_carpet_for_any_finite_frame():
    rng = np.random.default_rng(3)
    frames = rng.gamma(0.3, 5.0, (200, 8, 12)) * (rng.random((200, 8, 12)) < 0.2)
    frames[:20] *= 1e30  # huge
    frames[20:40] *= 1e-40  # denormal-small
    frames[40:60, 1:] = 0.0  # only row 0 loaded
    frames[60:80, :, 1:] = 0.0  # only column 0 loaded
    frames[80:100] -= 1.0  # negatives mixed in
    cop = center_of_pressure_m(frames.astype(np.float32), 0.02)
    assert np.isfinite(cop).all()
    lo, eps = 0.01, 1e-12  # sensel centres run from pitch/2 to (W − ½)·pitch
    assert (cop >= lo - eps).all() and (cop[:, 0] <= 0.23 + eps).all() and (cop[:, 1] <= 0.15 + eps).all()
    np.testing.assert_allclose(cop[40:60][frames[40:60].max((1, 2)) > 0, 1], 0.01)  # row 0: y on its centre line


# ------------------------------------------------------------------ the int8 bundle


@pytest.fixture(scope="module")
def tiny_bundle(tmp_path_factory):
    """A 32×32 bundle trained for 3 steps and quantized as export does (int8 QDQ encoder, dynamic head)."""
    from export.bundle import write_bundle
    from export.data import load_tracks
    from export.evaluate import track_inputs
    from export.model import ModelConfig
    from export.onnx_export import export_onnx
    from export.quantize import quantize_encoder, quantize_head_dynamic
    from export.train import TrainConfig, Trainer
    from sim.dataset import Dataset
    from sim.dataset.generate import generate

    tmp = tmp_path_factory.mktemp("tiny_bundle")
    generate(tmp / "data", subjects=2, seconds_per_activity=1.0, grid=GRID[0], pitch_mm=PITCH_M * 1e3, seed=3, workers=1,
             progress=False, activities=("squat",))
    trainer = Trainer(TrainConfig(data=str(tmp / "data"), out=str(tmp / "run"), steps=3, batch=4, lr=3e-3, val_every=0,
                                  checkpoint_every=1000, log_every=1, progress=False, seed=5, threads=1),
                      ModelConfig.preset("tiny"))
    trainer.run()
    fp32 = export_onnx(trainer.net, tmp / "fp32")
    tracks = load_tracks(Dataset(tmp / "data"), "train")
    calib = np.concatenate([track_inputs(t, PITCH_M, i)[0] for i, t in enumerate(tracks)])
    (tmp / "int8").mkdir()
    encoder = quantize_encoder(fp32["encoder"], tmp / "int8" / "encoder.onnx", calib)
    head = quantize_head_dynamic(fp32["head"], tmp / "int8" / "head.onnx")
    folder = write_bundle(tmp / "bundle", encoder, head, trainer.net.cfg, name="tiny-32", pitch_m=PITCH_M)
    return ModelBundle.load(folder, grid=GRID), calib


def busiest(calib: np.ndarray) -> np.ndarray:
    """(1,1,H,W): the calibration frame that reaches the calibration maximum."""
    i = int(np.argmax(calib.reshape(len(calib), -1).max(1)))
    return calib[i:i + 1]


def assert_published_values_valid(out: dict, batch: int) -> None:
    for key in ("pose_aa", "betas", "transl_m", "activity_probs", "confidence"):
        assert np.isfinite(out[key]).all(), key
    aa = out["pose_aa"].reshape(batch, 24, 3)
    assert (np.linalg.norm(aa, axis=-1) <= np.pi + 1e-5).all()  # axis-angle with θ in [0, π]
    np.testing.assert_allclose(out["activity_probs"].sum(-1), 1.0, atol=1e-5)


@pytest.mark.parametrize("scale", [0.0, 1.0, 3.0, 100.0])
def test_int8_model_at_and_beyond_its_calibration_maximum_stays_finite(tiny_bundle, scale):
    b, calib = tiny_bundle
    cmax = float(calib.max())
    frame = busiest(calib)
    x = np.concatenate([frame * scale, np.full_like(frame, cmax * scale)])  # a real frame, and a flat one
    feats = b.encode(x)
    assert feats.shape == (2, b.features) and np.isfinite(feats).all()
    # beyond the calibration maximum the input quantizer saturates: exactly the features of the clipped input
    np.testing.assert_array_equal(feats, b.encode(np.minimum(x, cmax)))
    out = b.head(np.repeat(feats[:, None], b.window, axis=1), origin_m=np.zeros((2, 3)))
    assert_published_values_valid(out, 2)


def test_int8_model_on_a_window_mixing_empty_and_saturated_frames(tiny_bundle):
    b, calib = tiny_bundle
    frames = np.concatenate([np.zeros_like(calib[:1]), busiest(calib) * 100.0, calib[:3]])
    feats = b.encode(frames)
    window = FeatureWindow(b.window, b.features)
    for f in feats:
        window.push(f)
    assert_published_values_valid(b.head(window.window()), 1)


def test_the_bundle_refuses_nan_and_inf_at_every_entry(tiny_bundle):
    b, calib = tiny_bundle
    p = np.zeros((1, *GRID), np.float32)
    p[0, 3, 4] = np.nan
    with pytest.raises(ValueError, match="1 NaN"):
        b.normalise(p)
    p[0, 3, 4] = np.inf
    with pytest.raises(ValueError, match="1 infinite"):
        b.origin_m(p)
    x = calib[:2].copy()
    x[1, 0, 5, 5] = np.nan  # the int8 encoder would turn this into ordinary-looking features
    with pytest.raises(ValueError, match=r"encode input \(normalised pressure\) holds 1 NaN"):
        b.encode(x)
    w = np.zeros((1, b.window, b.features), np.float32)
    w[0, -1, 0] = np.nan
    with pytest.raises(ValueError, match=r"head input \(window features\) holds 1 NaN"):
        b.head(w)


class _NanRot6d:
    """Wraps the head session and turns one rot6d value into NaN, as an overflowing graph would."""

    def __init__(self, session):
        self.session = session

    def get_outputs(self):
        return self.session.get_outputs()

    def run(self, names, feeds):
        outs = self.session.run(names, feeds)
        order = [o.name for o in self.session.get_outputs()]
        outs[order.index("rot6d")][0, 7] = np.nan
        return outs


def test_a_head_that_outputs_nan_is_refused_not_published(tiny_bundle):
    b, calib = tiny_bundle
    window = np.repeat(b.encode(busiest(calib))[:, None], b.window, axis=1)
    real = b._head
    b._head = _NanRot6d(real)
    try:
        with pytest.raises(ValueError, match=r"head\.onnx: output\(s\) rot6d hold NaN/∞ for a finite input"):
            b.head(window)
    finally:
        b._head = real
    assert_published_values_valid(b.head(window), 1)

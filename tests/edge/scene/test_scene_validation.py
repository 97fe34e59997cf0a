"""Frame validation: every reason is produced and counted; garbage never raises; config rejects unknown keys."""

import numpy as np
import pytest

from cavatar_common.config import StrictConfig
from edge.scene import REASONS, SceneConfig, SceneTracker

PITCH = 0.01905


def fresh():
    return SceneTracker(96, 96, PITCH, SceneConfig(noise_kpa=0.05))


def quiet(rng=np.random.default_rng(0)):
    return rng.normal(0, 0.05, (96, 96)).astype(np.float32)


@pytest.mark.parametrize("frame, masks, t_s, reason", [
    (None, None, 0.0, "not_an_array"),
    (np.array([["a"]]), None, 0.0, "not_an_array"),
    (np.zeros((96, 95), np.float32) + 0.1, None, 0.0, "shape_mismatch"),
    (quiet(), np.zeros((10, 10), bool), 0.0, "mask_shape_mismatch"),
    (quiet(), None, float("nan"), "bad_time"),
    (quiet(), None, "soon", "bad_time"),
    (np.full((96, 96), np.nan, np.float32), None, 0.0, "non_finite"),
    (np.full((96, 96), 5.0, np.float32), None, 0.0, "constant"),
    (np.where(np.eye(96, dtype=bool), 1e6, 0.0).astype(np.float32), None, 0.0, "out_of_range"),
    (np.full((96, 96), -100.0, np.float32) + quiet(), None, 0.0, "out_of_range"),
    (np.full((96, 96), 100.0, np.float32) + quiet(), None, 0.0, "implausible_force"),  # 33 kN
])
def test_each_reason_is_reported_and_counted(frame, masks, t_s, reason):
    st = fresh()
    out = st.update(frame, t_s, masks)
    assert not out.valid and out.reason == reason and out.people == []
    assert out.counters[f"rejected_{reason}"] == 1 and out.counters["frames"] == 1 and out.counters["valid"] == 0


def test_time_must_increase():
    st = fresh()
    assert st.update(quiet(), 1.0).valid
    assert st.update(quiet(), 1.0).reason == "time_not_increasing"
    assert st.update(quiet(), 0.5).reason == "time_not_increasing"
    assert st.update(quiet(), 1.1).valid


def test_few_nan_are_filled_and_all_zero_is_an_empty_frame():
    st = fresh()
    p = quiet()
    p[3, 4] = np.nan
    p[50, 7] = np.inf
    out = st.update(p, 0.0)
    assert out.valid and out.empty
    out = st.update(np.zeros((96, 96), np.float32), 0.1)
    assert out.valid and out.empty
    masked = np.full((96, 96), np.nan, np.float32)
    masked[:, :2] = quiet()[:, :2]  # everything masked except two columns: NaN under the mask is fine
    mask = np.ones((96, 96), bool)
    mask[:, :2] = False
    assert st.update(masked, 0.2, mask).valid


def test_garbage_stream_never_raises_and_every_frame_is_counted():
    rng = np.random.default_rng(1)
    st = fresh()
    makers = [lambda: quiet(), lambda: np.full((96, 96), np.nan, np.float32), lambda: quiet() * 1e9,
              lambda: np.full((96, 96), np.inf, np.float32), lambda: rng.normal(0, 1e30, (96, 96)),
              lambda: np.zeros((0, 0)), lambda: "frame", lambda: rng.integers(0, 4096, (96, 96), dtype=np.uint16)]
    n = 300
    for i in range(n):
        out = st.update(makers[rng.integers(len(makers))](), i * 0.07)
        assert out.valid == (out.reason is None)
    c = out.counters
    assert c["frames"] == n
    assert c["valid"] + sum(c[f"rejected_{r}"] for r in REASONS) == n
    assert c["rejected_out_of_range"] > 0 and c["rejected_non_finite"] > 0 and c["valid"] > 0


def test_config_rejects_unknown_keys_and_bad_values():
    with pytest.raises(ValueError, match="unknown scene option.*group_radius_mm.*accepted:"):
        SceneConfig.from_dict({"group_radius_mm": 600})
    with pytest.raises(ValueError, match="grow_fraction"):
        SceneConfig.from_dict({"grow_fraction": 2})
    with pytest.raises(ValueError, match="birth_frames"):
        SceneConfig.from_dict({"birth_frames": 1.5})
    with pytest.raises(ValueError, match="median_3x3"):
        SceneConfig.from_dict({"median_3x3": "yes"})
    with pytest.raises(ValueError, match="noise_kpa must be > 0"):
        SceneConfig.from_dict({"noise_kpa": 0})
    with pytest.raises(ValueError, match="below their max_ counterparts"):
        SceneConfig.from_dict({"min_pressure_kpa": 3000})
    assert isinstance(SceneConfig(), StrictConfig) and SceneConfig.from_dict({"noise_kpa": None}).noise_kpa is None
    cfg = SceneConfig.from_dict({"group_radius_m": 1, "noise_kpa": 0.1, "temporal_median": True})
    assert cfg.group_radius_m == 1.0 and cfg.temporal_median and SceneConfig.from_dict(cfg.to_dict()) == cfg
    docs = SceneConfig.describe()
    assert set(docs) == set(cfg.to_dict()) and all(len(d) > 20 for d in docs.values())

"""FrameStages(adaptive=False), the always-infer baseline of bench/speed_error.py: the model runs on EVERY
frame (still people re-inferred, the whole carpet on frames with nobody); records are decided as usual."""

from types import SimpleNamespace

import numpy as np
import pytest
from scripted_stages import Calibrated, H, ScriptedScene, W, foot, frame, person

from edge.infer import ModelBundle
from edge.runtime.config import default_bundle_path
from edge.runtime.counters import FRAME_COUNTERS, PUBLISH_COUNTERS, WORK_COUNTERS, Counters, StageTimes
from edge.runtime.stages import FrameStages


@pytest.fixture(scope="module")
def bundle():
    return ModelBundle.load(default_bundle_path(), grid=(H, W))


A = foot(20, 20, 30.0) + foot(20, 34, 25.0)
B = foot(60, 60, 40.0)
SCRIPT = [  # (people, live tracks, empty), the frame's pressure
    (([], [], True), np.zeros((H, W), np.float32)),                                # 0 empty
    (([], [], False), A),                                                          # 1 contacts, nobody confirmed yet
    (([person(1, A > 0, False)], [1], False), A),                                  # 2 new person
    (([person(1, A > 0, True)], [1], False), A),                                   # 3 still
    (([person(1, A > 0, True), person(2, B > 0, False)], [1, 2], False), A + B),   # 4 still + new
    (([person(2, B > 0, True)], [2], False), B),                                   # 5 still, 1 gone
    (([], [], True), np.zeros((H, W), np.float32)),                                # 6 empty
    (([], [], True), np.zeros((H, W), np.float32)),                                # 7 empty, no heartbeat due
]


def run(bundle, adaptive):
    encoded = []
    counters = Counters(FRAME_COUNTERS + WORK_COUNTERS + PUBLISH_COUNTERS)
    kwargs = {} if adaptive is None else {"adaptive": adaptive}
    st = FrameStages(Calibrated(), ScriptedScene([s for s, _ in SCRIPT]), bundle, device="carpet-01", times=StageTimes(),
                     counters=counters, heartbeat_s=1.0, **kwargs)
    encode = bundle.encode
    proxy = SimpleNamespace(**{k: getattr(bundle, k) for k in ("normalise", "origin_m", "head", "manifest", "window", "features")})
    proxy.encode = lambda x: (encoded.append(np.array(x)), encode(x))[1]
    st.infer.bundle = proxy
    outs = [st.process(frame(k, p)) for k, (_, p) in enumerate(SCRIPT)]
    return outs, encoded, counters.snapshot()


def test_always_infer_runs_the_model_on_every_frame(bundle):
    outs, encoded, n = run(bundle, adaptive=False)
    per_frame = [len(x) for x in encoded]
    assert len(per_frame) == len(SCRIPT)                  # one encoder call on every frame
    assert per_frame == [1, 1, 1, 1, 2, 1, 1, 1]          # every tracked person, or the whole carpet
    assert n["encoder_runs"] == n["head_runs"] == 9 and n["idle_runs"] == 4 and n["still_reuses"] == 0
    assert np.allclose(np.expm1(encoded[1][0, 0]), np.minimum(A, 14.0), atol=1e-5)  # nobody confirmed: the whole carpet


def test_adaptive_is_the_default_and_does_only_the_needed_work(bundle):
    outs, encoded, n = run(bundle, adaptive=None)
    assert [len(x) for x in encoded] == [1, 1]            # frame 2 (person 1) and frame 4 (person 2)
    assert n["encoder_runs"] == 2 and n["still_reuses"] == 3 and n.get("idle_runs", 0) == 0


def test_both_modes_publish_the_same_records_and_heartbeats(bundle):
    always, _, _ = run(bundle, adaptive=False)
    adaptive, _, _ = run(bundle, adaptive=True)
    assert [o.kind for o in always] == [o.kind for o in adaptive] == ["empty", "unconfirmed", "people", "people", "people",
                                                                      "people", "empty", "empty"]
    shape = [(o.record is not None, o.record and o.record["seq"], o.record and [p["track_id"] for p in o.record["people"]])
             for o in always]
    assert shape == [(o.record is not None, o.record and o.record["seq"],
                      o.record and [p["track_id"] for p in o.record["people"]]) for o in adaptive]

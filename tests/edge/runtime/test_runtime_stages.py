"""FrameStages on a scripted scene: exactly the work each frame needs, inputs as in training, windows freed."""

from types import SimpleNamespace

import numpy as np
import pytest
from scripted_stages import Calibrated, H, ScriptedScene, W, foot, frame, person

from edge.infer import ModelBundle
from edge.infer.model_input import person_pressure_kpa
from edge.runtime.config import default_bundle_path
from edge.runtime.counters import FRAME_COUNTERS, PUBLISH_COUNTERS, WORK_COUNTERS, Counters, StageTimes
from edge.runtime.stages import FrameStages

PITCH = 0.01905


@pytest.fixture(scope="module")
def bundle():
    return ModelBundle.load(default_bundle_path(), grid=(H, W))


def make(bundle, script, encoded):
    counters = Counters(FRAME_COUNTERS + WORK_COUNTERS + PUBLISH_COUNTERS)
    st = FrameStages(Calibrated(), ScriptedScene(script), bundle, device="carpet-01", times=StageTimes(),
                     counters=counters, heartbeat_s=1.0)
    encode = bundle.encode
    bundle_proxy = SimpleNamespace(**{k: getattr(bundle, k) for k in ("normalise", "origin_m", "head", "manifest")})
    bundle_proxy.encode = lambda x: (encoded.append(np.array(x)), encode(x))[1]
    st.infer.bundle = bundle_proxy
    return st, counters


def test_still_people_reuse_moving_people_run_gone_tracks_are_freed(bundle):
    a = foot(20, 20, 30.0) + foot(20, 34, 25.0)
    b = foot(60, 60, 40.0)
    both = a + b
    mask_a, mask_b = a > 0, b > 0
    script = [
        ([person(1, mask_a, False)], [1]),                            # 0: new → encoder + head
        ([person(1, mask_a, True)], [1]),                             # 1: still → reuse
        ([person(1, mask_a, True), person(2, mask_b, False)], [1, 2]),  # 2: 1 reused, 2 new → one encoder input
        ([person(2, mask_b, True)], [2]),                             # 3: track 1 gone → freed; 2 still → reuse
        ([], []),                                                     # 4: empty → heartbeat, track 2 freed
        ([], []),                                                     # 5: empty, < 1 s later → nothing
    ]
    encoded = []
    st, c = make(bundle, script, encoded)
    outs = [st.process(frame(k, both if k in (2, 3) else a)) for k in range(6)]
    n = c.snapshot()
    assert [o.kind for o in outs] == ["people", "people", "people", "people", "empty", "empty"]
    assert [len(x) for x in encoded] == [1, 1]  # frame 0 (person 1) and frame 2 (person 2 only)
    assert (n["encoder_runs"], n["head_runs"], n["still_reuses"], n["person_frames"]) == (2, 2, 3, 5)
    assert (n["tracks_started"], n["tracks_freed"], st.tracks_open) == (2, 2, 0)
    r0, r1, r2 = (o.record["people"] for o in outs[:3])
    assert r1 == r0  # reused exactly
    assert r2[0] == r0[0] and r2[1]["track_id"] == 2
    assert outs[4].record["people"] == [] and outs[5].record is None
    assert [o.record["seq"] for o in outs[:5]] == [0, 1, 2, 3, 4]
    # the encoder saw person 2 only, prepared as in training (person 1's sensels zeroed)
    x = encoded[1][0, 0]
    assert np.allclose(np.expm1(x), np.where(mask_b, np.minimum(b, 14.0), 0.0), atol=1e-5)


def test_a_new_track_that_is_already_still_still_gets_its_inference(bundle):
    a = foot(30, 30, 20.0)
    encoded = []
    st, c = make(bundle, [([person(5, a > 0, True)], [5])], encoded)
    out = st.process(frame(0, a))
    assert out.record["people"][0]["track_id"] == 5 and c.get("encoder_runs") == 1 and c.get("still_reuses") == 0


def test_person_pressure_is_masked_floored_and_clipped_like_training():
    p = np.array([[0.1, 0.25, 20.0], [-1.0, 5.0, 3.0]], np.float32)
    mask = np.array([[True, True, True], [True, True, False]])
    out = person_pressure_kpa(p, mask)
    assert out.tolist() == [[0.0, 0.25, 14.0], [0.0, 5.0, 0.0]]
    assert p[0, 2] == 20.0  # the frame itself is untouched


def test_the_translation_origin_is_the_centre_of_pressure_of_the_same_input(bundle):
    from edge.infer.model_input import batch_inputs

    p = foot(10, 40, 3.0) + foot(80, 80, 9.0)
    mask = np.zeros((H, W), bool)
    mask[:40] = True  # only the first foot is this person's
    x, origin = batch_inputs(bundle, p, [mask])
    r, c = 10 + 5.5, 40 + 2.5  # the foot's centre in sensels
    assert np.allclose(origin[0], [(c + 0.5) * PITCH, (r + 0.5) * PITCH, 0.0], atol=1e-6)
    assert x.shape == (1, 1, H, W) and np.isclose(x.max(), np.log1p(3.0))

"""judge + summarise on a hand-made capture: published = truth gives zero errors; an extra or a miss is counted."""

from __future__ import annotations

import numpy as np
import pytest

from export.score.capture import Scene, SceneRun
from export.score.judge import judge
from export.score.summary import summarise

UPRIGHT = [np.pi / 2, 0.0, 0.0]


@pytest.fixture(scope="module")
def body():
    from edge.body import BodyModel

    return BodyModel.load("lite")


def _person(sid, x, act="squat", turn=0.0, scene=0):
    from scipy.spatial.transform import Rotation

    pose = np.zeros(72)
    pose[:3] = (Rotation.from_rotvec([0, 0, turn]) * Rotation.from_rotvec(UPRIGHT)).as_rotvec()
    pose[3 * 5] = 0.4  # a bent knee
    return {"subject_id": sid, "pose_aa": pose, "betas": np.zeros(10), "transl_m": np.array([x, 0.9, 0.9]), "activity": act,
            "scene": scene}


def _published(track, truth, act=None, turn=0.0):
    p = _person(truth["subject_id"], truth["transl_m"][0], truth["activity"], turn)
    return {"track_id": track, "transl_m": p["transl_m"].tolist(), "pose_aa": p["pose_aa"].tolist(),
            "betas": p["betas"].tolist(), "activity": act or truth["activity"], "confidence": 0.9}


def _run(truth, published, people=1):
    n = len(truth)
    return SceneRun(Scene(people, 0, n / 14), "scored", published=published, kinds=["people"] * n,
                    frame_ms=[5.0] * n, truth=truth)


def test_published_equal_to_truth_scores_perfectly(body):
    truth = [[_person(0, 0.5), _person(1, 1.4, "lunge")] for _ in range(6)]
    pub = [[_published(3, t[0]), _published(4, t[1])] for t in truth]
    frames, persons = judge(_run(truth, pub, people=2), body, 0.5)
    assert persons["matched"].all() and persons["activity_ok"].all()
    assert np.allclose(persons["mpjpe_m"], 0, atol=1e-6) and np.allclose(persons["heading_rad"], 0, atol=1e-6)
    s = summarise([(Scene(2, 0, 1), frames, persons)], 14.0)
    o = s["overall"]
    assert (o["count_right_pct"], o["extra_frames_pct"], o["mota_pct"], o["idsw"]) == (100.0, 0.0, 100.0, 0)
    assert s["by_activity"]["lunge"]["person_frames"] == 6 and o["frame_ms_median"] == 5.0


def test_extra_miss_turn_and_wrong_activity_are_counted(body):
    truth = [[_person(0, 0.5)] for _ in range(4)]
    pub = [[_published(1, truth[0][0], turn=np.pi * 0.75)],  # turned 135°
           [_published(1, truth[1][0]), {**_published(2, truth[1][0]), "transl_m": [0.7, 0.9, 0.9]}],  # a split
           [],  # missed
           [_published(1, truth[3][0], act="sitting")]]
    frames, persons = judge(_run(truth, pub), body, 0.5)
    assert frames["extra"].tolist() == [0, 1, 0, 0] and frames["missed"].tolist() == [0, 0, 1, 0]
    assert np.degrees(np.abs(persons["heading_rad"][0])) == pytest.approx(135)
    assert np.isnan(persons["mpjpe_m"][2]) and persons["mpjpe_m"][0] > 0.05
    o = summarise([(Scene(1, 0, 1), frames, persons)], 14.0)["overall"]
    assert o["count_right_pct"] == 50.0 and o["extra_frames_pct"] == 25.0 and o["short_frames_pct"] == 25.0
    assert o["mota_pct"] == 50.0 and o["heading_over_90_pct"] == pytest.approx(100 / 3, abs=0.01)
    assert o["activity_acc_pct"] == pytest.approx(200 / 3, abs=0.01)


def test_a_new_scene_is_a_new_identity(body):
    """At a scene boundary the simulator moves people: a new track id there is no identity switch."""
    for scenes, switches in (((0, 0, 1, 1), 0), ((0, 0, 0, 0), 1)):
        truth = [[_person(0, x, scene=s)] for x, s in zip((0.5, 0.5, 1.5, 1.5), scenes)]
        pub = [[_published(track, t[0])] for track, t in zip((1, 1, 2, 2), truth)]
        frames, _ = judge(_run(truth, pub), body, 0.5)
        assert frames["switches"].sum() == switches

"""PeopleInference.step on handovers made by hand (no scene, no runtime): one batched encoder and head call for
everyone whose pressure changed, still reuse, windows that live exactly as long as the scene holds the track."""

import copy

import numpy as np
import pytest

from edge.infer import ModelBundle, PeopleInference
from edge.runtime.config import default_bundle_path
from edge.scene import PersonObservation
from edge.scene.handover import PeopleHandover

H = W = 96


@pytest.fixture(scope="module")
def shipped():
    return ModelBundle.load(default_bundle_path(), grid=(H, W))


@pytest.fixture
def calls(shipped):
    """The shipped bundle, its encoder and head calls recorded as (name, batch size)."""
    seen: list[tuple[str, int]] = []
    b = copy.copy(shipped)
    b.encode = lambda x: (seen.append(("encoder", len(x))), shipped.encode(x))[1]
    b.head = lambda w, o=None: (seen.append(("head", len(w))), shipped.head(w, o))[1]
    return b, seen


def foot(r0, c0, kpa):
    p = np.zeros((H, W), np.float32)
    p[r0:r0 + 12, c0:c0 + 6] = kpa
    return p


def person(track_id, mask, still=False):
    z = np.zeros(2)
    return PersonObservation(track_id, z, 600.0, z, 600.0, 0.01, z, mask, (slice(0, 1), slice(0, 1)), 1, still, 1.0)


A, B = foot(20, 20, 30.0), foot(60, 60, 40.0)
BOTH = A + B


def handover(people, held=None, frame=BOTH):
    held = {p.track_id for p in people} if held is None else held
    return PeopleHandover(frame, tuple(people), frozenset(held))


def test_everyone_who_moved_goes_through_one_encoder_and_one_head_call(calls):
    bundle, seen = calls
    inf = PeopleInference(bundle)
    step = inf.step(handover([person(1, A > 0), person(2, B > 0)]))
    assert seen == [("encoder", 2), ("head", 2)]
    assert [r.activity in bundle.activities for r in step.results] == [True, True]
    assert step.work["encoder_runs"] == step.work["head_runs"] == 2 and step.work["tracks_started"] == 2
    assert step.encoder_ms > 0 and step.head_ms > 0
    assert not np.allclose(step.results[0].transl_m, step.results[1].transl_m)  # each on their own pressure


def test_a_still_person_reuses_their_result_and_pushes_the_same_features(calls):
    bundle, seen = calls
    inf = PeopleInference(bundle)
    first = inf.step(handover([person(1, A > 0)])).results[0]
    seen.clear()
    again = inf.step(handover([person(1, A > 0, still=True)]))
    assert seen == [] and again.results[0] is first and again.work["still_reuses"] == 1
    window = inf.tracks.get(1)[0].window.window()[0]
    assert np.array_equal(window[-1], window[-2]) and np.array_equal(window[-1], first.features)


def test_a_coasting_track_keeps_its_window_and_a_lost_one_frees_it(calls):
    bundle, seen = calls
    inf = PeopleInference(bundle)
    first = inf.step(handover([person(1, A > 0)])).results[0]
    coast = inf.step(handover([], held={1}))  # out of view, still held by the scene
    assert coast.results == [] and coast.work["tracks_freed"] == 0 and inf.tracks_open == 1
    seen.clear()
    back = inf.step(handover([person(1, A > 0, still=True)]))
    assert seen == [] and back.results[0] is first and back.work["tracks_started"] == 0  # the same track, continued
    lost = inf.step(handover([], held=set()))
    assert lost.work["tracks_freed"] == 1 and inf.tracks_open == 0


def test_always_infer_runs_the_whole_carpet_when_nobody_is_confirmed(calls):
    bundle, seen = calls
    step = PeopleInference(bundle, adaptive=False).step(handover([], held=set(), frame=A))
    assert seen == [("encoder", 1), ("head", 1)] and step.results == [] and step.work["idle_runs"] == 1
    assert PeopleInference(bundle).step(handover([], held=set(), frame=A)).work["encoder_runs"] == 0


def test_inference_never_imports_the_runtime_and_reads_the_scene_only_through_its_handover():
    import ast
    from pathlib import Path

    import edge.infer

    for path in Path(edge.infer.__file__).parent.glob("*.py"):
        tree = ast.parse(path.read_text())
        guarded = {id(n) for node in ast.walk(tree) if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.dump(node.test)
                   for n in ast.walk(node)}
        for node in ast.walk(tree):
            if isinstance(node, ast.ImportFrom) and node.module:
                assert not node.module.startswith("edge.runtime"), f"{path.name} imports {node.module}"
                if node.module.startswith("edge.scene"):
                    assert id(node) in guarded, f"{path.name} imports {node.module} at run time (types only)"


def test_a_frame_whose_model_call_fails_leaves_no_half_opened_window(calls):
    bundle, seen = calls
    inf = PeopleInference(bundle)
    real = bundle.encode
    bundle.encode = lambda x: (_ for _ in ()).throw(RuntimeError("onnxruntime failed"))
    with pytest.raises(RuntimeError):
        inf.step(handover([person(1, A > 0)]))
    assert inf.tracks_open == 0  # so the next frame opens it again, and counts it
    bundle.encode = real
    step = inf.step(handover([person(1, A > 0)]))
    assert step.work["tracks_started"] == 1 and inf.tracks_open == 1 and step.results[0] is not None

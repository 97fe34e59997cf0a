"""The published record: built by edge.record, valid against the JSON Schema (jsonschema, tests only)."""

import copy
import json
import math

import jsonschema
import numpy as np
import pytest
from sink_helpers import DEVICE, MODEL, body_record

from edge import record as R

SCHEMA = R.load_schema()
VALIDATOR = jsonschema.Draft202012Validator(SCHEMA)


def test_the_schema_is_valid_draft_2020_12_and_matches_the_module():
    jsonschema.Draft202012Validator.check_schema(SCHEMA)
    assert SCHEMA["$schema"] == "https://json-schema.org/draft/2020-12/schema"
    assert SCHEMA["properties"]["schema"]["const"] == R.SCHEMA_ID
    assert SCHEMA["properties"]["device"]["pattern"] == R.DEVICE_PATTERN
    assert SCHEMA["properties"]["model"]["pattern"] == R.MODEL_PATTERN
    person = SCHEMA["$defs"]["person"]
    assert person["properties"]["activity"]["pattern"] == R.ACTIVITY_PATTERN
    assert tuple(SCHEMA["required"]) == R.RECORD_KEYS and tuple(person["required"]) == R.PERSON_KEYS
    assert person["properties"]["pose_aa"]["minItems"] == R.POSE_LEN == 72
    assert person["properties"]["betas"]["maxItems"] == R.BETAS_LEN == 10
    assert SCHEMA["properties"]["people"]["maxItems"] == R.MAX_PEOPLE


@pytest.mark.parametrize("people", [0, 1, 2, 5])
def test_built_records_validate(people):
    rec = body_record(123, people=people)
    VALIDATOR.validate(rec)
    R.check_record(rec)
    VALIDATOR.validate(json.loads(R.dumps(rec)))  # and after a trip through JSON


def test_heartbeat_is_a_record_with_no_people():
    hb = R.heartbeat(DEVICE, 9, 1_732_240_000.1234, MODEL)
    VALIDATOR.validate(hb)
    assert hb["people"] == [] and hb["time"] == 1_732_240_000.123


def test_numpy_inputs_are_rounded_and_flattened():
    rng = np.random.default_rng(0)
    pose = rng.normal(size=(24, 3)).astype(np.float32)
    p = R.make_person(np.int64(4), np.array([1.0, 2.0, 0.9512345678]), pose, rng.normal(size=10), np.float32(0.91234), "squat")
    rec = R.make_record(DEVICE, np.int64(5), np.float64(1_732_240_000.5), MODEL, [p])
    VALIDATOR.validate(rec)
    assert len(p["pose_aa"]) == 72 and p["pose_aa"][3] == round(float(pose[1, 0]), 5)
    assert p["transl_m"][2] == 0.95123 and p["confidence"] == 0.912
    assert all(type(v) is float for v in p["pose_aa"]) and type(rec["seq"]) is int
    # 5 decimals: a record with one person stays under ~1 KB
    assert len(R.dumps(rec)) < 1100


@pytest.mark.parametrize("bad", [math.nan, math.inf, -math.inf])
def test_nan_and_inf_are_refused_everywhere(bad):
    good = dict(track_id=1, transl_m=[0, 0, 1], pose_aa=[0.0] * 72, betas=[0.0] * 10, confidence=0.5, activity="walking")
    for field, value in [("transl_m", [0, bad, 1]), ("pose_aa", [0.0] * 71 + [bad]), ("betas", [bad] * 10), ("confidence", bad)]:
        with pytest.raises(R.RecordError, match="NaN/Inf|confidence"):
            R.make_person(**{**good, field: value})
    with pytest.raises(R.RecordError, match="NaN/Inf"):
        R.make_record(DEVICE, 1, bad, MODEL, [])
    rec = body_record(1)
    rec["people"][0]["pose_aa"][10] = bad  # a record edited after it was built
    with pytest.raises(R.RecordError):
        R.check_record(rec)
    with pytest.raises(R.RecordError):
        R.dumps(rec)


def mutations():
    """Records that are wrong in one way each; both the schema and check_record must refuse them."""
    def m(fn):
        rec = body_record(3, people=2)
        fn(rec)
        return rec
    p = lambda rec: rec["people"][0]  # noqa: E731
    yield "schema", m(lambda r: r.update(schema="cavatar.bodies/2"))
    yield "extra key", m(lambda r: r.update(note="hi"))
    yield "missing seq", m(lambda r: r.pop("seq"))
    yield "negative seq", m(lambda r: r.update(seq=-1))
    yield "float seq", m(lambda r: r.update(seq=1.5))
    yield "bool seq", m(lambda r: r.update(seq=True))
    yield "device slash", m(lambda r: r.update(device="carpet/01"))
    yield "device wildcard", m(lambda r: r.update(device="carpet#"))
    yield "model format", m(lambda r: r.update(model="bundle"))
    yield "time string", m(lambda r: r.update(time="now"))
    yield "time negative", m(lambda r: r.update(time=-1.0))
    yield "people dict", m(lambda r: r.update(people={}))
    yield "too many people", m(lambda r: r.update(people=r["people"] * 17))
    yield "person extra", m(lambda r: p(r).update(vertices=[1.0]))
    yield "person missing", m(lambda r: p(r).pop("betas"))
    yield "pose short", m(lambda r: p(r).update(pose_aa=[0.0] * 69))
    yield "pose nested", m(lambda r: p(r).update(pose_aa=[[0.0] * 3] * 24))
    yield "betas string", m(lambda r: p(r).update(betas=["0"] * 10))
    yield "transl 2", m(lambda r: p(r).update(transl_m=[0.0, 0.0]))
    yield "confidence > 1", m(lambda r: p(r).update(confidence=1.5))
    yield "activity caps", m(lambda r: p(r).update(activity="Squat!"))
    yield "activity long", m(lambda r: p(r).update(activity="a" * 40))
    yield "track id negative", m(lambda r: p(r).update(track_id=-2))
    yield "track id float", m(lambda r: p(r).update(track_id=2.5))


@pytest.mark.parametrize("name,rec", list(mutations()), ids=[n for n, _ in mutations()])
def test_schema_and_structural_check_refuse_the_same_records(name, rec):
    assert not VALIDATOR.is_valid(json.loads(json.dumps(rec))), name
    with pytest.raises(R.RecordError):
        R.check_record(rec)


def test_the_structural_check_does_not_mutate():
    rec = body_record(2, people=2)
    before = copy.deepcopy(rec)
    R.check_record(rec)
    assert rec == before

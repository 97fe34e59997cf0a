"""Privacy: raw or calibrated pressure can never be published, by any sink.

First every way of smuggling it in is refused (extra keys, info payloads, arrays). Then a
full fake session — pressure frames → bodies → jsonl file, stdout and MQTT, with info and
presence — is run, and everything that came out is searched for pressure.
"""

import json
import re

import jsonschema
import numpy as np
import pytest
from sink_helpers import DEVICE, MODEL, body_record, wait_until

from edge import record as R
from edge.record import PrivacyError, RecordError
from edge.sinks import open_sink

SMUGGLED_RECORDS = [
    ("top-level pressure_kpa", lambda r: r.update(pressure_kpa=[[1.0] * 96] * 96)),
    ("top-level raw counts", lambda r: r.update(counts=[2048] * 9216)),
    ("top-level frame", lambda r: r.update(frame={"rows": 96, "data": "AAAA"})),
    ("person pressure", lambda r: r["people"][0].update(pressure=[0.5] * 100)),
    ("person contact image", lambda r: r["people"][0].update(image_kpa=[0.1])),
    ("person sensel mask", lambda r: r["people"][0].update(sensel_mask=[1, 0, 1])),
]


@pytest.mark.parametrize("name,smuggle", SMUGGLED_RECORDS, ids=[n for n, _ in SMUGGLED_RECORDS])
def test_records_carrying_pressure_are_refused_and_nothing_is_written(tmp_path, capsys, name, smuggle):
    rec = body_record(1)
    smuggle(rec)
    with pytest.raises(PrivacyError, match="never published"):
        R.check_record(rec)
    path = tmp_path / "bodies.jsonl"
    for url in (f"jsonl://{path}", "jsonl:-"):
        sink = open_sink(url, device=DEVICE)
        with pytest.raises(PrivacyError):
            sink.publish_bodies(rec)
        assert sink.stats()["refused"] == 1 and sink.stats()["sent"] == 0
        sink.close()
    assert path.read_bytes() == b"" and capsys.readouterr().out == ""


@pytest.mark.parametrize("info", [
    {"pressure_kpa_max": 12.0},
    {"calibration": {"baseline_counts": 5}},
    {"last_frame": [[0.0] * 96] * 96},
    {"debug": list(range(1000))},
    {"debug": "x" * 10_000},
    {"Raw": 1},
])
def test_info_payloads_cannot_carry_pressure(tmp_path, info):
    sink = open_sink(f"jsonl://{tmp_path}/b.jsonl", device=DEVICE)
    with pytest.raises(PrivacyError):
        sink.publish_info(info)
    sink.close()
    assert not (tmp_path / "b.info.json").exists()


def test_only_json_shaped_records_pass():
    for thing in [None, "text", [1, 2], b"bytes", np.zeros((96, 96))]:
        with pytest.raises(RecordError):
            R.check_record(thing)


def fake_frames(n, rng):
    """Pressure frames (kPa, 96x96) with two footprints; the values are > 10 kPa and distinctive."""
    yy, xx = np.mgrid[0:96, 0:96]
    for k in range(n):
        cx, cy = 30 + k * 0.3, 48
        blob = np.exp(-((xx - cx) ** 2 + (yy - cy) ** 2) / 20.0) + np.exp(-((xx - cx - 10) ** 2 + (yy - cy) ** 2) / 20.0)
        yield (blob * 80.0 + rng.uniform(10.0, 11.0, size=(96, 96)) * (blob > 0.05)).astype(np.float32)


def all_numbers(obj):
    if isinstance(obj, dict):
        for v in obj.values():
            yield from all_numbers(v)
    elif isinstance(obj, list):
        for v in obj:
            yield from all_numbers(v)
    elif isinstance(obj, (int, float)) and not isinstance(obj, bool):
        yield obj


def all_keys(obj):
    if isinstance(obj, dict):
        for k, v in obj.items():
            yield k
            yield from all_keys(v)
    elif isinstance(obj, list):
        for v in obj:
            yield from all_keys(v)


def test_a_full_fake_session_publishes_no_pressure(tmp_path, broker, subscribe, capsys):
    rng = np.random.default_rng(7)
    everything = subscribe(broker.port, ["#"])
    jsonl = open_sink(f"jsonl://{tmp_path}/bodies.jsonl?rotate_mb=0.01", device=DEVICE)
    stdout = open_sink("jsonl:-", device=DEVICE)
    mqtt = open_sink(broker.url("qos=1&ha=1"), device=DEVICE)
    sinks = [jsonl, stdout, mqtt]
    assert mqtt.wait_connected(10)
    secrets: set[str] = set()
    refused = 0
    for seq, frame in enumerate(fake_frames(60, rng)):
        peak = np.sort(frame.ravel())[-20:]
        for v in peak:  # what a leak would look like, at any rounding
            secrets.update({f"{v:.5f}".rstrip("0"), f"{v:.4f}".rstrip("0"), f"{v:.3f}".rstrip("0"), repr(float(v))})
        # a stand-in for the pipeline: the body comes from the centre of pressure, never the pressure itself
        w = frame / frame.sum()
        cop = [float((w.sum(0) * (np.arange(96) + 0.5)).sum() * 0.01905), float((w.sum(1) * (np.arange(96) + 0.5)).sum() * 0.01905)]
        person = R.make_person(1, [cop[0], cop[1], 0.95], np.zeros((24, 3)), np.zeros(10), 0.9, "walking")
        rec = R.make_record(DEVICE, seq, 1_732_240_000 + seq / 14, MODEL, [person] if seq % 10 else [])
        for sink in sinks:
            sink.publish_bodies(rec)
            sink.publish_presence(len(rec["people"]), [p["activity"] for p in rec["people"]])
            if seq % 20 == 0:
                sink.publish_info({"model": MODEL, "frames_in": seq, "calibration_age_s": 3600.0, "firmware": "1.2.0"})
            # a careless caller tries to attach the frame in every way
            for attempt in (lambda: sink.publish_bodies({**rec, "pressure_kpa": frame.tolist()}),
                            lambda: sink.publish_info({"frame": frame.ravel()[:50].tolist()}),
                            lambda: sink.publish_info({"peak_kpa": float(peak[-1])})):
                with pytest.raises(RecordError):
                    attempt()
                refused += 1
    assert mqtt.flush(10)
    assert wait_until(lambda: len([m for m in everything.messages if m[0].endswith("/bodies")]) == 60, 10)
    for sink in sinks:
        sink.close()
    assert wait_until(lambda: any(m[1] == b"offline" for m in everything.messages), 5)
    assert refused == 60 * 3 * 3 and sum(s.stats()["refused"] for s in sinks) == refused

    # everything that left the process
    blobs = [p.read_bytes() for p in sorted(tmp_path.glob("*.json*"))]
    blobs += [capsys.readouterr().out.encode()]
    blobs += [t.encode() + b" " + p for t, p, _, _ in everything.messages]
    data = b"\n".join(blobs)
    assert len(list(tmp_path.glob("bodies-*.jsonl"))) >= 2  # rotated files are searched too
    text = data.decode()
    for word in ("pressure", "kpa", "sensel", "counts", "heatmap"):
        assert word not in text.lower(), word
    numbers_out = set(re.findall(r"\d+(?:\.\d+)?", text))
    leaked = secrets & numbers_out
    assert not leaked, sorted(leaked)[:5]
    canary = json.dumps({"x": round(float(peak[-1]), 5)})  # the detector does see a leak
    assert secrets & set(re.findall(r"\d+(?:\.\d+)?", canary))
    # every JSON document: no sensor-like key, no number in the pressure range except time, no frame-sized array
    validator = jsonschema.Draft202012Validator(R.load_schema())
    n_docs = 0
    for line in text.replace(" {", "\n{").splitlines():
        line = line.strip()
        if not line.startswith("{"):
            continue
        doc = json.loads(line)
        n_docs += 1
        assert not any(R.FORBIDDEN_KEY.search(k) for k in all_keys(doc))
        if doc.get("schema") == R.SCHEMA_ID:
            validator.validate(doc)
            numbers = [x for x in all_numbers({k: v for k, v in doc.items() if k != "time"})]
            assert all(abs(x) < 10 for x in numbers if x not in (doc["seq"],) and not float(x).is_integer())
    assert n_docs >= 60 * 3

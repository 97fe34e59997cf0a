"""Privacy: nothing a sink writes carries pressure — no pressure-like key, no frame-sized array, no marker value.

The run (conftest.two_people_run) wrote a unique raw reading (MARK_COUNT) into sensel (0, 0)
of every frame and a unique calibrated pressure (MARK_KPA) into the most loaded sensel of
every frame, which the model did see. Every byte of every sink output is scanned for them.
"""

import json
import re

import numpy as np
from conftest import MARK_COUNT, MARK_KPA
from runtime_helpers import finite_numbers, longest_number_array, pressure_keys, read_jsonl

GRID = 96


def sink_outputs(out):
    return [out / "bodies.jsonl", out / "bodies.info.json"]


def test_no_pressure_key_and_no_frame_sized_array_in_any_output(two_people_run):
    out, _, _, inputs = two_people_run
    assert inputs, "the model saw no input: nothing was tested"
    docs = read_jsonl(out / "bodies.jsonl") + [json.loads((out / "bodies.info.json").read_text())]
    for doc in docs:
        assert pressure_keys(doc) == []
        assert longest_number_array(doc) <= 72  # pose_aa is the longest; a row of the carpet would be 96
        assert finite_numbers(doc)
    status = json.loads((out / "status.json").read_text())
    assert pressure_keys(status) == [] and longest_number_array(status) < GRID


def test_the_marker_values_never_appear_in_any_byte_written(two_people_run):
    out, _, _, inputs = two_people_run
    seen = np.expm1(np.concatenate(inputs))
    assert np.isclose(seen, MARK_KPA, atol=1e-5).any(), "the kPa marker never reached the model: nothing was tested"
    kpa = [f"{MARK_KPA:.6f}", f"{MARK_KPA:.5f}"]  # records round to 5 decimals
    raw = re.compile(rf"(?<![\d.]){MARK_COUNT}(?![\d.])")
    for path in [*sink_outputs(out), out / "status.json"]:
        text = path.read_bytes().decode()
        for m in kpa:
            assert m not in text, f"{m} found in {path.name}"
        if path.name != "status.json":  # (the status file's byte and packet counters could equal it by chance)
            assert not raw.search(text), f"{MARK_COUNT} found in {path.name}"

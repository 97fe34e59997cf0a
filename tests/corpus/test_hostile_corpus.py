"""The hostile corpus (issue 18), rtl_433 style: committed hostile inputs, each with its expected outcome.

Every input ends in a clear refusal or counted drops: nothing of another board, no frame
without its FRAME_END and CRC-32, no traceback."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from edge.sources import SourceError, open_source

CORPUS = Path(__file__).parent / "hostile"
EXPECTED = json.loads((CORPUS / "expected.json").read_text())


def _counters(stats: dict) -> dict:
    out: dict = {}
    for key in ("source", "decoder", "frames"):
        out.update({k: v for k, v in stats.get(key, {}).items() if isinstance(v, int)})
    return out


@pytest.mark.parametrize("name", sorted(EXPECTED["wire"]))
def test_wire_input_ends_as_expected(name):
    want = EXPECTED["wire"][name]
    path = CORPUS / "wire" / f"{name}.bin"
    source = open_source(f"replay://{path}?speed=0")
    if "refused" in want:
        with pytest.raises(SourceError) as err:
            source.start()
        message = str(err.value)
        assert want["refused"] in message and "\n" not in message
        return
    with source:
        frames = [int(f.counts[0, 0]) for f in source.frames(timeout_s=5.0)]
        stats = source.stats()
    assert frames == want["frames"]
    if want["board_mismatch"] is None:
        assert stats["board_mismatch"] is None
    else:
        assert want["board_mismatch"] in stats["board_mismatch"]
    counters = _counters(stats)
    for key, value in want["counters"].items():
        assert counters.get(key, 0) == value, (key, counters)


def test_the_committed_wire_files_are_what_the_generator_writes():
    from make_hostile_corpus import build

    built = build()
    assert sorted(built) == sorted(EXPECTED["wire"])
    for name, data in built.items():
        assert (CORPUS / "wire" / f"{name}.bin").read_bytes() == data, f"{name}.bin: rerun tests/corpus/make_hostile_corpus.py"

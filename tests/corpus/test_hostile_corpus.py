"""The hostile corpus (issue 18), rtl_433 style: committed hostile inputs, each with its expected outcome.

Every input ends in a clear refusal or counted drops: nothing of another board, no frame
without its FRAME_END and CRC-32, no calibration decompressed before it is checked, no traceback."""

from __future__ import annotations

import json
import tracemalloc
from pathlib import Path

import pytest

from calibration.file import Calibration, CalibrationError
from edge.cli import main
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


@pytest.mark.parametrize("name", sorted(EXPECTED["calibration"]))
def test_damaged_calibration_is_one_clear_line_read_cheaply(name):
    path = CORPUS / "calibration" / f"{name}.npz"
    tracemalloc.start()
    try:
        with pytest.raises(CalibrationError) as err:
            Calibration.load(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    message = str(err.value)
    assert EXPECTED["calibration"][name]["says"] in message and "\n" not in message
    assert "cavatar calibrate" in message
    assert peak < 8e6, f"{peak / 1e6:.1f} MB allocated reading a damaged calibration"


def test_cavatar_run_with_a_damaged_calibration_exits_2_with_one_line(tmp_path, capsys):
    code = main(["run", "--source", f"replay://{tmp_path}/none.bin", "--calibration",
                 str(CORPUS / "calibration" / "bit_flipped.npz"), "--status-file", str(tmp_path / "status.json"),
                 "--sink", f"jsonl://{tmp_path}/bodies.jsonl", "--quiet"])
    err = capsys.readouterr().err.strip()
    assert code == 2 and "Bad CRC-32" in err and "Traceback" not in err
    assert not (tmp_path / "bodies.jsonl").exists()


def test_the_committed_files_are_what_the_generator_writes():
    from make_hostile_corpus import build, build_calibrations

    for folder, suffix, built, expected in (("wire", ".bin", build(), EXPECTED["wire"]),
                                            ("calibration", ".npz", build_calibrations(), EXPECTED["calibration"])):
        assert sorted(built) == sorted(expected)
        for name, data in built.items():
            assert (CORPUS / folder / f"{name}{suffix}").read_bytes() == data, \
                f"{folder}/{name}{suffix}: rerun tests/corpus/make_hostile_corpus.py"


def test_inspect_reports_a_board_swap_instead_of_crashing(capsys):
    assert main(["inspect", str(CORPUS / "wire" / "board_swap_grid.bin")]) == 0
    out = capsys.readouterr().out
    assert "frames 3 " in out and "another board answered 1 time(s)" in out and "rows 6 (was 8)" in out

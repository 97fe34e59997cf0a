"""Every `cavatar` subcommand of the runtime meets a missing device, a destination it cannot write and a closed
standard input with one clear line and a non-zero exit — never a traceback (issue 17, "How we will know").

In-process (``main``), stdin replaced by an empty stream (so ``input()`` raises EOFError as with ``< /dev/null``);
a traceback would surface here as an exception. Unwritable: paths under /proc, which not even root can create.
`cavatar calibrate`'s own walk is tests/calibration/test_calibrate_refusals.py (it needs a board).
"""

import io
import json

import pytest

from edge.cli import main
from edge.record import make_person, make_record

NO_PORT = "serial:///dev/ttyCAVATAR-NOT-HERE"


@pytest.fixture
def record_file(tmp_path):
    person = make_person(1, [0.9, 0.9, 0.95], [0.0] * 72, [0.0] * 10, 0.9, "standing")
    path = tmp_path / "one.jsonl"
    path.write_text(json.dumps(make_record("carpet-01", 0, 1.0, "m@0123456789ab", [person])) + "\n")
    return path


def cases(tmp, record_file):
    unwritable = "/proc/cavatar-test"
    return {
        "record, missing device": (["record", "--source", NO_PORT, str(tmp / "x.bin"), "--frames", "3"], "does not exist"),
        "record, unwritable": (["record", "--source", "sim://?seed=7&speed=0", f"{unwritable}/x.bin", "--frames", "3"],
                               "cannot write"),
        "stream, missing device": (["stream", "--source", NO_PORT], "does not exist"),
        "inspect, missing file": (["inspect", str(tmp / "none.bin")], "no capture file"),
        "render, missing file": (["render", str(tmp / "none.jsonl"), "--png", str(tmp / "x.png")], "cannot read"),
        "render, unwritable": (["render", str(record_file), "--png", f"{unwritable}/x.png"], "cannot write"),
        "run, missing device": (["run", "--source", NO_PORT, "--calibration", str(tmp / "none.npz")], "calibration"),
        "run, unwritable status": (["run", "--status-file", f"{unwritable}/status.json", "--seconds", "1"],
                                   "set [runtime] status_file (--status-file) to a writable place"),
        "status, missing file": (["status", "--file", str(tmp / "none.json")], "no status file"),
        "config, missing file": (["config", "validate", str(tmp / "none.toml")], "no such file"),
        "peripherals, missing bus": (["peripherals", "--bus", "97"], "does not exist"),
    }


CASES = ["record, missing device", "record, unwritable", "stream, missing device", "inspect, missing file",
         "render, missing file", "render, unwritable", "run, missing device", "run, unwritable status",
         "status, missing file", "config, missing file", "peripherals, missing bus"]


@pytest.mark.parametrize("name", CASES)
def test_one_clear_line_never_a_traceback(name, tmp_path, record_file, capsys, monkeypatch):
    monkeypatch.setattr("sys.stdin", io.StringIO(""))
    monkeypatch.delenv("CAVATAR_CONFIG", raising=False)
    table = cases(tmp_path, record_file)
    assert sorted(table) == sorted(CASES)
    argv, phrase = table[name]
    monkeypatch.chdir(tmp_path)
    code = main(argv)
    out = capsys.readouterr()
    err = out.err.strip().splitlines()
    assert code == 2, (code, out.out, out.err)
    errors = [line for line in err if line.startswith(f"cavatar {argv[0]}: error: ")]
    assert len(errors) == 1 and phrase in out.err, out.err  # (config lists every problem under its one line)
    assert "Traceback" not in out.err
    assert not list(tmp_path.glob("*.part")) and not (tmp_path / "x.bin").exists()  # nothing half-written


def test_doctor_on_a_missing_configuration_is_a_fail_line_and_exit_1(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr("sys.stdin", io.StringIO(""))
    code = main(["doctor", "--config", str(tmp_path / "none.toml"), "--no-open"])
    out = capsys.readouterr().out
    assert code == 1 and "FAIL  config:" in out and "no such file" in out and "Traceback" not in out

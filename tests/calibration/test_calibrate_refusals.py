"""`cavatar calibrate` never ends in a traceback (issue 17, finding 4): each failure an installer meets is one line
and exit 2, found BEFORE anything is asked or recorded — a missing or busy port, a destination this user cannot
write, recordings that are not there, standard input closed, a mass that is not one.

Run as real processes with stdin closed (as from a script or a service), against a virtual board behind a real
pseudo-terminal where a board is needed.
"""

import os
import subprocess
import sys
from pathlib import Path

import pytest

from firmware_protocol.pty_board import PtyBoard
from firmware_protocol.virtual_board import VirtualBoard

HOLD = "import serial, sys, time; s = serial.Serial(sys.argv[1], exclusive=True); print('held', flush=True); time.sleep(60)"


def calibrate(cwd: Path, *args: str, stdin: str | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "edge", "calibrate", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=60, input=stdin, stdin=None if stdin is not None else subprocess.DEVNULL,
                          env={**os.environ, "PYTHONPATH": os.getcwd()})


def one_line_refusal(proc: subprocess.CompletedProcess, *phrases: str) -> str:
    err = proc.stderr.strip()
    assert proc.returncode == 2, (proc.returncode, proc.stdout, err)
    assert "Traceback" not in err and len(err.splitlines()) == 1, err
    assert err.startswith("cavatar calibrate: error: "), err
    for phrase in phrases:
        assert phrase in err, (phrase, err)
    assert "mass in kg?" not in proc.stdout  # refused before asking anything
    return err


@pytest.fixture(scope="module")
def board():
    with PtyBoard(VirtualBoard(rows=32, cols=32)) as pty:
        yield pty


def test_a_missing_port_is_said_before_the_mass_is_asked(tmp_path):
    proc = calibrate(tmp_path, "--source", "serial:///dev/ttyNOPE9", "--out", str(tmp_path / "cal.npz"))
    one_line_refusal(proc, "serial port /dev/ttyNOPE9 does not exist", "Nothing was asked or recorded yet")
    assert not (tmp_path / "cal.npz").exists()


def test_a_busy_port_names_its_holder(tmp_path, board):
    holder = subprocess.Popen([sys.executable, "-c", HOLD, board.port], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        proc = calibrate(tmp_path, "--source", f"serial://{board.port}", "--mass", "72")
    finally:
        holder.kill()
        holder.wait()
    one_line_refusal(proc, "is in use by another program", f"pid {holder.pid}", "systemctl stop cavatar")


@pytest.mark.parametrize("where", ["service folder", "file as folder", "missing folder"])
def test_an_unwritable_destination_is_found_before_the_session(tmp_path, board, where):
    blocker = tmp_path / "a-file"
    blocker.write_text("x")
    out = {"service folder": "/proc/cavatar/calibration.npz",  # not writable even by root
           "file as folder": str(blocker / "calibration.npz"),
           "missing folder": str(tmp_path / "no" / "such" / "calibration.npz")}[where]
    proc = calibrate(tmp_path, "--source", f"serial://{board.port}", "--out", out)
    err = one_line_refusal(proc, f"cannot write the calibration to {out}", "no session is wasted")
    assert "--out" in err


def test_the_service_folder_hint_names_sudo_u_cavatar(tmp_path, monkeypatch):
    from calibration import preflight

    (tmp_path / "lib").write_text("")  # a folder this user cannot write in, even as root: a file
    monkeypatch.setattr(preflight, "SERVICE_FOLDER", str(tmp_path / "lib"))
    with pytest.raises(preflight.PreflightError, match="sudo -u cavatar cavatar calibrate"):
        preflight.check_destination(tmp_path / "lib" / "calibration.npz")


def test_closed_stdin_asks_for_mass_on_the_command_line(tmp_path, board):
    proc = calibrate(tmp_path, "--source", f"serial://{board.port}", "--out", str(tmp_path / "cal.npz"))
    err = proc.stderr.strip()
    assert proc.returncode == 2 and "Traceback" not in err and len(err.splitlines()) == 1, err
    assert "standard input is closed" in err and "--mass KG" in err


def test_a_mass_that_is_not_a_number_is_one_line(tmp_path, board):
    proc = calibrate(tmp_path, "--source", f"serial://{board.port}", "--out", str(tmp_path / "cal.npz"), stdin="heavy\n")
    err = proc.stderr.strip()
    assert proc.returncode == 2 and "Traceback" not in err and len(err.splitlines()) == 1, err
    assert "the mass must be a number of kilograms" in err


def test_closed_stdin_at_the_first_step_keeps_the_session_and_says_why(tmp_path, board):
    proc = calibrate(tmp_path, "--source", f"serial://{board.port}", "--mass", "72", "--out", str(tmp_path / "cal.npz"))
    err = proc.stderr.strip()
    assert proc.returncode == 2 and "Traceback" not in err and len(err.splitlines()) == 1, err
    assert "standard input closed while waiting for Enter" in err and "calibration-work" in err


def test_missing_recordings_are_named_before_anything_runs(tmp_path):
    proc = calibrate(tmp_path, "--empty", "e.bin", "--walk", str(tmp_path / "w.bin"), "--mass", "72")
    one_line_refusal(proc, "no such recording: --empty e.bin, --walk", "cavatar record")

"""`cavatar run` and `cavatar status` from the command line: clean stops, clear refusals, nothing half-written."""

import json
import os
import shutil
import signal
import subprocess
import sys
import time

import pytest
from runtime_helpers import read_jsonl, sim_url

from edge.cli import main
from edge.runtime.config import default_bundle_path


def run_args(out, *extra):
    return ["run", "--sink", f"jsonl://{out}/bodies.jsonl", "--status-file", str(out / "status.json"), "--quiet", *extra]


def assert_nothing_written(out):
    assert not out.exists() or not any(out.iterdir()), sorted(p.name for p in out.iterdir())


def test_sigterm_stops_cleanly(tmp_path, sim_calibration):
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "edge", "run", "--source", sim_url(1), "--calibration", str(sim_calibration),
           "--sink", f"jsonl://{out}/bodies.jsonl", "--status-file", str(out / "status.json")]
    proc = subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            env={**os.environ, "PYTHONUNBUFFERED": "1"})
    status_file = out / "status.json"
    try:
        deadline = time.monotonic() + 60
        while time.monotonic() < deadline:
            if status_file.exists() and json.loads(status_file.read_text())["frames"]["frames_in"] >= 10:
                break
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.1)
        else:
            pytest.fail("the runtime processed no frames within 60 s")
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    status = json.loads(status_file.read_text())
    assert status["state"] == "stopped" and status["end_reason"] == "stop requested"
    records = read_jsonl(out / "bodies.jsonl")  # complete lines only: the file ends with a newline
    assert len(records) == status["publish"]["published"] > 0
    assert status["publish"]["last_seq"] == records[-1]["seq"] and status["publish"]["queued"] == 0
    assert "frames" in err and "stopped (stop requested)" in err
    assert not list(out.glob(".*.part*")) and not list(out.glob(".*.tmp"))  # the atomic writes left no temporary file


def test_a_bad_configuration_exits_2_listing_every_problem_and_writes_nothing(tmp_path, capsys):
    out = tmp_path / "out"
    bad = tmp_path / "bad.toml"
    bad.write_text(f'[runtime]\nstatus_file = "{out}/status.json"\nseconds = "forever"\n[source]\nurl = "tcp://x"\n')
    assert main(["run", "--config", str(bad)]) == 2
    err = capsys.readouterr().err
    assert "2 problem(s)" in err and "runtime.seconds: must be a number" in err and "source.url: unknown source" in err
    assert "cavatar config validate" in err
    assert_nothing_written(out)


def test_a_tampered_bundle_exits_2_and_writes_nothing(tmp_path, capsys, sim_calibration):
    bundle = tmp_path / "bundle"
    shutil.copytree(default_bundle_path(), bundle)
    data = bytearray((bundle / "head.onnx").read_bytes())
    data[len(data) // 2] ^= 0x01
    (bundle / "head.onnx").write_bytes(bytes(data))
    out = tmp_path / "out"
    assert main(run_args(out, "--bundle", str(bundle), "--source", sim_url(0), "--calibration", str(sim_calibration))) == 2
    err = capsys.readouterr().err
    assert "model bundle refused" in err and "head.onnx: SHA-256 mismatch" in err and "tampered or corrupt" in err
    assert len(err.strip().splitlines()) == 1  # one paragraph
    assert_nothing_written(out)


def test_a_calibration_of_another_carpet_exits_2_and_writes_nothing(tmp_path, capsys, sim_calibration):
    out = tmp_path / "out"
    other = "sim://?people=0&seed=8&speed=0"  # another virtual carpet: device sim-8
    assert main(run_args(out, "--source", other, "--calibration", str(sim_calibration))) == 2
    err = capsys.readouterr().err
    assert "belongs to another carpet" in err and "'sim-7' in the file, 'sim-8' on the device" in err
    assert "cavatar calibrate" in err
    assert_nothing_written(out)


@pytest.mark.parametrize("url, how", [
    ("serial:///dev/ttyACM0", "cavatar calibrate --source 'serial:///dev/ttyACM0' --mass KG"),
    ("usb://1209:CA7A", "cavatar calibrate --source 'usb://1209:CA7A' --mass KG"),
    ("replay://capture.bin", "cavatar calibrate --empty empty.bin --walk walk.bin"),
])
def test_a_real_carpet_without_calibration_is_refused_with_how_to_calibrate(tmp_path, capsys, url, how):
    out = tmp_path / "out"
    assert main(run_args(out, "--source", url)) == 2
    err = capsys.readouterr().err
    assert f"no calibration for {url}" in err and how in err and "cavatar run --calibration" in err
    assert_nothing_written(out)


def test_the_virtual_carpet_is_calibrated_automatically_and_the_file_reused(tmp_path, capsys):
    from edge.runtime.carpet_calibration import choose_calibration, sim_calibration_path
    from edge.sources import open_source

    url = "sim://?people=0&seed=3&grid=32&speed=0"
    said = []
    chosen = choose_calibration("", url, tmp_path, said.append)
    path = sim_calibration_path(tmp_path, 3, 32)
    assert chosen.automatic and chosen.path == path and path.is_file()
    assert len(said) == 1 and "calibrated as an installer would" in said[0] and str(path) in said[0]
    with open_source(url) as src:  # it is this board's calibration
        chosen.calibration.check_device(src.info)
    again = choose_calibration("", url, tmp_path, said.append)
    assert again.calibration.sha256 == chosen.calibration.sha256 and "from an earlier run" in said[-1]
    # the shipped bundle is for 96×96: a 32×32 carpet is refused after its calibration was found
    assert main(run_args(tmp_path, "--source", url)) == 2
    err = capsys.readouterr().err
    assert "is for a 96×96 carpet; this board is 32×32" in err
    assert not (tmp_path / "bodies.jsonl").exists() and not (tmp_path / "status.json").exists()


def test_status_prints_a_readable_report_and_json(tmp_path, capsys, config):
    from edge.runtime import Runtime

    Runtime(config(people=0), say=lambda text: None).run_for(frames=15)
    assert main(["status", "--file", str(tmp_path / "status.json")]) == 0
    text = capsys.readouterr().out
    assert "device carpet-01: stopped" in text and "frames: in 15" in text and "stages, ms median/p99" in text
    assert "saved: 15 frames without inference" in text and "heartbeats" in text
    assert main(["status", "--file", str(tmp_path / "status.json"), "--json"]) == 0
    assert json.loads(capsys.readouterr().out)["frames"]["frames_in"] == 15
    assert main(["status", "--file", str(tmp_path / "nope.json")]) == 2
    assert "no status file" in capsys.readouterr().err

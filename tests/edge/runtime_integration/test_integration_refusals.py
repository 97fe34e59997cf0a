"""Bad inputs over the output of an earlier run: a clear error, exit 2, and that output untouched.

tests/edge/runtime/test_runtime_cli.py already proves a bad configuration, a tampered bundle and
a calibration of another carpet exit 2 writing nothing into an EMPTY output folder. What it does
not cover, added here: the output folder already holds an earlier run's bodies file, info file
and status file (the usual case on a board, restarted by systemd) and each refusal — those three
and a tampered calibration file — leaves every byte and every modification time as it was, and
creates no file; the process itself exits 2 (not only ``main()``), and a refused run with an MQTT
sink never connects to the broker: nothing published, no retained "online" left behind.
"""

import os
import shutil
import subprocess
import sys

import numpy as np
import pytest
from integration_helpers import wait_until
from runtime_helpers import sim_url

from edge.cli import main
from edge.runtime.config import default_bundle_path

EARLIER = {
    "bodies.jsonl": '{"schema":"cavatar.bodies/1","device":"carpet-01","seq":0,"time":1732240000.0,"model":"m@0","people":[]}\n',
    "bodies.info.json": '{"schema":"cavatar.info/1","device":"carpet-01","time":1732240000.0}\n',
    "status.json": '{"schema":"cavatar.status/1","device":"carpet-01","state":"stopped","publish":{"last_seq":0}}\n',
}


@pytest.fixture
def earlier_output(tmp_path):
    out = tmp_path / "out"
    out.mkdir()
    for name, text in EARLIER.items():
        (out / name).write_text(text)
        os.utime(out / name, ns=(1_700_000_000_000_000_000, 1_700_000_000_000_000_000))
    return out


def files_state(folder):
    return {p.name: (p.read_bytes(), p.stat().st_mtime_ns) for p in sorted(folder.iterdir())}


def tampered_bundle(tmp_path):
    bundle = tmp_path / "bundle"
    shutil.copytree(default_bundle_path(), bundle)
    data = bytearray((bundle / "encoder.onnx").read_bytes())
    data[len(data) // 3] ^= 0x04
    (bundle / "encoder.onnx").write_bytes(bytes(data))
    return bundle


def tampered_calibration(tmp_path, good):
    """The seed-7 calibration with one gain changed and its recorded SHA-256 kept."""
    with np.load(good) as z:
        arrays = {k: z[k] for k in z.files}
    arrays["gain"] = arrays["gain"].copy()
    arrays["gain"][40, 40] *= 1.01
    path = tmp_path / "tampered-calibration.npz"
    np.savez_compressed(path, **arrays)
    return path


def run_args(out, *extra):
    return ["run", "--sink", f"jsonl://{out}/bodies.jsonl", "--status-file", str(out / "status.json"), "--quiet", *extra]


@pytest.mark.parametrize("case", ["configuration", "bundle", "calibration_of_another_carpet", "tampered_calibration"])
def test_a_refusal_leaves_an_earlier_runs_output_untouched(case, tmp_path, earlier_output, sim_calibration, capsys):
    out = earlier_output
    before = files_state(out)
    if case == "configuration":
        bad = tmp_path / "bad.toml"
        bad.write_text(f'[runtime]\nstatus_file = "{out}/status.json"\nheartbeat_s = -1\n'
                       f'[sinks]\nurls = ["jsonl://{out}/bodies.jsonl?rotate_mb=lots"]\n')
        code, says = main(["run", "--config", str(bad)]), ["2 problem(s)", "runtime.heartbeat_s", "rotate_mb"]
    elif case == "bundle":
        code = main(run_args(out, "--bundle", str(tampered_bundle(tmp_path)), "--source", sim_url(0),
                             "--calibration", str(sim_calibration)))
        says = ["model bundle refused", "encoder.onnx: SHA-256 mismatch"]
    elif case == "calibration_of_another_carpet":
        code = main(run_args(out, "--source", "sim://?people=0&seed=8&speed=0", "--calibration", str(sim_calibration)))
        says = ["belongs to another carpet", "'sim-7' in the file, 'sim-8' on the device"]
    else:
        code = main(run_args(out, "--source", sim_url(0), "--calibration", str(tampered_calibration(tmp_path, sim_calibration))))
        says = ["is damaged", "SHA-256", "recalibrate"]
    err = capsys.readouterr().err
    assert code == 2, err
    assert all(s in err for s in says), err
    assert files_state(out) == before  # same files, same bytes, same modification times; nothing new


def test_the_refused_process_exits_2_and_publishes_nothing(tmp_path, earlier_output, sim_calibration, mqtt_broker,
                                                          subscribe):
    broker = mqtt_broker()
    sub = subscribe(broker.port, ["#"])
    before = files_state(earlier_output)
    cmd = [sys.executable, "-m", "edge", *run_args(earlier_output, "--sink", broker.url("qos=1"),
                                                   "--source", "sim://?people=0&seed=8&speed=0",
                                                   "--calibration", str(sim_calibration))]
    proc = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=60,
                          env={**os.environ, "OMP_NUM_THREADS": "1"})
    assert proc.returncode == 2, proc.stderr
    lines = proc.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("cavatar run: error: calibration") and "belongs to another carpet" in lines[0]
    assert files_state(earlier_output) == before
    late = subscribe(broker.port, ["#"])  # would get any retained status/info/presence left behind
    assert not wait_until(lambda: sub.messages or late.messages, 0.5)
    assert "cavatar-carpet-01" not in broker.log.read_text()  # the sink never even connected

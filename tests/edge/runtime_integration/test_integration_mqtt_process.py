"""`cavatar run` as a process on the virtual carpet, publishing to a real mosquitto on 127.0.0.1.

A paho subscriber sees valid bodies records (JSON Schema), the retained status "online" and
info; killing the process (SIGKILL) makes the broker publish the last will "offline" within
seconds; SIGTERM stops it cleanly: exit 0, "offline" published by the runtime itself (the broker
logs a clean DISCONNECT, so it is not the will), every record published is the status file's count.
"""

import json
import os
import signal
import subprocess
import sys
import time

import pytest
from integration_helpers import bodies_validator, wait_until
from runtime_helpers import sim_url


def start_run(tmp_path, device, broker, calibration):
    out = tmp_path / device
    cmd = [sys.executable, "-m", "edge", "run", "--source", sim_url(1), "--calibration", str(calibration),
           "--sink", broker.url("qos=1"), "--device", device, "--status-file", str(out / "status.json"), "--quiet"]
    env = {**os.environ, "PYTHONUNBUFFERED": "1", "OMP_NUM_THREADS": "1"}
    proc = subprocess.Popen(cmd, cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)
    return proc, out


def bodies(sub, device):
    return [json.loads(p) for p, _ in sub.on(f"cavatar/{device}/bodies")]


def wait_for_bodies(sub, proc, device, n, timeout_s=60.0):
    ok = wait_until(lambda: len(bodies(sub, device)) >= n or proc.poll() is not None, timeout_s)
    if proc.poll() is not None:
        pytest.fail(f"cavatar run exited with {proc.returncode}: {proc.communicate()}")
    assert ok, f"fewer than {n} bodies records within {timeout_s} s"


def client_log(broker, device):
    return [line.split(": ", 1)[1] for line in broker.log.read_text().splitlines() if f"Client cavatar-{device} " in line]


def test_run_publishes_valid_records_status_and_info_and_the_will_says_offline_when_killed(
        tmp_path, mqtt_broker, subscribe, sim_calibration):
    broker = mqtt_broker()
    device = "killed-1"
    sub = subscribe(broker.port, [f"cavatar/{device}/#"])
    proc, _ = start_run(tmp_path, device, broker, sim_calibration)
    try:
        wait_for_bodies(sub, proc, device, 20)
        # a subscriber arriving now gets the retained state: status "online" and info
        late = subscribe(broker.port, [f"cavatar/{device}/status", f"cavatar/{device}/info"])
        assert late.wait_for(f"cavatar/{device}/status", b"online", 5) and late.wait_for(f"cavatar/{device}/info", None, 5)
        assert late.on(f"cavatar/{device}/status")[0] == (b"online", True)
        info, retained = late.on(f"cavatar/{device}/info")[0]
        info = json.loads(info)
        assert retained and info["schema"] == "cavatar.info/1" and info["device"] == device
        assert info["model"].startswith("lean-96@") and info["health"]["frames_in"] >= 0
        assert proc.poll() is None
        t_kill = time.monotonic()
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=10)
        assert sub.wait_for(f"cavatar/{device}/status", b"offline", 5.0), "no last will within 5 s of SIGKILL"
        will_s = time.monotonic() - t_kill
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=10)
    print(f"\nlast will 'offline' seen {will_s:.3f} s after SIGKILL")
    assert proc.returncode == -signal.SIGKILL
    records = bodies(sub, device)
    validator = bodies_validator()
    for r in records:
        validator.validate(r)
    seqs = [r["seq"] for r in records]
    assert seqs == list(range(seqs[0], seqs[0] + len(seqs)))  # one connection, QoS 1: none lost, none repeated
    assert sum(1 for r in records if r["people"]) >= len(records) - 3  # the person is on the carpet
    statuses = [p for p, _ in sub.on(f"cavatar/{device}/status")]
    assert statuses[0] == b"online" and statuses[-1] == b"offline"
    assert client_log(broker, device)[-1] == f"Client cavatar-{device} closed its connection."  # no DISCONNECT: the will


def test_sigterm_publishes_offline_itself_and_exits_0(tmp_path, mqtt_broker, subscribe, sim_calibration):
    broker = mqtt_broker()
    device = "stopped-1"
    sub = subscribe(broker.port, [f"cavatar/{device}/#"])
    proc, out = start_run(tmp_path, device, broker, sim_calibration)
    try:
        wait_for_bodies(sub, proc, device, 10)
        proc.send_signal(signal.SIGTERM)
        _, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=10)
    assert proc.returncode == 0, err
    assert sub.wait_for(f"cavatar/{device}/status", b"offline", 5.0)
    statuses = [p for p, _ in sub.on(f"cavatar/{device}/status")]
    # "online" may come twice: the connect's announce and the runtime's own publish_status can both send it
    # when they race (edge/sinks/mqtt.py: a state is never lost, at worst repeated); no other order is right
    changes = [s for i, s in enumerate(statuses) if i == 0 or s != statuses[i - 1]]
    assert changes == [b"online", b"offline"] and statuses.count(b"offline") == 1
    # a clean DISCONNECT (the will is not sent on one): so "offline" is the runtime's own publish
    assert client_log(broker, device)[-1] == f"Client cavatar-{device} disconnected."
    status = json.loads((out / "status.json").read_text())
    assert status["state"] == "stopped" and status["end_reason"] == "stop requested"
    records = bodies(sub, device)
    seqs = [r["seq"] for r in records]
    assert seqs == list(range(len(seqs)))  # a new status file: seq from 0, none lost, none repeated
    assert len(records) == status["publish"]["published"] and status["publish"]["queued"] == 0
    sink = next(iter(status["publish"]["sinks"].values()))
    assert sink["sent"] == len(records) and sink["dropped"] == 0

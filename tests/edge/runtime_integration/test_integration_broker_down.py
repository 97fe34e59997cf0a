"""A broker that cannot be reached is loud (issue 17, finding 2): `cavatar run` as a process, default log level.

- broker down (nothing listens on the port) for the whole bounded run → a WARNING naming the reason, a
  closing WARNING that the sink never connected, exit 1 (it used to print "published 56" and exit 0);
- a host name that does not resolve → the same, the reason says so;
- a broker that is up → "connected to" appears at the default level (the journal confirms it), exit 0;
- ``--require-sinks 1`` with the broker down → not started: one line, exit 1, no frame read.
"""

import json
import os
import subprocess
import sys

from tests.edge.runtime.runtime_helpers import sim_url
from tests.edge.sinks.sink_helpers import free_port


def cavatar_run(tmp_path, calibration, sink, *extra, seconds=2.0):
    out = tmp_path / "out"
    cmd = [sys.executable, "-m", "edge", "run", "--source", sim_url(1), "--calibration", str(calibration),
           "--sink", sink, "--status-file", str(out / "status.json"), "--seconds", str(seconds), "--quiet", *extra]
    proc = subprocess.run(cmd, cwd=tmp_path, capture_output=True, text=True, timeout=120,
                          env={**os.environ, "PYTHONUNBUFFERED": "1"})
    status = json.loads((out / "status.json").read_text()) if (out / "status.json").exists() else None
    return proc, status


def test_a_broker_down_for_the_whole_run_warns_with_the_reason_and_exits_1(tmp_path, sim_calibration):
    port = free_port()  # nothing listens there
    proc, status = cavatar_run(tmp_path, sim_calibration, f"mqtt://127.0.0.1:{port}/x?retry_s=0.5")
    err = proc.stderr
    assert proc.returncode == 1, err
    assert f"WARNING edge.sinks.mqtt: mqtt:// cannot connect to 127.0.0.1:{port}: Connection refused" in err, err
    assert err.count("cannot connect to") == 1  # the first failure, not one line per retry
    assert "never connected during the run" in err and "Traceback" not in err
    assert status["frames"]["frames_in"] > 0  # it did run: the failure is the broker, not the runtime


def test_a_host_that_does_not_resolve_says_so_and_exits_1(tmp_path, sim_calibration):
    proc, _ = cavatar_run(tmp_path, sim_calibration, "mqtt://no-such-broker.invalid/x?retry_s=0.5", seconds=1.0)
    assert proc.returncode == 1, proc.stderr
    assert "the host name 'no-such-broker.invalid' does not resolve" in proc.stderr, proc.stderr
    assert "never connected during the run" in proc.stderr


def test_a_reachable_broker_is_confirmed_at_the_default_level_and_exits_0(tmp_path, sim_calibration, mqtt_broker):
    broker = mqtt_broker()
    proc, status = cavatar_run(tmp_path, sim_calibration, broker.url("qos=1"), seconds=1.0)
    assert proc.returncode == 0, proc.stderr
    assert proc.stderr.count("mqtt:// connected to mqtt://127.0.0.1") == 1, proc.stderr
    assert "cannot connect" not in proc.stderr and "never connected" not in proc.stderr


def test_require_sinks_refuses_to_start_without_the_broker(tmp_path, sim_calibration):
    port = free_port()
    proc, status = cavatar_run(tmp_path, sim_calibration, f"mqtt://127.0.0.1:{port}/x?retry_s=0.5",
                               "--require-sinks", "1", seconds=30.0)
    assert proc.returncode == 1, proc.stderr
    lines = [line for line in proc.stderr.splitlines() if line.startswith("cavatar run:")]
    assert lines == [f"cavatar run: not started: mqtt://127.0.0.1:{port}/x (qos 1) did not connect within 1 s "
                     "(--require-sinks); the WARNING above says why. Check the broker (`cavatar doctor`)."], proc.stderr
    assert status is None or status["frames"]["frames_in"] == 0

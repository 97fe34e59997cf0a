"""docs/examples/subscriber.py runs against the real broker (issue 17, finding 7): it drops repeats by
(device, seq), counts gaps, skips garbage, and turns every person into 24 joints with edge.body."""

import json
import os
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import paho.mqtt.publish as publish
from sink_helpers import DEVICE, body_record

from edge.body import SMPL_JOINT_NAMES
from edge.topics import DeviceTopics

EXAMPLE = Path(__file__).resolve().parents[3] / "docs" / "examples" / "subscriber.py"


def test_the_subscriber_example_drops_duplicates_and_computes_joints(broker):
    proc = subprocess.Popen([sys.executable, str(EXAMPLE), "--port", str(broker.port), "--device", DEVICE, "--json",
                             "--count", "5", "--timeout", "20"], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            text=True, env={**os.environ, "PYTHONPATH": str(EXAMPLE.parents[2])})
    try:
        assert proc.stderr.readline().startswith("listening on cavatar/carpet-01/bodies"), proc.stderr.read()
        sent = {}
        topic = DeviceTopics("cavatar", DEVICE).bodies
        for seq, people in ((0, 1), (1, 2), (1, 2), (2, 0), (None, 0), (5, 1), (5, 1), (6, 2)):
            if seq is None:
                payload = b"\x00garbage{"
            else:
                sent[seq] = body_record(seq, people)
                payload = json.dumps(sent[seq])
            publish.single(topic, payload, qos=1, hostname="127.0.0.1", port=broker.port)
            time.sleep(0.02)
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
    assert proc.returncode == 0, err
    assert "5 records, 2 duplicates dropped, 2 missed (gaps in seq), 1 unreadable" in err, err
    people = [json.loads(line) for line in out.splitlines()]
    assert [(p["seq"], p["track_id"]) for p in people] == [(0, 1), (1, 1), (1, 2), (5, 1), (6, 1), (6, 2)]
    for p in people:
        src = sent[p["seq"]]["people"][p["track_id"] - 1]
        assert list(p["joints_m"]) == list(SMPL_JOINT_NAMES)
        joints = np.array(list(p["joints_m"].values()))
        assert joints.shape == (24, 3) and np.isfinite(joints).all()
        np.testing.assert_allclose(joints[0], src["transl_m"], atol=1e-4)  # the pelvis is transl_m
        spread = np.linalg.norm(joints - joints[0], axis=1).max()
        assert 0.5 < spread < 1.5  # a body's size, in metres
        assert p["activity"] == src["activity"] and p["confidence"] == src["confidence"]

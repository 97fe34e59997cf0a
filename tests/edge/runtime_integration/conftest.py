"""Fixtures of the runtime's integration tests (issue 7, "How we will know").

Reuses the runtime tests' helpers (tests/edge/runtime/runtime_helpers.py: the seed-7 virtual
carpet, configurations) and the sink tests' real mosquitto and subscriber
(tests/edge/sinks/sink_helpers.py). The calibration is the one the runtime tests use: a perfect
calibration of ``sim://?seed=7`` made from the simulator's truth (milliseconds, not the 10-s session).
"""

import sys
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[2]
for p in (HERE, HERE.parent / "runtime", HERE.parent / "sinks", ROOT):  # ROOT: bench.runtime_soak
    if str(p) not in sys.path:
        sys.path.insert(0, str(p))

from runtime_helpers import SEED  # noqa: E402


@pytest.fixture(scope="session")
def sim_calibration(tmp_path_factory) -> Path:
    from calibration.from_truth import calibration_from_truth
    from sim.live import live_sensor

    path = tmp_path_factory.mktemp("calibration") / f"calibration-sim-{SEED}.npz"
    calibration_from_truth(live_sensor(SEED, 96), device_id=f"sim-{SEED}").save(path)
    return path


@pytest.fixture(scope="session")
def one_person_frames():
    """300 frames of ``sim://?people=1&seed=7`` (two 10-s scenes), made once (~3 s)."""
    from integration_helpers import make_premade

    return make_premade(1, 300)


@pytest.fixture
def mqtt_broker(tmp_path):
    """Factory: ``mqtt_broker()`` → a started mosquitto on a free 127.0.0.1 port (stopped after the test)."""
    from sink_helpers import Broker

    brokers = []

    def make(users=None):
        b = Broker(tmp_path / f"broker{len(brokers)}", users)
        brokers.append(b)
        b.start()
        return b

    yield make
    for b in brokers:
        b.stop()


@pytest.fixture
def subscribe():
    """Factory of paho subscribers (sink_helpers.Subscriber), closed after the test."""
    from sink_helpers import Subscriber

    subs = []

    def make(port, topics, **kwargs):
        s = Subscriber(port, topics, **kwargs)
        subs.append(s)
        return s

    yield make
    for s in subs:
        s.close()

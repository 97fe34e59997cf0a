"""Fixtures of the runtime's integration tests (issue 7, "How we will know").

Reuses the runtime tests' helpers (tests/edge/runtime/runtime_helpers.py: the seed-7 virtual
carpet, configurations) and the sink tests' real mosquitto and subscriber
(tests/edge/sinks/sink_helpers.py). The calibration is the one the runtime tests use: a perfect
calibration of ``sim://?seed=7`` made from the simulator's truth (milliseconds, not the 10-s session).
"""

from pathlib import Path

import pytest

from tests.edge.runtime.runtime_helpers import truth_calibration


@pytest.fixture(scope="session")
def sim_calibration(tmp_path_factory) -> Path:
    return truth_calibration(tmp_path_factory.mktemp("calibration"))


@pytest.fixture(scope="session")
def one_person_frames():
    """300 frames of ``sim://?people=1&seed=7`` (two 10-s scenes), made once (~3 s)."""
    from integration_helpers import make_premade

    return make_premade(1, 300)


@pytest.fixture
def mqtt_broker(tmp_path):
    """Factory: ``mqtt_broker()`` → a started mosquitto on a free 127.0.0.1 port (stopped after the test)."""
    from tests.edge.sinks.sink_helpers import brokers

    yield from brokers(tmp_path)


@pytest.fixture
def subscribe():
    """Factory of paho subscribers (sink_helpers.Subscriber), closed after the test."""
    from tests.edge.sinks.sink_helpers import Subscriber

    subs = []

    def make(port, topics, **kwargs):
        s = Subscriber(port, topics, **kwargs)
        subs.append(s)
        return s

    yield make
    for s in subs:
        s.close()

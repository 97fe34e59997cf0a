"""A real mosquitto on 127.0.0.1 for the sink tests, a paho subscriber, and record factories.

The broker runs from a tiny config in a tmp dir: a listener on a free port bound to
127.0.0.1, anonymous or a password file, persistence in the tmp dir (so persistent
subscriber sessions survive a broker restart). Nothing here is skipped: without
mosquitto the fixture fails and says how to get it.
"""

import pytest
from sink_helpers import Subscriber, body_record, brokers


@pytest.fixture
def make_broker(tmp_path):
    """Factory: ``make_broker(users={"cavatar": "pw"})`` → a started Broker (stopped after the test)."""
    yield from brokers(tmp_path)


@pytest.fixture
def broker(make_broker):
    return make_broker()


@pytest.fixture
def subscribe():
    subs: list[Subscriber] = []

    def make(port: int, topics: list[str], **kwargs) -> Subscriber:
        s = Subscriber(port, topics, **kwargs)
        subs.append(s)
        return s

    yield make
    for s in subs:
        s.close()


@pytest.fixture
def record():
    return body_record

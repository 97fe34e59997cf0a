"""Broker problems are loud (issue 17, finding 2): the first failed attempt of an outage is one WARNING with the
reason, retries are not; the connection that ends it is a WARNING too, so the journal (default level) confirms it."""

import logging

from sink_helpers import DEVICE, Broker, free_port, wait_until

from edge.sinks import open_sink
from edge.sinks.mqtt import unreachable_reason


def warnings(caplog, text):
    return [r.getMessage() for r in caplog.records if r.levelno == logging.WARNING and text in r.getMessage()]


def test_down_at_start_then_up_one_warning_each_way(tmp_path, caplog):
    caplog.set_level(logging.WARNING, logger="edge.sinks.mqtt")
    broker = Broker(tmp_path / "broker")  # its port is chosen; nothing listens until start()
    sink = open_sink(broker.url("qos=1&retry_s=0.3"), device=DEVICE)
    try:
        assert wait_until(lambda: sink.stats()["connect_failures"] >= 3, 10)
        failed = warnings(caplog, "cannot connect")
        assert failed == [f"mqtt:// cannot connect to 127.0.0.1:{broker.port}: Connection refused at 127.0.0.1:"
                          f"{broker.port} (is the broker running, on this port?); records wait in memory (up to "
                          "max_queued=1000) until it connects; retrying every 0.3 s at most"], failed
        broker.start()
        assert sink.wait_connected(10)
        up = warnings(caplog, "connected to")
        assert len(up) == 1 and "again after" in up[0] and "failed attempts" in up[0], up
        broker.stop()  # a second outage is announced again, once
        assert wait_until(lambda: len(warnings(caplog, "cannot connect")) == 2, 10), caplog.text
        broker.start()
        assert wait_until(lambda: len(warnings(caplog, "connected to")) == 2, 10)
    finally:
        sink.close()
        broker.stop()


def test_reasons_in_words():
    assert "does not resolve" in unreachable_reason("no-such-broker.invalid", 1883)
    assert "Connection refused" in unreachable_reason("127.0.0.1", free_port())

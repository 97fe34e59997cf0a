"""mqtt:// against a real mosquitto: topics, retain flags, status and last will, HA discovery, auth."""

import json
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest
from sink_helpers import DEVICE, body_record, wait_until

from edge.ha_discovery import discovery
from edge.sinks import open_sink
from edge.topics import DeviceTopics

T = DeviceTopics("cavatar", DEVICE)
REPO = Path(__file__).resolve().parents[3]


def test_stream_reaches_subscriber_with_topics_and_retain_flags(broker, subscribe):
    live = subscribe(broker.port, ["cavatar/#", "homeassistant/#"])
    sink = open_sink(broker.url("qos=1&keepalive=5"), device=DEVICE)
    try:
        assert sink.wait_connected(10)
        sink.publish_info({"model": "test-bundle@0123456789ab", "calibration_age_s": 12.5, "frames_in": 40})
        for seq in range(40):
            sink.publish_bodies(body_record(seq, people=seq % 3))
            sink.publish_presence(seq // 10, ["walking"] * (seq // 10))  # the same state 10 times in a row
        assert sink.flush(10)
        assert wait_until(lambda: len(live.on(T.bodies)) == 40, 10)
        # a subscriber that comes later gets the retained state, flagged retained; never bodies
        late = subscribe(broker.port, ["cavatar/#", "homeassistant/#"])
        assert wait_until(lambda: len(late.on(T.presence)) >= 1 and late.on(T.info), 10)
        time.sleep(0.2)
        stats = sink.stats()
    finally:
        sink.close()

    seqs = [json.loads(p)["seq"] for p, _ in live.on(T.bodies)]
    assert seqs == list(range(40))
    assert live.on(T.status)[0] == (b"online", False)
    assert stats["sent"] == 40 and stats["dropped"] == 0 and stats["queued"] == 0 and stats["lag_ms"] is not None
    # presence is published on change only: 4 states, 4 messages
    presence = [json.loads(p) for p, _ in live.on(T.presence)]
    assert [p["count"] for p in presence] == [0, 1, 2, 3]
    assert presence[0]["present"] is False and presence[0]["activity"] == "none"
    assert presence[-1] == {**presence[-1], "present": True, "activity": "walking", "activities": ["walking"] * 3}
    retained = {t for t, _, r, _ in late.messages if r}
    assert {T.status, T.info, T.presence} <= retained
    assert T.bodies not in {t for t, _, _, _ in late.messages}
    info = json.loads(late.on(T.info)[0][0])
    assert info["schema"] == "cavatar.info/1" and info["device"] == DEVICE and info["frames_in"] == 40


def test_status_online_retained_then_offline_on_clean_close(broker, subscribe):
    sink = open_sink(broker.url("qos=0"), device=DEVICE)
    assert sink.wait_connected(10)
    late = subscribe(broker.port, [T.status])
    assert late.wait_for(T.status, b"online")
    assert late.on(T.status)[0] == (b"online", True)  # retained
    sink.close()
    assert late.wait_for(T.status, b"offline", timeout_s=5)
    after = subscribe(broker.port, [T.status])  # and "offline" is what stays
    assert after.wait_for(T.status)
    assert after.on(T.status) == [(b"offline", True)]


PUBLISHER = textwrap.dedent("""
    import sys, time
    sys.path.insert(0, {helpers!r})
    from sink_helpers import body_record
    from edge.sinks import open_sink
    sink = open_sink({url!r}, device="carpet-01")
    assert sink.wait_connected(10)
    for seq in range(5):
        sink.publish_bodies(body_record(seq))
    sink.flush(5)
    print("ready", flush=True)
    time.sleep(60)
""")


def test_last_will_says_offline_when_the_publisher_is_killed(broker, subscribe):
    watcher = subscribe(broker.port, [T.status])
    code = PUBLISHER.format(helpers=str(Path(__file__).parent), url=broker.url("qos=1&keepalive=2"))
    proc = subprocess.Popen([sys.executable, "-c", code], stdout=subprocess.PIPE, text=True, cwd=REPO)
    try:
        assert proc.stdout.readline().strip() == "ready"
        assert watcher.wait_for(T.status, b"online")
        t_kill = time.monotonic()
        proc.send_signal(signal.SIGKILL)
        proc.wait(timeout=5)
        assert watcher.wait_for(T.status, b"offline", timeout_s=6), broker.log_tail()
        took = time.monotonic() - t_kill
    finally:
        if proc.poll() is None:
            proc.kill()
    print(f"\nlast will 'offline' {took * 1000:.0f} ms after SIGKILL")
    assert took < 4.0


def test_home_assistant_discovery_payloads(broker, subscribe):
    ha = subscribe(broker.port, ["homeassistant/#"])
    sink = open_sink(broker.url("qos=0&ha=1"), device=DEVICE)
    expected = {topic for topic, _ in discovery(T)}
    try:
        assert sink.wait_connected(10)
        assert len(expected) == 8
        events = {f"homeassistant/binary_sensor/{DEVICE}_person_down/config",  # fall events (docs/falls.md)
                  f"homeassistant/event/{DEVICE}_fall/config"}
        expected |= events
        assert wait_until(lambda: expected <= {t for t, *_ in ha.messages}, 10)
        n_before = len(ha.messages)
        # Home Assistant restarts and announces itself: discovery is sent again
        import paho.mqtt.publish as publish

        publish.single("homeassistant/status", "online", hostname="127.0.0.1", port=broker.port)
        assert wait_until(lambda: len(ha.messages) >= n_before + len(expected) + 1, 10)
        # the runtime's info names the model's activities: the activity sensor becomes an enum of them
        sink.publish_info({"state": "running", "activities": ["walking", "squat"]})
        activity = f"homeassistant/sensor/{DEVICE}_activity/config"
        assert wait_until(lambda: "options" in json.loads([p for t, p, *_ in ha.messages if t == activity][-1]), 10)
    finally:
        sink.close()
    configs = {t: json.loads(p) for t, p, _, _ in ha.messages if t.endswith("/config")}
    assert set(configs) == expected
    carpet = {f"homeassistant/binary_sensor/{DEVICE}_presence/config", f"homeassistant/sensor/{DEVICE}_people/config",
              activity}
    for topic, cfg in configs.items():
        pairs = [(a["topic"], a["payload_available"], a["payload_not_available"]) for a in cfg["availability"]]
        if topic in carpet or topic in events:  # the runtime AND the board (frames arriving)
            assert cfg["availability_mode"] == "all"
            assert cfg["state_topic"] == (T.events if topic in events else T.presence)
            assert pairs == [(T.status, "online", "offline"), (T.board, "online", "offline")]
        else:  # diagnostics: while the runtime is up, so "board disconnected" can be shown
            assert pairs == [(T.status, "online", "offline")] and cfg["entity_category"] == "diagnostic"
        assert cfg["unique_id"].startswith("cavatar_") and "value_template" in cfg or "payload_on" in cfg
        assert cfg["device"]["identifiers"] == [f"cavatar_{DEVICE}"] and cfg["origin"]["name"] == "CAvatar Edge"
    assert configs[f"homeassistant/binary_sensor/{DEVICE}_presence/config"]["device_class"] == "occupancy"
    assert configs[activity]["device_class"] == "enum" and configs[activity]["options"] == ["walking", "squat", "none"]


def test_auth_with_user_in_url_and_password_from_environment(make_broker, subscribe, monkeypatch, caplog):
    secret = "s3cret-carpet-pw"
    broker = make_broker(users={"cavatar": secret, "reader": "r"})
    reader = subscribe(broker.port, ["cavatar/#"], username="reader", password="r")

    monkeypatch.setenv("CAVATAR_MQTT_PASSWORD", "wrong")
    bad = open_sink(broker.url("qos=1&retry_s=0.5", user="cavatar"), device=DEVICE)
    try:
        assert not bad.wait_connected(1.5)
        assert bad.stats()["errors"] >= 1
    finally:
        bad.close()

    monkeypatch.setenv("CAVATAR_MQTT_PASSWORD", secret)
    good = open_sink(broker.url("qos=1", user="cavatar"), device=DEVICE)
    try:
        assert good.wait_connected(10)
        good.publish_bodies(body_record(7))
        assert good.flush(5)
        assert reader.wait_for(T.bodies)
        described = good.describe()
    finally:
        good.close()
    assert json.loads(reader.on(T.bodies)[0][0])["seq"] == 7
    assert "cavatar@" in described and secret not in described
    assert secret not in caplog.text and "wrong" not in caplog.text
    assert any("refused the connection" in r.getMessage() for r in caplog.records)


def test_password_in_url_and_bad_options_are_refused_without_echoing_the_secret():
    with pytest.raises(ValueError) as err:
        open_sink("mqtt://cavatar:hunter2@127.0.0.1:1883/cavatar", device=DEVICE)
    assert "hunter2" not in str(err.value) and "CAVATAR_MQTT_PASSWORD" in str(err.value)
    for url, words in [
        ("mqtt://127.0.0.1/cavatar?qos=3", "qos"),
        ("mqtt://127.0.0.1/cavatar?colour=red", "no option 'colour'"),
        ("mqtt://127.0.0.1/cavatar?qos=0&spool=/tmp/x", "qos=1"),
        ("mqtt://127.0.0.1/ca+var", "prefix"),
        ("mqtt:///cavatar", "host"),
        ("mqtts://127.0.0.1", "Accepted forms"),
    ]:
        with pytest.raises(ValueError) as err:
            open_sink(url, device=DEVICE)
        assert words in str(err.value) and "mqtt://[user@]host" in str(err.value), url
    with pytest.raises(ValueError):
        open_sink("mqtt://127.0.0.1/cavatar", device="carpet/01")  # device is one topic level


def test_mqtt_sink_counts_qos0_drops_while_the_broker_is_absent():
    from sink_helpers import free_port

    sink = open_sink(f"mqtt://127.0.0.1:{free_port()}/cavatar?qos=0&retry_s=0.2", device=DEVICE)
    try:
        for seq in range(10):
            sink.publish_bodies(body_record(seq))
        s = sink.stats()
    finally:
        sink.close()
    assert s["dropped"] == 10 and s["sent"] == 0 and s["connected"] is False


def test_mutual_tls_with_ca_cert_and_key_files(make_broker, subscribe, tmp_path):
    from sink_helpers import make_certificates

    c = make_certificates(tmp_path / "pki")
    broker = make_broker(tls={"cafile": c["ca_crt"], "certfile": c["server_crt"], "keyfile": c["server_key"]})
    url = broker.url(f"qos=1&ca={c['ca_crt']}&cert={c['client_crt']}&key={c['client_key']}")
    sink = open_sink(url, device=DEVICE)
    try:
        assert sink.wait_connected(10), broker.log_tail()
        assert sink.config.tls and sink.config.port == broker.port
        sink.publish_bodies(body_record(1))
        assert sink.flush(5) and sink.stats()["sent"] == 1
    finally:
        sink.close()
    # without a client certificate the broker refuses; a missing file is a clear error at once
    no_cert = open_sink(broker.url(f"qos=1&retry_s=0.5&ca={c['ca_crt']}"), device=DEVICE)
    try:
        assert not no_cert.wait_connected(1.5)
    finally:
        no_cert.close()
    from edge.sinks import SinkError

    with pytest.raises(SinkError, match="no such file"):
        open_sink(broker.url(f"ca={tmp_path / 'missing.pem'}"), device=DEVICE)

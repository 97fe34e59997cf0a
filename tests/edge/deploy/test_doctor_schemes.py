"""`cavatar doctor` checks sources and sinks through each scheme module's own ``check(url, ctx)``, reached through
the scheme registry: replace one scheme's check and its finding is what doctor reports."""

import types

import pytest

from edge.health import FAIL, OK, Board, CheckContext, Finding
from edge.runtime import doctor

SOURCE_SCHEMES = {  # scheme module → a source URL of that scheme
    "edge.sources.serial_port": "serial:///dev/ttyCHECKED",
    "edge.sources.usb_bulk": "usb://1209:CA7A?serial=checked",
    "edge.sources.replay": "replay:///tmp/checked.bin",
}
SINK_SCHEMES = {
    "edge.sinks.jsonl": "jsonl:///tmp/checked/bodies.jsonl",
    "edge.sinks.mqtt": "mqtt://cavatar@broker.invalid:1883/cavatar?qos=1",
}


def _findings(config_path, **kwargs):
    return {f.check: f for f in doctor.diagnose(config_path, **kwargs)}


@pytest.mark.parametrize("module_name", SOURCE_SCHEMES)
def test_each_source_scheme_check_is_what_doctor_reports(module_name, config, monkeypatch):
    import importlib

    module, url, calls = importlib.import_module(module_name), SOURCE_SCHEMES[module_name], []

    def check(got_url, ctx):
        calls.append((got_url, ctx))
        return Finding("source", OK, f"checked by {module_name}"), Board("the test", "sim-7", 96, 96, 12)

    monkeypatch.setattr(module, "check", check)
    backend = object()
    found = _findings(config(source={"url": url}), timeout_s=0.5, usb_backend=backend)
    assert found["source"] == Finding("source", OK, f"checked by {module_name}")
    assert [(u, c.timeout_s, c.usb_backend) for u, c in calls] == [(url, 0.5, backend)]
    assert "board" not in found  # the scheme told the board: nothing to probe
    assert found["calibration vs board"].message == "matches the test (device id, grid, ADC bits)"


def test_the_virtual_carpet_plugin_check_is_what_doctor_reports(config, monkeypatch):
    from edge.sources import virtual

    calls = []

    def check(url, plugin, ctx):
        calls.append((url, plugin.scheme))
        return Finding("source", OK, "checked by the virtual carpet"), Board("its options", "sim-7", 96, 96, 12)

    monkeypatch.setattr(virtual, "check", check)
    found = _findings(config(source={"url": "sim://?seed=7&people=2"}))
    assert found["source"].message == "checked by the virtual carpet"
    assert calls == [("sim://?seed=7&people=2", "sim")]


def test_a_failed_source_check_ends_the_board_checks(config, monkeypatch):
    from edge.sources import serial_port

    monkeypatch.setattr(serial_port, "check", lambda url, ctx: (Finding("source", FAIL, "no port"), None))
    found = _findings(config(source={"url": "serial:///dev/ttyNOPE"}))
    assert found["source"].level == FAIL and "board" not in found and "calibration vs board" not in found


@pytest.mark.parametrize("module_name", SINK_SCHEMES)
def test_each_sink_scheme_check_is_what_doctor_reports(module_name, config, monkeypatch):
    import importlib

    module, url, calls = importlib.import_module(module_name), SINK_SCHEMES[module_name], []

    def check(got_url, ctx):
        calls.append((got_url, dict(ctx.env), ctx.timeout_s))
        return [Finding(f"sink {got_url}", OK, f"checked by {module_name}"), Finding("sink extra", OK, "second")]

    monkeypatch.setattr(module, "check", check)
    env = {"CAVATAR_MQTT_PASSWORD": "pw"}
    found = _findings(config(sinks={"urls": [url]}), env=env, timeout_s=0.25, open_board=False)
    assert found[f"sink {url}"].message == f"checked by {module_name}" and found["sink extra"].message == "second"
    assert calls == [(url, env, 0.25)]


def test_doctor_turns_an_unknown_scheme_into_a_fail_line_quoting_the_forms():
    ctx = CheckContext()
    [sink] = doctor.check_sink("ftp://me:secret@x", ctx)
    assert sink.check == "sink ftp://me:***@x" and sink.level == FAIL
    assert "unknown sink 'ftp://me:***@x'. Accepted forms: mqtt://" in sink.message and "secret" not in sink.message
    cfg = types.SimpleNamespace(source=types.SimpleNamespace(url="tcp://board:9000"))
    board, [source] = doctor.check_source(cfg, True, ctx)
    assert board is None and source.level == FAIL
    assert "unknown source 'tcp://board:9000'. Accepted forms: serial:///dev/ttyACM0" in source.message

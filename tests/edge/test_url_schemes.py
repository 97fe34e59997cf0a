"""One URL-scheme registry (edge.urls.Schemes) serves sources and sinks: an unknown scheme is a ValueError that
quotes every accepted form, for both, at every entry point (open, check, validate); a scheme whose module cannot
load is reported for that scheme only."""

import types

import pytest

from edge.health import CheckContext
from edge.sinks import SINKS, SinkError, check_sink, open_sink, sink_url_problem
from edge.sources import SOURCES, SourceError, check_source, open_link, open_source, source_options
from edge.urls import Schemes, redact

SOURCE_FORMS = ("serial:///dev/ttyACM0?baud=", "usb://1209:CA7A", "replay://capture.bin", "sim://?people")
SINK_FORMS = ("mqtt://[user@]host[:port]", "jsonl:///path/bodies.jsonl", "jsonl:- (stdout)")


@pytest.mark.parametrize("entry", [open_link, open_source, source_options,
                                   lambda url: check_source(url, CheckContext())])
@pytest.mark.parametrize("url", ["tcp://10.0.0.1:9000", "/dev/ttyACM0", "jsonl:-"])
def test_every_source_entry_point_refuses_an_unknown_scheme_quoting_the_forms(entry, url):
    with pytest.raises(ValueError) as err:
        entry(url)
    msg = str(err.value)
    assert msg.startswith(f"unknown source {url!r}. Accepted forms: ")
    assert all(form in msg for form in SOURCE_FORMS), msg
    assert "cavatar.sources" in msg  # where plug-in schemes come from


@pytest.mark.parametrize("entry", [lambda url: open_sink(url, device="carpet-01"),
                                   lambda url: check_sink(url, CheckContext())])
@pytest.mark.parametrize("url", ["ftp://x", "kafka://broker:9092", "bodies.jsonl", "serial:///dev/ttyACM0"])
def test_every_sink_entry_point_refuses_an_unknown_scheme_quoting_the_forms(entry, url):
    with pytest.raises(ValueError) as err:
        entry(url)
    msg = str(err.value)
    assert msg.startswith(f"unknown sink {url!r}. Accepted forms: ")
    assert all(form in msg for form in SINK_FORMS), msg


def test_sink_validation_names_the_unknown_scheme_and_hides_a_password():
    problem = sink_url_problem("ftp://me:hunter2@host/x")
    assert problem.startswith("unknown sink 'ftp://me:***@host/x'. Accepted forms: mqtt://") and "hunter2" not in problem
    assert sink_url_problem("jsonl:-") is None and sink_url_problem("mqtt://broker/cavatar?qos=1") is None
    assert "jsonl:// sink has no option 'rotate'" in sink_url_problem("jsonl:///tmp/b.jsonl?rotate=1")


def test_both_kinds_use_the_one_registry_class():
    assert isinstance(SOURCES, Schemes) and isinstance(SINKS, Schemes)
    assert list(SOURCES.loaders())[:3] == ["serial", "usb", "replay"] and "sim" in SOURCES.loaders()
    assert list(SINKS.loaders()) == ["mqtt", "jsonl"]


def test_a_scheme_that_cannot_load_is_reported_for_itself_only(monkeypatch):
    good = types.ModuleType("good_scheme")
    good.FORM = "good://thing"
    registry = Schemes("sink", {"good": "good_scheme", "gone": "no_such_module_for_cavatar"}, separator=":",
                       unavailable=SinkError)
    monkeypatch.setitem(__import__("sys").modules, "good_scheme", good)
    assert registry.handler("good://x") is good
    with pytest.raises(SinkError, match="gone:// sinks are unavailable here: No module named 'no_such_module"):
        registry.handler("gone://x")
    assert registry.accepted_forms() == ("good://thing; gone:// (unavailable here: No module named "
                                         "'no_such_module_for_cavatar')")
    with pytest.raises(ValueError, match=r"unknown sink 'what://x'\. Accepted forms: good://thing; gone://"):
        registry.handler("what://x")


def test_plugin_schemes_are_asked_for_each_time():
    found = {}
    registry = Schemes("source", {}, plugins=lambda: found, unavailable=SourceError, hint=" (plug-ins: see docs)")
    with pytest.raises(ValueError, match=r"Accepted forms: none \(plug-ins: see docs\)$"):
        registry.scheme_of("late://")
    late = types.SimpleNamespace(FORM="late://?x=1")
    found["late"] = lambda: late
    assert registry.handler("late://") is late and registry.accepted_forms() == "late://?x=1"


def test_redact_hides_only_the_password():
    assert redact("mqtt://user:pw@host:1883/p") == "mqtt://user:***@host:1883/p"
    assert redact("mqtt://user@host/p") == "mqtt://user@host/p" and redact("jsonl:-") == "jsonl:-"

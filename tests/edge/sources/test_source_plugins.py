"""Source plug-ins (edge/sources/plugins.py): sim:// reaches edge through an entry point, and a plug-in that
cannot load is reported for its own scheme only, never fatal for the others."""

import subprocess
import sys
import types

import numpy as np
import pytest

from edge.sources import SourceError, accepted_forms, open_link, open_source, plugins, source_options, source_plugin
from edge.sources.virtual import VirtualCarpetLink


@pytest.fixture
def extra_plugins(monkeypatch):
    """Register plug-ins beside the installed ones for one test: {scheme: target or module}."""
    found = dict(plugins.registered())

    def add(scheme, target, module=None):
        found[scheme] = plugins.Plugin(scheme, target, module=None)
        if module is not None:
            monkeypatch.setitem(sys.modules, target, module)

    monkeypatch.setattr(plugins, "_FOUND", found)
    return add


def test_sim_is_registered_as_an_entry_point_and_edge_imports_no_sim():
    assert plugins.registered()["sim"].target == "sim.source"
    code = ("import sys, edge.sources, edge.runtime.loop, edge.cli; "
            "print(sorted(m for m in sys.modules if m == 'sim' or m.startswith('sim.')))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"  # found by its entry point only when a sim:// URL is opened
    link = open_link("sim://?world=footsteps&people=1&seed=3&speed=0&faults=1")
    assert isinstance(link, VirtualCarpetLink) and link.opts["faults"] is True and link.describe() == "sim://"


def test_sim_options_are_typed_and_checked_by_edge():
    assert source_options("sim://?people=2&seed=7")["people"] == 2
    assert source_options("sim://?faults=no")["faults"] is False  # bool in the plug-in's OPTIONS reads 0/1, yes/no
    with pytest.raises(ValueError, match=r"rate='0' is not valid \(rate must be > 0 Hz\).*Form: sim://\?people"):
        source_options("sim://?rate=0")
    with pytest.raises(ValueError, match="no option 'colour'"):
        open_link("sim://?colour=red")


def test_a_plugin_that_cannot_load_is_reported_for_its_scheme_only(extra_plugins):
    extra_plugins("broken", "no_such_package_for_cavatar.source")
    extra_plugins("half", "half_plugin", types.ModuleType("half_plugin"))  # no FORM, OPTIONS, open_carpet
    with pytest.raises(SourceError, match="broken:// sources are unavailable here: .*no_such_package_for_cavatar"):
        open_link("broken://")
    with pytest.raises(SourceError, match="half:// .*lacks FORM, OPTIONS, open_carpet"):
        open_link("half://")
    forms = accepted_forms()
    assert "broken:// (unavailable here" in forms and "half:// (unavailable here" in forms
    assert "serial:///dev/ttyACM0" in forms and "sim://?people" in forms  # the others still listed
    with pytest.raises(ValueError, match="unknown source 'nope://x'.*broken://"):
        open_link("nope://x")
    assert source_plugin("sim://").scheme == "sim"  # the working plug-in still loads


def test_a_new_plugin_streams_through_the_real_protocol(extra_plugins):
    """The contract is enough for a plug-in edge has never heard of: a flat 8×8 carpet of one value."""
    flat = types.ModuleType("flat_plugin")
    flat.FORM = "flat://?level=100"
    flat.OPTIONS = {"level": (int, 100, "counts of every sensel"), "speed": (float, 0.0, "0 = virtual clock")}

    def open_carpet(opts):
        board = {"rows": 8, "cols": 8, "tile_rows": 1, "tile_cols": 1, "adc_bits": 12, "sign": -1, "rate_hz": 10.0,
                 "device_id": "flat-1"}
        return (lambda index: np.full((8, 8), opts["level"], np.uint16)), board

    flat.open_carpet = open_carpet
    extra_plugins("flat", "flat_plugin", flat)
    with open_source("flat://?level=321") as source:
        frame = next(iter(source.frames(timeout_s=5.0)))
        assert source.info.device_id == "flat-1"
    assert frame.counts.shape == (8, 8) and int(frame.counts[3, 4]) == 321

"""Source plug-ins: URL schemes that other packages register, found through importlib.metadata.

edge never imports the packages that offer them (the virtual carpet of ``sim`` is one: design.md
lets edge import neither sim nor export). A plug-in is a module registered in its distribution's
metadata under the entry-point group ``cavatar.sources``, named by its URL scheme::

    [options.entry_points]          # setup.cfg
    cavatar.sources =
        sim = sim.source

The module offers a *virtual carpet* — frames made in-process — and edge puts a virtual readout
board (firmware_protocol.virtual_board) in front of it, so the frames cross the real protocol,
decoder and frame assembly (edge.sources.virtual). The module defines:

- ``FORM``: the accepted URL form, quoted in every error;
- ``OPTIONS``: ``{name: (parse, default, description)}``, ``parse(text) -> value`` raising
  ValueError with the reason (``bool`` reads 0/1, true/false, yes/no, on/off); ``speed`` (1 = real
  time, 0 = a virtual clock, as fast as frames are taken) and ``faults`` (line noise now and then)
  are read by the board when present;
- ``open_carpet(opts) -> (frames, board)``: ``frames(index)`` gives the (rows, cols) counts the
  board scans as its ``index``-th frame (its ``close()``, when it has one, is called as the link
  closes); ``board`` holds the board's ``rows, cols, tile_rows, tile_cols, adc_bits, sign,
  rate_hz, device_id``;
- optionally ``calibration_sensor(opts)``: the sensor model the automatic calibration of this
  carpet acts on (``calibration.actor.Actor``), ValueError when it has none; with it come
  ``device_id(opts)`` and the options ``seed``, ``grid``, ``bits`` and ``pitch_mm``, which name
  the saved calibration and check that it still fits; `cavatar doctor` compares the calibration
  with the board these name (:func:`edge.sources.virtual.check`), and asks the virtual board for
  its INFO instead when a plug-in does not name them.

A plug-in that fails to load (its package missing or broken) is reported when its scheme is asked
for and in the list of accepted forms, never at import and never for the other schemes.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from importlib import metadata
from types import ModuleType
from typing import Any

from edge.urls import Option, parse_bool

GROUP = "cavatar.sources"
REQUIRED = ("FORM", "OPTIONS", "open_carpet")


@dataclass
class Plugin:
    """One registered scheme: where it comes from, and once loaded, its module and typed options."""

    scheme: str
    target: str  # "module" or "module:attribute", as registered
    module: ModuleType | Any = None
    options: dict[str, Option] = field(default_factory=dict)
    error: str = ""  # why it could not be loaded ("" when it loaded or was not tried)

    @property
    def form(self) -> str:
        return self.module.FORM

    def calibration_sensor(self, opts: dict[str, Any]) -> Any:
        """The sensor the automatic calibration acts on; ValueError when this carpet has none."""
        hook = getattr(self.module, "calibration_sensor", None)
        if hook is None:
            raise ValueError(f"{self.scheme}:// offers no sensor model to calibrate")
        return hook(opts)


_FOUND: dict[str, Plugin] | None = None


def registered(refresh: bool = False) -> dict[str, Plugin]:
    """Every scheme registered under ``cavatar.sources`` (not loaded yet), by name."""
    global _FOUND
    if _FOUND is None or refresh:
        _FOUND = {ep.name: Plugin(ep.name, ep.value) for ep in metadata.entry_points(group=GROUP)}
    return _FOUND


def load(plugin: Plugin) -> Plugin:
    """``plugin`` with its module loaded and checked; ImportError that says which plug-in and why."""
    if plugin.module is not None:
        return plugin
    if plugin.error:
        raise ImportError(plugin.error)
    try:
        module = metadata.EntryPoint(plugin.scheme, plugin.target, GROUP).load()
        missing = [name for name in REQUIRED if not hasattr(module, name)]
        if missing:
            raise ImportError(f"it lacks {', '.join(missing)} (see edge/sources/plugins.py)")
        plugin.options = {name: _option(name, spec) for name, spec in module.OPTIONS.items()}
    except Exception as exc:  # a broken plug-in is reported, never fatal for the other schemes
        plugin.error = f"the {plugin.scheme}:// plug-in {plugin.target} cannot be loaded: {exc}"
        raise ImportError(plugin.error) from None
    plugin.module = module
    return plugin


def _option(name: str, spec: Any) -> Option:
    try:
        parse, default, doc = spec
    except (TypeError, ValueError):
        raise ImportError(f"option {name!r} must be (parse, default, description), got {spec!r}") from None
    return Option(parse_bool if parse is bool else parse, default, doc)


__all__ = ["GROUP", "Plugin", "load", "registered"]

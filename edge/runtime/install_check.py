"""`cavatar doctor`'s first checks: is this installation whole? Python, packages, onnxruntime, and no torch.

- ``python``: 3.11 or newer; ``packages``: every runtime dependency imports;
- ``onnxruntime``: imports, has the CPU provider; ``runtime modules``: the runtime's modules import;
- ``torch``: not required by the installed package and not imported by the runtime's modules
  (the board never has it).
"""

from __future__ import annotations

import importlib
import importlib.metadata
import importlib.util
import sys

from edge.health import FAIL, OK, Finding

RUNTIME_MODULES = ("edge.runtime.loop", "edge.infer", "edge.sinks.mqtt", "edge.sinks.jsonl",
                   "edge.sources.serial_port", "edge.sources.usb_bulk")
DEPENDENCIES = (("numpy", "numpy"), ("scipy", "scipy"), ("pyserial", "serial"), ("pyusb", "usb"),
                ("smbus2", "smbus2"), ("paho-mqtt", "paho.mqtt.client"))


def check_python() -> list[Finding]:
    """``python`` and ``packages``."""
    from edge import __version__

    v = sys.version_info
    out = [Finding("python", OK if v >= (3, 11) else FAIL,
                   f"Python {v.major}.{v.minor}.{v.micro} ({sys.executable})" if v >= (3, 11) else
                   f"Python {v.major}.{v.minor} ({sys.executable}); CAvatar Edge needs 3.11 or newer: install it "
                   "(Debian bookworm has 3.11) and reinstall with deploy/install.sh")]
    found, missing = [f"cavatar-edge {__version__}"], []
    for dist, module in DEPENDENCIES:
        try:
            importlib.import_module(module)
            found.append(f"{dist} {_version(dist)}")
        except ImportError as exc:
            missing.append(f"{dist} ({exc})")
    if missing:
        out.append(Finding("packages", FAIL, f"cannot import {', '.join(missing)}: reinstall the package "
                           "(sudo deploy/install.sh, or pip install cavatar-edge in this environment)"))
    else:
        out.append(Finding("packages", OK, ", ".join(found)))
    return out


def check_onnxruntime() -> list[Finding]:
    """``onnxruntime``, then ``runtime modules`` (only when one fails) and ``torch``."""
    try:
        import onnxruntime as ort

        providers = ort.get_available_providers()
        if "CPUExecutionProvider" in providers:
            out = [Finding("onnxruntime", OK, f"{ort.__version__}, providers {', '.join(providers)}")]
        else:
            out = [Finding("onnxruntime", FAIL, f"{ort.__version__} has no CPUExecutionProvider ({providers}): "
                           "install the PyPI wheel (pip install --force-reinstall onnxruntime)")]
    except ImportError as exc:
        out = [Finding("onnxruntime", FAIL, f"cannot import it ({exc}): pip install onnxruntime (a 64-bit "
                       "system is needed: onnxruntime has no 32-bit ARM wheels)")]
    return out + _check_torch()


def _check_torch() -> list[Finding]:
    requires = [r for r in (_requires("cavatar-edge") or []) if r.split(";")[0].strip().startswith("torch")
                and "extra" not in r]
    loaded_before = "torch" in sys.modules
    failed = []
    for name in RUNTIME_MODULES:
        try:
            importlib.import_module(name)
        except ImportError as exc:
            failed.append(f"{name} ({exc})")
    try:
        installed = importlib.util.find_spec("torch") is not None
    except ImportError:  # an import hook that refuses torch outright
        installed = False
    out = []
    if failed:
        out.append(Finding("runtime modules", FAIL, f"cannot import {'; '.join(failed)}: reinstall the package "
                           "(sudo deploy/install.sh)"))
    if requires:
        out.append(Finding("torch", FAIL, f"the installed package requires torch ({'; '.join(requires)}), which only "
                           "the export extra needs: reinstall it from an intact release"))
    elif any("torch" in f for f in failed) or (not loaded_before and "torch" in sys.modules):
        out.append(Finding("torch", FAIL, "the runtime's modules import torch, which the board never has: a bug, "
                           "report it with the output of `cavatar doctor --json`"))
    else:
        out.append(Finding("torch", OK, "not required" + (" (installed here, unused by the runtime)" if installed
                                                          else " (not installed)")))
    return out


def _version(dist: str) -> str:
    try:
        return importlib.metadata.version(dist)
    except importlib.metadata.PackageNotFoundError:
        return "(version unknown)"


def _requires(dist: str) -> list[str] | None:
    try:
        return importlib.metadata.requires(dist)
    except importlib.metadata.PackageNotFoundError:
        return None


__all__ = ["check_onnxruntime", "check_python"]

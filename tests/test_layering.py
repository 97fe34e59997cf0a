"""design.md's layering, read from the source: who may import whom, private names, import cycles.

The table of design.md ("Layout"), as import rules (a rule names dotted prefixes; the most
specific rule for a module applies):

- ``cavatar_common`` (errors, provenance, atomic writes shared by several packages): stdlib only;
- ``firmware_protocol``: stdlib (+ cavatar_common);
- ``calibration``: numpy, scipy, firmware_protocol (+ cavatar_common); frames reach it through an
  interface the runtime passes in;
- ``edge``: numpy, scipy, onnxruntime, pyserial, pyusb, smbus2, paho-mqtt, firmware_protocol,
  calibration (+ cavatar_common) — never sim, export, torch; the virtual carpet arrives as a source
  plug-in (entry points). Inside edge, ``edge.cli`` is the top: nothing else in edge imports it;
  ``edge.body`` imports nothing else of edge, since sim may import it;
- ``sim``: numpy, scipy, edge.body (+ cavatar_common);
- ``export``: torch (onnx, anny for the body model) and everything above; ``export.cli`` also imports
  ``bench`` (`cavatar bench` runs bench.speed_error_run; bench may import everything).

Optional extras (matplotlib, h5py, joblib) may be imported only inside functions, so that a package
imports without them. A private name (``_x``) is never imported across top-level packages, and no
module of a package imports itself again through a cycle (lazy imports included).
"""

from __future__ import annotations

import ast
import sys
from dataclasses import dataclass
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
PACKAGES = ("cavatar_common", "firmware_protocol", "calibration", "edge", "sim", "export")
OPTIONAL = ("matplotlib", "h5py", "joblib")  # the viz and data extras: imported where used, never at import time

_EDGE_DEPS = ("numpy", "scipy", "onnxruntime", "serial", "usb", "smbus2", "paho", "firmware_protocol", "calibration",
              "cavatar_common")


@dataclass(frozen=True)
class Rule:
    allowed: tuple[str, ...]  # dotted prefixes this part may import (the stdlib always)
    denied: tuple[str, ...] = ()  # prefixes refused even though an allowed prefix covers them
    optional: bool = True  # OPTIONAL extras allowed inside functions


RULES: dict[str, Rule] = {
    "cavatar_common": Rule(("cavatar_common",), optional=False),
    "firmware_protocol": Rule(("firmware_protocol", "cavatar_common"), optional=False),
    "calibration": Rule(("calibration", "numpy", "scipy", "firmware_protocol", "cavatar_common")),
    "edge": Rule(("edge", *_EDGE_DEPS), denied=("edge.cli",)),
    "edge.cli": Rule(("edge", *_EDGE_DEPS)),
    "edge.__main__": Rule(("edge", *_EDGE_DEPS)),
    "edge.body": Rule(("edge.body", "numpy", "scipy", "cavatar_common")),
    "sim": Rule(("sim", "numpy", "scipy", "edge.body", "cavatar_common")),
    "export": Rule(("export", "torch", "onnx", "onnxscript", "anny", "sim", "edge", *_EDGE_DEPS)),
    "export.cli": Rule(("export", "bench", "torch", "onnx", "onnxscript", "anny", "sim", "edge", *_EDGE_DEPS)),
}


@dataclass(frozen=True)
class Import:
    module: str  # the importing module, dotted
    path: str  # its file, relative to the root
    line: int
    target: str  # the imported module, dotted (absolute)
    names: tuple[str, ...]  # for ``from target import a, b``
    lazy: bool  # inside a function body


def _covers(prefix: str, name: str) -> bool:
    return name == prefix or name.startswith(prefix + ".")


def module_name(root: Path, path: Path) -> str:
    parts = list(path.relative_to(root).with_suffix("").parts)
    if parts[-1] == "__init__":
        parts.pop()
    return ".".join(parts)


def _resolve(module: str, is_package: bool, node: ast.ImportFrom) -> str:
    """The absolute module of a ``from … import`` (relative ones resolved against ``module``)."""
    if not node.level:
        return node.module or ""
    base = module.split(".")
    base = base[: len(base) - node.level + (1 if is_package else 0)]
    return ".".join(base + ([node.module] if node.module else []))


def read_imports(root: Path, packages: tuple[str, ...]) -> list[Import]:
    """Every import statement of every module in ``packages`` (folders under ``root``)."""
    found: list[Import] = []
    for package in packages:
        for path in sorted((root / package).rglob("*.py")):
            module = module_name(root, path)
            tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
            found.extend(_imports_in(tree, module, path.name == "__init__.py", str(path.relative_to(root))))
    return found


def _imports_in(tree: ast.AST, module: str, is_package: bool, rel: str) -> list[Import]:
    out: list[Import] = []

    def visit(node: ast.AST, lazy: bool) -> None:
        for child in ast.iter_child_nodes(node):
            inner = lazy or isinstance(child, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda))
            if isinstance(child, ast.Import):
                out.extend(Import(module, rel, child.lineno, a.name, (), lazy) for a in child.names)
            elif isinstance(child, ast.ImportFrom):
                target = _resolve(module, is_package, child)
                out.append(Import(module, rel, child.lineno, target, tuple(a.name for a in child.names), lazy))
            visit(child, inner)

    visit(tree, False)
    return out


def rule_for(module: str) -> Rule:
    best = max((p for p in RULES if _covers(p, module)), key=len)
    return RULES[best]


def _private(name: str) -> bool:
    return name.startswith("_") and not (name.startswith("__") and name.endswith("__"))


def layering_violations(imports: list[Import]) -> list[str]:
    """One line per import that breaks RULES, OPTIONAL or the private-name rule."""
    bad: list[str] = []
    for imp in imports:
        top = imp.target.split(".")[0]
        where = f"{imp.path}:{imp.line}"
        if top in sys.stdlib_module_names or top == "__future__":
            continue
        rule = rule_for(imp.module)
        if top in OPTIONAL:
            if not rule.optional:
                bad.append(f"{where}: {imp.module} imports {imp.target} (an optional extra; this package is stdlib only)")
            elif not imp.lazy:
                bad.append(f"{where}: {imp.module} imports {imp.target} at import time; import optional extras "
                           "inside the function that needs them")
            continue
        ok = any(_covers(p, imp.target) for p in rule.allowed) and not any(
            _covers(p, imp.target) and not _covers(p, imp.module) for p in rule.denied)
        if not ok:
            bad.append(f"{where}: {imp.module} imports {imp.target}, which design.md does not allow")
        if top != imp.module.split(".")[0]:
            private = [n for n in (*imp.target.split("."), *imp.names) if _private(n)]
            if private:
                bad.append(f"{where}: {imp.module} imports the private {', '.join(private)} from {imp.target}")
    return bad


def import_cycles(root: Path, imports: list[Import]) -> list[list[str]]:
    """Cycles among modules of one top-level package (lazy imports count: they are a knot all the same)."""
    def known(name: str) -> bool:
        base = root / name.replace(".", "/")
        return base.with_suffix(".py").is_file() or (base / "__init__.py").is_file()

    graph: dict[str, set[str]] = {}
    for imp in imports:
        targets = [f"{imp.target}.{n}" for n in imp.names if known(f"{imp.target}.{n}")] or [imp.target]
        for t in targets:
            if t != imp.module and t.split(".")[0] == imp.module.split(".")[0] and known(t):
                graph.setdefault(imp.module, set()).add(t)
    cycles, state, stack = [], {}, []

    def walk(node: str) -> None:
        state[node] = 1
        stack.append(node)
        for nxt in sorted(graph.get(node, ())):
            if state.get(nxt) == 1:
                cycles.append(stack[stack.index(nxt):] + [nxt])
            elif nxt not in state:
                walk(nxt)
        stack.pop()
        state[node] = 2

    for node in sorted(graph):
        if node not in state:
            walk(node)
    return cycles


@pytest.fixture(scope="module")
def repo_imports() -> list[Import]:
    return read_imports(ROOT, PACKAGES)


def test_the_checker_reads_the_imports_it_must_judge(repo_imports):
    """A checker that read nothing would pass everything: it sees the known imports of each package."""
    seen = {(i.module, i.target) for i in repo_imports}
    assert ("edge.frames", "firmware_protocol") in seen
    assert ("sim.sensor.model", "sim.sensor.config") in seen  # a relative import, resolved
    assert {i.module.split(".")[0] for i in repo_imports} >= {"firmware_protocol", "calibration", "edge", "sim", "export"}


def test_imports_follow_design_md(repo_imports):
    bad = layering_violations(repo_imports)
    assert not bad, "imports that break the layering of design.md:\n" + "\n".join(bad)


def test_no_import_cycle_inside_a_package(repo_imports):
    cycles = import_cycles(ROOT, repo_imports)
    assert not cycles, "import cycles:\n" + "\n".join(" -> ".join(c) for c in cycles)


def _write(root: Path, files: dict[str, str]) -> None:
    for rel, text in files.items():
        path = root / rel
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_text(text)


def test_the_checker_fails_a_broken_tiny_repository(tmp_path):
    """Each kind of break, planted in a tiny tree of the same packages, is reported, and only those."""
    _write(tmp_path, {
        "cavatar_common/__init__.py": "",
        "firmware_protocol/__init__.py": "import numpy\n",  # stdlib only
        "calibration/__init__.py": "from edge.sources import open_source\n",  # calibration above edge
        "calibration/ok.py": "import numpy as np\nfrom scipy import ndimage\nfrom cavatar_common import errors\n",
        "edge/__init__.py": "",
        "edge/body/__init__.py": "from edge.frames import RawFrame\n",  # edge.body must stay low
        "edge/frames.py": "from firmware_protocol import codec\nfrom calibration.ok import np\n",
        "edge/runtime/demo.py": "def f():\n    from edge.cli.run import serve\n",  # runtime under cli
        "edge/sources/sim.py": "def g():\n    from sim.live import LiveCarpet\n",  # a hard import of sim
        "edge/plot.py": "import matplotlib\n",  # an optional extra at import time
        "edge/cli/__init__.py": "import edge.runtime.demo\n",
        "sim/__init__.py": "from edge.body.render import _draw_view\n",  # private across packages
        "sim/a.py": "from sim import b\n",
        "sim/b.py": "def h():\n    from sim.a import x\n",  # a cycle, even a lazy one
        "export/__init__.py": "import torch\nfrom sim import a\nfrom edge.cli import main\n",
    })
    imports = read_imports(tmp_path, PACKAGES)
    bad = layering_violations(imports)
    expected = {
        "firmware_protocol/__init__.py:1": "firmware_protocol imports numpy",
        "calibration/__init__.py:1": "calibration imports edge.sources",
        "edge/body/__init__.py:1": "edge.body imports edge.frames",
        "edge/runtime/demo.py:2": "edge.runtime.demo imports edge.cli.run",
        "edge/sources/sim.py:2": "edge.sources.sim imports sim.live",
        "edge/plot.py:1": "edge.plot imports matplotlib at import time",
    }
    for where, what in expected.items():
        assert any(line.startswith(f"{where}: {what}") for line in bad), (where, bad)
    assert any(line.startswith("sim/__init__.py:1: sim imports the private _draw_view") for line in bad), bad
    assert len(bad) == len(expected) + 1, bad  # the allowed imports (calibration/ok.py, edge/frames.py, export) pass
    assert import_cycles(tmp_path, imports) == [["sim.a", "sim.b", "sim.a"]]

"""The runtime configuration described: every key's type, default and purpose, and the file as TOML.

    for row in describe(): print(row.key, row.type, row.default, row.doc)
    text = to_toml()                 # deploy/cavatar.example.toml, `cavatar config show --toml`

Read from the section dataclasses of :mod:`edge.runtime.config` (their field metadata), so the
description and the checks never disagree; deploy/cavatar.example.toml is tested against it.
"""

from __future__ import annotations

import dataclasses
from typing import Any, NamedTuple

from edge.runtime.config import DELEGATED, SECTIONS, RuntimeConfig


class Key(NamedTuple):
    """One configuration key: dotted path, TOML type, default (TOML text) and its description."""

    key: str
    type: str
    default: str
    doc: str


def _toml_type(f: dataclasses.Field) -> str:
    t = str(f.type).replace("typing.", "")
    return {"bool": "boolean", "int": "integer", "float": "float", "str": "string", "list[str]": "array of strings",
            "tuple[int, int]": "array of 2 integers", "float | None": "float (optional)"}.get(t, t)


def toml_value(v: Any) -> str:
    """A TOML literal for a config value (strings quoted, arrays inline)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    raise TypeError(f"no TOML form for {v!r}")


def describe() -> list[Key]:
    """Every key of the configuration, in file order, with its type, default and description."""
    rows: list[Key] = []

    def add(kind: Any, prefix: str) -> None:
        for f in dataclasses.fields(kind):
            if f.default is not dataclasses.MISSING:
                default = f.default
            elif f.default_factory is not dataclasses.MISSING:
                default = f.default_factory()
            else:
                raise TypeError(f"{kind.__name__}.{f.name} has no default")
            if dataclasses.is_dataclass(default):
                add(type(default), f"{prefix}.{f.name}")
                continue
            doc = f.metadata.get("doc", "")
            if kind in DELEGATED.values():
                doc = kind.describe()[f.name].rsplit(" (default", 1)[0]
            rows.append(Key(f"{prefix}.{f.name}", _toml_type(f),
                            "(unset)" if default is None else toml_value(default), doc))

    for name, kind in SECTIONS.items():
        add(kind, name)
    return rows


def section_docs() -> dict[str, str]:
    """Section path → its one-line purpose."""
    out = {name: (kind.__doc__ or "").strip().splitlines()[0] for name, kind in SECTIONS.items()}
    out["scene"] = "Filters, contact detection, people segmentation and tracking (edge.scene.SceneConfig)."
    out["calibration.baseline"] = "Runtime baseline tracking of the calibration (calibration.baseline.BaselineConfig)."
    return out


def to_toml(config: RuntimeConfig | None = None, comments: bool = True) -> str:
    """The configuration as TOML (defaults when ``config`` is None), each key preceded by its description."""
    import textwrap

    config = config or RuntimeConfig()
    values = config.to_dict()
    docs = section_docs()
    rows = describe()
    lines: list[str] = []
    current = None
    for row in rows:
        section, key = row.key.rsplit(".", 1)
        if section != current:
            if lines:
                lines.append("")
            if comments:
                lines.append(f"# {docs.get(section, '')}")
            lines.append(f"[{section}]")
            current = section
        node: Any = values
        for part in section.split("."):
            node = node.get(part, {})
        if comments:
            lines += textwrap.wrap(f"{row.doc} ({row.type})", 110, initial_indent="# ", subsequent_indent="#   ")
        if key in node:
            lines.append(f"{key} = {toml_value(node[key])}")
        else:
            lines.append(f"# {key} = (unset)")
    return "\n".join(lines) + "\n"


__all__ = ["Key", "describe", "section_docs", "to_toml", "toml_value"]

"""One strict-dataclass config base: every field described, unknown keys refused, types checked.

    @dataclass(frozen=True)
    class DriftConfig(StrictConfig):
        WHAT: ClassVar[str] = "drift"
        hold_s: float = described(60.0, "how long a condition must last", at_least_zero)

        def __post_init__(self) -> None:
            self.check_fields()                       # ValueError "hold_s must be ≥ 0, got -1"

    DriftConfig.from_dict({"hold_s": 5})              # unknown keys: ValueError listing the accepted ones
    DriftConfig.describe()                            # {"hold_s": "how long ... (default 60.0)"}

A check is ``value -> problem or None``; the problem reads after the field's name
("must be > 0"). Stdlib only, so every package can use it.
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any, Callable, ClassVar

Check = Callable[[Any], str | None]


def described(default: Any, doc: str, check: Check | None = None) -> Any:
    """A dataclass field carrying its one-line doc and an optional check (a list default is copied per instance)."""
    meta = {"doc": doc, "check": check}
    if isinstance(default, list):
        return dataclasses.field(default_factory=lambda: list(default), metadata=meta)
    return dataclasses.field(default=default, metadata=meta)


def positive(v: Any) -> str | None:
    return None if v > 0 else "must be > 0"


def at_least_zero(v: Any) -> str | None:
    return None if v >= 0 else "must be ≥ 0"


def at_least_one(v: Any) -> str | None:
    return None if v >= 1 else "must be ≥ 1"


def between(lo: float, hi: float) -> Check:
    """A bounded value: a huge count would hang or exhaust the board rather than fail."""
    return lambda v: f"must be ≥ {lo}" if v < lo else (f"must be ≤ {hi}" if v > hi else None)


def _is_int(v: Any) -> bool:
    return isinstance(v, int) and not isinstance(v, bool)


def _is_number(v: Any) -> bool:
    return isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)


_TYPES: dict[str, tuple[str, Callable[[Any], bool]]] = {
    "bool": ("a boolean (true/false)", lambda v: isinstance(v, bool)),
    "int": ("an integer", _is_int),
    "float": ("a number", _is_number),
    "float | None": ("a number or None", lambda v: v is None or _is_number(v)),
    "str": ("a string", lambda v: isinstance(v, str)),
    "list[str]": ("an array of strings", lambda v: isinstance(v, list) and all(isinstance(x, str) for x in v)),
    "tuple[int, int]": ("two integers", lambda v: isinstance(v, tuple) and len(v) == 2 and all(map(_is_int, v))),
}


def expected_type(f: dataclasses.Field) -> tuple[str, Callable[[Any], bool]]:
    """(what the field holds in words, a test of a value) from its annotation; TypeError for an unsupported one."""
    t = (f.type if isinstance(f.type, str) else getattr(f.type, "__name__", str(f.type))).replace("typing.", "")
    if t not in _TYPES:
        raise TypeError(f"configuration field {f.name} has unsupported type {t}")
    return _TYPES[t]


def unknown_keys(cls: type, values: dict[str, Any], what: str) -> None:
    """ValueError naming the keys ``cls`` does not have and every one it accepts."""
    known = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(values) - known, key=str)
    if unknown:
        raise ValueError(f"unknown {what} option(s) {', '.join(map(str, unknown))}; accepted: {', '.join(sorted(known))}")


def strict_from_dict(cls: type, values: dict[str, Any], what: str) -> Any:
    """``cls(**values)`` for a dataclass, refusing unknown keys (a file written by a newer version fails loudly)."""
    unknown_keys(cls, values, what)
    return cls(**values)


class StrictConfig:
    """Base of a frozen config dataclass: ``from_dict`` refuses unknown keys, ``describe`` documents, fields are checked."""

    WHAT: ClassVar[str] = "config"

    def check_fields(self) -> None:
        """ValueError for the first field of the wrong type or failing its check (call from ``__post_init__``)."""
        for f in dataclasses.fields(self):  # type: ignore[arg-type]
            v = getattr(self, f.name)
            what, ok = expected_type(f)
            if not ok(v):
                raise ValueError(f"{f.name} must be {what}, got {v!r}")
            check = f.metadata.get("check")
            problem = check(v) if check and v is not None else None
            if problem:
                raise ValueError(f"{f.name} {problem}, got {v!r}")

    @classmethod
    def from_dict(cls, values: dict[str, Any]) -> Any:
        """Build from a parsed mapping: unknown keys refused, an integer taken for a number, a list for a tuple."""
        unknown_keys(cls, values, cls.WHAT)
        kwargs = {}
        for f in dataclasses.fields(cls):  # type: ignore[arg-type]
            if f.name in values:
                v = values[f.name]
                if isinstance(v, list) and str(f.type).startswith("tuple"):
                    v = tuple(v)
                elif _is_int(v) and str(f.type).startswith("float"):
                    v = float(v)
                kwargs[f.name] = v
        return cls(**kwargs)

    @classmethod
    def describe(cls) -> dict[str, str]:
        """Field name -> its one-line documentation, with its default."""
        return {f.name: f"{f.metadata['doc']} (default {f.default!r})" for f in dataclasses.fields(cls)}  # type: ignore[arg-type]

"""The strict-dataclass config base: unknown keys refused with the known ones, types and checks enforced."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import pytest

from cavatar_common.config import StrictConfig, between, described, positive


@dataclass(frozen=True)
class Demo(StrictConfig):
    WHAT: ClassVar[str] = "demo"

    hold_s: float = described(60.0, "how long a condition must last", positive)
    count: int = described(3, "how many reports", between(1, 10))
    tiles: tuple[int, int] = described((3, 3), "tiles (rows, cols)")

    def __post_init__(self) -> None:
        self.check_fields()


def test_unknown_keys_name_every_accepted_one():
    with pytest.raises(ValueError, match=r"unknown demo option\(s\) colour; accepted: count, hold_s, tiles"):
        Demo.from_dict({"colour": "red"})


def test_types_and_checks_are_enforced_with_the_field_name():
    with pytest.raises(ValueError, match="hold_s must be > 0, got 0.0"):
        Demo(hold_s=0.0)
    with pytest.raises(ValueError, match="count must be an integer, got 2.5"):
        Demo(count=2.5)
    with pytest.raises(ValueError, match="count must be ≤ 10, got 11"):
        Demo(count=11)
    with pytest.raises(ValueError, match="hold_s must be a number, got True"):
        Demo(hold_s=True)


def test_from_dict_takes_parsed_toml_values_and_describe_documents_each_field():
    d = Demo.from_dict({"hold_s": 5, "tiles": [2, 4]})
    assert d.hold_s == 5.0 and isinstance(d.hold_s, float) and d.tiles == (2, 4)
    assert Demo.describe()["count"] == "how many reports (default 3)"

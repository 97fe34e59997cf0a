"""Load protocol.toml into typed definitions and compute the definition hash.

The definition hash is CRC-16/CCITT-FALSE over a canonical text of the wire layout
(protocol version, header, and for each packet its id, name, seed kind, fields and
tail — never the documentation). It seeds the CRC of every packet marked
``seed = "definition"``, so that a peer built from another definition fails its CRC
instead of being misread (MAVLink's "CRC extra", folded into the seed).
"""

from __future__ import annotations

import binascii
import struct
import tomllib
from dataclasses import dataclass
from functools import cache
from pathlib import Path

SPEC_PATH = Path(__file__).with_name("protocol.toml")

# Field types → struct codes (little-endian). "char16" is 16 bytes of NUL-padded ASCII.
FIELD_CODES = {"u8": "B", "i8": "b", "u16": "H", "i16": "h", "u32": "I", "i32": "i", "char16": "16s"}


@dataclass(frozen=True)
class FieldDef:
    name: str
    type: str
    doc: str = ""
    enum: str | None = None


@dataclass(frozen=True)
class PacketDef:
    name: str
    id: int
    direction: str  # "device_to_host" | "host_to_device"
    seed: str  # "fixed" | "definition"
    fields: tuple[FieldDef, ...]
    tail: FieldDef | None
    doc: str

    @property
    def struct(self) -> struct.Struct:
        """Header and fixed payload fields (everything before the tail and the CRC)."""
        return struct.Struct("<BH" + "".join(FIELD_CODES[f.type] for f in self.fields))


@dataclass(frozen=True)
class Spec:
    name: str
    version: int
    fixed_seed: int
    max_packet_bytes: int
    header: tuple[FieldDef, ...]
    enums: dict[str, dict[str, int]]
    packets: tuple[PacketDef, ...]
    definition_hash: int

    def by_name(self, name: str) -> PacketDef:
        for p in self.packets:
            if p.name == name:
                return p
        raise KeyError(f"no packet named {name!r}; known: {', '.join(p.name for p in self.packets)}")

    def seed_for(self, packet: PacketDef) -> int:
        return self.fixed_seed if packet.seed == "fixed" else self.definition_hash


def _fields(items: list[dict]) -> tuple[FieldDef, ...]:
    out = []
    for item in items:
        if item["type"] not in FIELD_CODES:
            raise ValueError(f"protocol.toml: field {item['name']!r} has unknown type {item['type']!r}")
        out.append(FieldDef(item["name"], item["type"], item.get("doc", ""), item.get("enum")))
    return tuple(out)


def canonical_text(raw: dict) -> str:
    """The hashed description of the wire layout: one line per packet, docs left out."""
    proto = raw["protocol"]
    lines = [f"{proto['name']} v{proto['version']} {proto['byte_order']} {proto['framing']} {proto['crc']}"]
    lines.append("header " + ",".join(f"{f['name']}:{f['type']}" for f in raw["header"]["fields"]))
    for p in sorted(raw["packet"], key=lambda p: p["id"]):
        fields = ",".join(f"{f['name']}:{f['type']}" for f in p["fields"])
        tail = f" tail {p['tail']['name']}:{p['tail']['type']}" if "tail" in p else ""
        lines.append(f"{p['id']:#04x} {p['name']} {p['seed']} {p['direction']} [{fields}]{tail}")
    for name in sorted(raw.get("enums", {})):
        values = {k: v for k, v in raw["enums"][name].items() if k != "doc"}
        lines.append(f"enum {name} " + ",".join(f"{k}={v}" for k, v in sorted(values.items(), key=lambda kv: kv[1])))
    return "\n".join(lines) + "\n"


def parse(raw: dict) -> Spec:
    proto = raw["protocol"]
    packets = []
    for p in raw["packet"]:
        tail = p.get("tail")
        packets.append(
            PacketDef(
                name=p["name"],
                id=int(p["id"]),
                direction=p["direction"],
                seed=p["seed"],
                fields=_fields(p["fields"]),
                tail=FieldDef(tail["name"], tail["type"], tail.get("doc", "")) if tail else None,
                doc=p.get("doc", ""),
            )
        )
    ids = [p.id for p in packets]
    if len(set(ids)) != len(ids):
        raise ValueError("protocol.toml: two packets share an id")
    enums = {name: {k: v for k, v in values.items() if k != "doc"} for name, values in raw.get("enums", {}).items()}
    definition_hash = binascii.crc_hqx(canonical_text(raw).encode("ascii"), 0xFFFF)
    return Spec(
        name=proto["name"],
        version=int(proto["version"]),
        fixed_seed=int(proto["fixed_seed"]),
        max_packet_bytes=int(proto["max_packet_bytes"]),
        header=_fields(raw["header"]["fields"]),
        enums=enums,
        packets=tuple(packets),
        definition_hash=definition_hash,
    )


@cache
def load(path: Path = SPEC_PATH) -> Spec:
    """The protocol definition this host speaks (cached)."""
    with open(path, "rb") as fh:
        return parse(tomllib.load(fh))

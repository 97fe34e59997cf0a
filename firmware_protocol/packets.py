"""The protocol's packets as Python classes, built from protocol.toml at import.

The spec file is the only place a field is defined: each packet becomes a frozen
dataclass (``seq`` first, then its fields, then its tail) carrying ``NAME``, ``TYPE``
(its id), ``DEF`` (its :class:`~firmware_protocol.spec.PacketDef`) and ``STRUCT``.
The protocol's constants and enums come from the same load.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass, make_dataclass
from typing import Any

from firmware_protocol import spec as _spec

SPEC = _spec.load()
PROTOCOL_VERSION = SPEC.version
DEFINITION_HASH = SPEC.definition_hash
PACKING = SPEC.enums["packing"]  # name -> code
NAK_REASON = SPEC.enums["nak_reason"]
SIGN = SPEC.enums["sign"]  # name -> value
PACKING_NAMES = {v: k for k, v in PACKING.items()}
NAK_REASON_NAMES = {v: k for k, v in NAK_REASON.items()}
CRC16 = struct.Struct("<H")  # the CRC-16 that ends every packet
INFO_PREFIX = struct.Struct("<BHHH")  # type, seq, protocol_version, definition_hash: frozen forever


def _packet_class(pdef: _spec.PacketDef) -> type:
    """The frozen dataclass of one packet definition."""
    names = [("seq", int)] + [(f.name, Any) for f in pdef.fields]
    if pdef.tail is not None:
        names.append((pdef.tail.name, bytes))
    cls = make_dataclass(
        "".join(part.title() for part in pdef.name.split("_")),
        names,
        frozen=True,
        slots=True,
        namespace={"NAME": pdef.name, "TYPE": pdef.id, "DEF": pdef, "STRUCT": pdef.struct, "__module__": __name__},
    )
    cls.__doc__ = f"{pdef.name} (0x{pdef.id:02X}, {pdef.direction.replace('_', ' ')}): {pdef.doc}"
    return cls


# Any: the classes are made from the spec at import, so their fields are known at run time only.
PACKET_CLASSES: dict[str, Any] = {p.name: _packet_class(p) for p in SPEC.packets}
BY_ID: dict[int, type] = {cls.TYPE: cls for cls in PACKET_CLASSES.values()}
SEED: dict[int, int] = {cls.TYPE: SPEC.seed_for(cls.DEF) for cls in PACKET_CLASSES.values()}  # CRC seed by id

Info = PACKET_CLASSES["INFO"]
Row = PACKET_CLASSES["ROW"]
FrameEnd = PACKET_CLASSES["FRAME_END"]
Status = PACKET_CLASSES["STATUS"]
Ack = PACKET_CLASSES["ACK"]
Nak = PACKET_CLASSES["NAK"]
GetInfo = PACKET_CLASSES["GET_INFO"]
Start = PACKET_CLASSES["START"]
Stop = PACKET_CLASSES["STOP"]
SetRate = PACKET_CLASSES["SET_RATE"]
SetGain = PACKET_CLASSES["SET_GAIN"]
Ping = PACKET_CLASSES["PING"]


@dataclass(frozen=True, slots=True)
class ForeignInfo:
    """An INFO whose CRC is good but whose definition is not ours (its layout may differ too)."""

    seq: int
    protocol_version: int
    definition_hash: int

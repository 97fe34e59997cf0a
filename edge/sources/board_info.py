"""A board's INFO as a carpet source reads it: the checks, the identity a calibration is bound to, the messages.

An INFO from another protocol definition is refused loudly (``ProtocolMismatchError``);
one whose fields are out of range never sizes a buffer. The first INFO pins the board's
identity (:data:`IDENTITY`); a later INFO with another identity is another board.
"""

from __future__ import annotations

from typing import Any

from firmware_protocol import codec

IDENTITY = ("device_id", "rows", "cols", "adc_bits", "sign")  # INFO fields a calibration is bound to


INFO_TYPES = (codec.Info, codec.ForeignInfo)  # an INFO of our protocol definition or another's


def is_info(pkt: Any) -> bool:
    """Whether ``pkt`` is an INFO, of our protocol definition or another's."""
    return isinstance(pkt, INFO_TYPES)


def info_problems(info: Any) -> list[str]:
    """Why ``info`` is out of range for a host to act on (empty: usable); ProtocolMismatchError unless it is ours."""
    codec.check_compatible(info)
    return codec.info_range_problems(info)


def identity_changes(pinned: Any, info: Any) -> list[str]:
    """The :data:`IDENTITY` fields where ``info`` differs from the ``pinned`` INFO, as "key new (was old)"."""
    return [f"{key} {theirs!r} (was {ours!r})" for key, ours, theirs in
            ((key, getattr(pinned, key), getattr(info, key)) for key in IDENTITY) if ours != theirs]


def board_mismatch_message(changes: list[str]) -> str:
    """Why frames are held back when another board answered (``changes`` from :func:`identity_changes`)."""
    return ("another board answered: " + ", ".join(changes) + ". Its frames are not used (the calibration "
            "and model belong to the first board); plug the original board back, or calibrate this one "
            "and restart with its calibration.")


def no_info_message(where: str, stats: codec.DecoderStats, timeout_s: float) -> str:
    """Why no INFO came from ``where`` within ``timeout_s``, guessed from the decoder's ``stats``."""
    if stats.bytes_in == 0:
        return f"{where}: no bytes from the board within {timeout_s} s; is it powered and running carpet firmware?"
    if stats.dropped.get("bad_crc", 0) >= 3 and stats.packets == 0:
        return (
            f"{where}: {stats.dropped['bad_crc']} well-framed packets failed their CRC and none passed: the board likely "
            f"speaks another protocol definition (ours: v{codec.PROTOCOL_VERSION}, 0x{codec.DEFINITION_HASH:04X}); "
            "update the firmware or the host"
        )
    return (f"{where}: {stats.bytes_in} bytes but no INFO packet within {timeout_s} s "
            "(wrong baud rate or not a carpet board?)")

"""Ask a board for its INFO packet through the runtime's own source code, then let it go (`cavatar doctor`).

Common to every scheme whose board is not known from its URL alone (serial://, usb://, replay://,
a plug-in that does not state its board): the source is opened as `cavatar run` opens it, the
handshake waits at most ``timeout_s``, and the source is stopped again.
"""

from __future__ import annotations

from typing import Any

from edge.health import FAIL, OK, Board, Finding


def probe_board(url: str, timeout_s: float, usb_backend: Any = None) -> tuple[Board | None, Finding]:
    """(the board as its INFO packet describes it, the ``board`` finding); (None, FAIL) when it did not answer."""
    from edge.sources import SourceError, open_source
    from firmware_protocol.codec import ProtocolError

    try:
        source = open_source(url, usb_backend=usb_backend, handshake_timeout_s=timeout_s)
        source.start()
    except (SourceError, ProtocolError, OSError, ValueError) as exc:
        return None, Finding("board", FAIL, f"no INFO from the board: {exc}")
    try:
        info = source.info
    finally:
        source.stop()
    fw = f"{info.fw_major}.{info.fw_minor}.{info.fw_patch}"
    board = Board("the board's INFO packet", info.device_id, int(info.rows), int(info.cols), int(info.adc_bits), info)
    return board, Finding("board", OK, f"{info.device_id} answered: {info.rows}×{info.cols}, {info.adc_bits}-bit, "
                          f"{info.rate_mhz / 1000:g} Hz, firmware {fw}, protocol v{info.protocol_version}")


__all__ = ["probe_board"]

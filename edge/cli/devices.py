"""`cavatar devices`: serial ports and USB devices that could be a carpet readout board."""

from __future__ import annotations

import argparse

from edge.cli import command_name


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        command_name(__name__),
        help="list serial ports and USB devices that could be the carpet's readout board",
        description="List serial ports (stable /dev/serial/by-id names first) and USB devices. "
        "Boards with our default USB id 1209:CA7A are marked; use the printed URL as --source.",
    )
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from serial.tools import list_ports

    from edge.sources.base import SourceError
    from edge.sources.usb_bulk import DEFAULT_VID_PID, list_devices

    ours = "{:04x}:{:04x}".format(*DEFAULT_VID_PID)
    ports = sorted(list_ports.comports(), key=lambda p: p.device)
    print("Serial ports:")
    if not ports:
        print("  none found")
    for port in ports:
        vid_pid = f"{port.vid:04x}:{port.pid:04x}" if port.vid is not None else "-"
        mark = "  <- carpet board" if vid_pid == ours else ""
        print(f"  serial://{port.device}  [{vid_pid}] {port.description}{mark}")
    print("USB devices:")
    try:
        devices = list_devices()
    except SourceError as exc:
        print(f"  unavailable: {exc}")
        return 0
    if not devices:
        print("  none found")
    for vid_pid in devices:
        mark = "  <- carpet board" if vid_pid == ours else ""
        print(f"  usb://{vid_pid}{mark}")
    return 0

"""The `cavatar` command line: every subcommand has help, errors are one clear line."""

from types import SimpleNamespace

import pytest

from edge.cli import SUBCOMMANDS, build_parser, main


def test_every_registered_subcommand_is_available_and_has_help(capsys):
    parser, unavailable = build_parser()
    assert unavailable == {}, f"subcommands that failed to import: {unavailable}"
    import argparse

    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    names = list(sub.choices)
    assert len(names) >= len(SUBCOMMANDS)
    for name in names:
        with pytest.raises(SystemExit) as exc:
            main([name, "--help"])
        assert exc.value.code == 0
        out = capsys.readouterr().out
        assert out.startswith(f"usage: cavatar {name}") and len(out.splitlines()) > 3


def test_command_names_are_written_once_in_subcommands(monkeypatch):
    """--help lists exactly the names of SUBCOMMANDS; a module that adds another name is refused, and a module that
    cannot import is reported under its own command names (not its module's last component)."""
    import argparse

    parser, _ = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    assert list(sub.choices) == [name for names in SUBCOMMANDS.values() for name in names]
    monkeypatch.setitem(SUBCOMMANDS, "edge.cli.doctor", ("checkup",))  # edge's modules read their name from it
    parser, _ = build_parser()
    sub = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    assert "checkup" in sub.choices and "doctor" not in sub.choices
    monkeypatch.setitem(SUBCOMMANDS, "export.score.cli", ("grade",))  # a module that names its own command
    with pytest.raises(ValueError, match=r"export.score.cli added the commands \('score',\); SUBCOMMANDS lists"):
        build_parser()
    monkeypatch.setitem(SUBCOMMANDS, "export.score.cli", ("score",))
    monkeypatch.setitem(SUBCOMMANDS, "no_such_module_for_cavatar.cli", ("ghost", "phantom"))
    parser, unavailable = build_parser()
    assert set(unavailable) == {"ghost", "phantom"} and "No module named" in unavailable["ghost"]
    assert "ghost: unavailable" in parser.epilog and "phantom: unavailable" in parser.epilog


def test_no_command_prints_help_and_fails(capsys):
    assert main([]) == 2
    assert "commands:" in capsys.readouterr().out


def test_devices_lists_ports_and_marks_our_board(monkeypatch, capsys):
    import serial.tools.list_ports

    import edge.sources.usb_bulk as usb_bulk

    ports = [
        SimpleNamespace(device="/dev/ttyACM0", vid=0x1209, pid=0xCA7A, description="CAvatar carpet"),
        SimpleNamespace(device="/dev/ttyS0", vid=None, pid=None, description="n/a"),
    ]
    monkeypatch.setattr(serial.tools.list_ports, "comports", lambda: ports)
    monkeypatch.setattr(usb_bulk, "list_devices", lambda backend=None: ["1d6b:0002", "1209:ca7a"])
    assert main(["devices"]) == 0
    out = capsys.readouterr().out
    assert "serial:///dev/ttyACM0  [1209:ca7a] CAvatar carpet  <- carpet board" in out
    assert "serial:///dev/ttyS0  [-]" in out
    assert "usb://1209:ca7a  <- carpet board" in out and "usb://1d6b:0002\n" in out


def test_devices_without_libusb_says_what_to_install(monkeypatch, capsys):
    import serial.tools.list_ports

    import edge.sources.usb_bulk as usb_bulk
    from edge.sources.base import SourceError

    def no_backend(backend=None):
        raise SourceError("pyusb found no libusb backend; install it (Debian: apt-get install libusb-1.0-0)")

    monkeypatch.setattr(serial.tools.list_ports, "comports", lambda: [])
    monkeypatch.setattr(usb_bulk, "list_devices", no_backend)
    assert main(["devices"]) == 0
    out = capsys.readouterr().out
    assert "none found" in out and "libusb-1.0-0" in out


def test_stream_prints_a_summary_each_second(capsys):
    assert main(["stream", "--source", "sim://?world=footsteps&people=1&speed=4", "--seconds", "1.6"]) == 0
    out = capsys.readouterr().out
    assert "device 'sim-0', 96x96, 12-bit" in out
    assert "fps  active sensels" in out
    assert "decoder:" in out and "dropped 0" in out


def test_stream_error_is_one_line(capsys):
    assert main(["stream", "--source", "sim://?people=7"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("cavatar stream: error:") and "people must be 0..3" in err[0]

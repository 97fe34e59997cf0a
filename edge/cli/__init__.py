"""The `cavatar` command line: one entry point, one module per subcommand.

Each module listed in SUBCOMMANDS defines ``register(subparsers)``, which adds its
parser(s) and sets ``func`` (called with the parsed namespace, returns an exit code).
A module that fails to import (an optional part, e.g. one that needs the `export`
extra) is reported in ``cavatar --help`` and never breaks the other subcommands.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys

from cavatar_common.errors import CliError  # noqa: F401  (re-exported: the subcommands raise it)
from edge import __version__

# Module paths, in the order they appear in --help. Later issues append theirs.
SUBCOMMANDS: list[str] = [
    "edge.cli.devices",
    "edge.cli.record",
    "edge.cli.inspect",
    "edge.cli.stream",
    "edge.cli.peripherals",
    "edge.cli.render",
    "sim.cli",
    "export.cli",
    "edge.cli.calibrate",
    "edge.cli.run",
    "edge.cli.config_cmd",
    "edge.cli.status",
    "edge.cli.doctor",
    "export.score.cli",
]

EPILOG = """\
Sources are URLs: serial:///dev/ttyACM0?baud=2000000, usb://VID:PID,
replay://capture.bin?speed=1, sim://?people=2&seed=7 (the virtual carpet).
Run `cavatar COMMAND --help` for the options of one command.
"""


def build_parser() -> tuple[argparse.ArgumentParser, dict[str, str]]:
    parser = argparse.ArgumentParser(
        prog="cavatar",
        description="CAvatar Edge: private, real-time 3D human bodies from a tactile carpet.",
        epilog=EPILOG,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    parser.add_argument("--version", action="version", version=f"cavatar-edge {__version__}")
    parser.add_argument("-v", "--verbose", action="count", default=0, help="more log output (-vv for debug)")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND", title="commands")
    unavailable: dict[str, str] = {}
    for module_name in SUBCOMMANDS:
        try:
            module = importlib.import_module(module_name)
        except ImportError as exc:  # an optional part that is not installed
            unavailable[module_name.rsplit(".", 1)[-1]] = str(exc)
            continue
        module.register(sub)
    if unavailable:
        lines = [f"  {name}: unavailable ({why})" for name, why in unavailable.items()]
        parser.epilog = EPILOG + "\nNot available in this installation:\n" + "\n".join(lines)
    return parser, unavailable


def main(argv: list[str] | None = None) -> int:
    parser, _ = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(
        level=logging.WARNING - 10 * min(args.verbose, 2),
        format="%(asctime)s %(levelname)s %(name)s: %(message)s",
    )
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except CliError as exc:
        print(f"cavatar {args.command}: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        print(f"cavatar {args.command}: interrupted", file=sys.stderr)
        return 130


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())

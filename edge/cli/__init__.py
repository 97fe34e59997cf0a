"""The `cavatar` command line: one entry point, one module per subcommand.

Each module listed in SUBCOMMANDS defines ``register(subparsers)``, which adds its
parser(s) and sets ``func`` (called with the parsed namespace, returns an exit code).
SUBCOMMANDS is the one place the command names are written: edge's own modules read
theirs back with :func:`command_name`, and a module that adds other names than listed is
a ValueError. A module that fails to import (an optional part, e.g. one that needs the
`export` extra) is reported in ``cavatar --help`` under its command names and never
breaks the other subcommands.
"""

from __future__ import annotations

import argparse
import importlib
import logging
import sys

from cavatar_common.errors import CliError  # noqa: F401  (re-exported: the subcommands raise it)
from edge import __version__

# Module → the commands it adds, in the order they appear in --help. Later issues append theirs.
SUBCOMMANDS: dict[str, tuple[str, ...]] = {
    "edge.cli.devices": ("devices",),
    "edge.cli.record": ("record",),
    "edge.cli.inspect": ("inspect",),
    "edge.cli.stream": ("stream",),
    "edge.cli.peripherals": ("peripherals",),
    "edge.cli.render": ("render",),
    "sim.cli": ("sim",),
    "export.cli": ("train", "bundle", "eval", "finetune", "bench"),
    "edge.cli.calibrate": ("calibrate",),
    "edge.cli.run": ("run",),
    "edge.cli.config_cmd": ("config",),
    "edge.cli.status": ("status",),
    "edge.cli.doctor": ("doctor",),
    "export.score.cli": ("score",),
}


def command_name(module: str) -> str:
    """The one command ``module`` (a module path in SUBCOMMANDS) adds; KeyError/ValueError when it is not listed so."""
    names = SUBCOMMANDS[module]
    if len(names) != 1:
        raise ValueError(f"{module} adds {len(names)} commands ({', '.join(names)}), not one")
    return names[0]


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
    for module_name, names in SUBCOMMANDS.items():
        try:
            module = importlib.import_module(module_name)
        except ImportError as exc:  # an optional part that is not installed
            unavailable.update(dict.fromkeys(names, str(exc)))
            continue
        before = set(sub.choices)
        module.register(sub)
        added = tuple(name for name in sub.choices if name not in before)
        if sorted(added) != sorted(names):
            raise ValueError(f"{module_name} added the commands {added}; SUBCOMMANDS lists {names} for it")
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

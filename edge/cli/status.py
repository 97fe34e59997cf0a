"""`cavatar status`: what a running (or stopped) `cavatar run` reports in its status file.

    cavatar status                          # the status file of the configuration in use (see below)
    cavatar status --config cavatar.toml    # the status file that configuration names
    cavatar status --file /run/cavatar/status.json --json
"""

from __future__ import annotations

import argparse
import json

from edge.cli import CliError, command_name


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        command_name(__name__),
        help="print the health of `cavatar run`: frames, drops, people, work saved, ms per stage, sinks",
        description="Reads the status file that `cavatar run` rewrites every second (atomically) and prints it: "
        "frames in and dropped, decoder and frame-assembly drops, invalid frames, work saved, per-stage "
        "milliseconds (median/p99), publish lag and every sink's counters, calibration age.",
        epilog=__doc__.split("\n\n")[1],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--file", metavar="PATH", help="status file (default: runtime.status_file of the configuration in use)")
    p.add_argument("--config", metavar="FILE", help="take the status file's path from this configuration (default: "
                   "$CAVATAR_CONFIG, else /etc/cavatar/cavatar.toml when it exists, else the built-in defaults)")
    p.add_argument("--json", action="store_true", help="print the raw JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from edge.runtime.config import ConfigError
    from edge.runtime.config_choice import load_chosen
    from edge.runtime.status import StatusFileError, format_status, read_status

    path, note = args.file, "--file"
    if path is None:
        try:
            cfg, choice = load_chosen(args.config)
        except ConfigError as exc:
            raise CliError(str(exc)) from None
        path, note = cfg.runtime.status_file, choice.describe
    try:
        status = read_status(path)
    except StatusFileError as exc:
        raise CliError(f"{exc} (status file from {note})") from None
    if args.json:
        print(json.dumps(status, indent=1))
    else:
        print(f"status file {path} ({note})")
        print(format_status(status))
    return 0

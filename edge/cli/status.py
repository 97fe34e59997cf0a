"""`cavatar status`: what a running (or stopped) `cavatar run` reports in its status file.

    cavatar status                          # the default status file (out/cavatar/status.json)
    cavatar status --config cavatar.toml    # the status file that configuration names
    cavatar status --file /run/cavatar/status.json --json
"""

from __future__ import annotations

import argparse
import json

from edge.cli import CliError


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        "status",
        help="print the health of `cavatar run`: frames, drops, people, work saved, ms per stage, sinks",
        description="Reads the status file that `cavatar run` rewrites every second (atomically) and prints it: "
        "frames in and dropped, decoder and frame-assembly drops, invalid frames, work saved, per-stage "
        "milliseconds (median/p99), publish lag and every sink's counters, calibration age.",
        epilog=__doc__.split("\n\n")[1],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--file", metavar="PATH", help="status file (default: runtime.status_file of --config, or out/cavatar/status.json)")
    p.add_argument("--config", metavar="FILE", help="take the status file's path from this configuration")
    p.add_argument("--json", action="store_true", help="print the raw JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from edge.runtime.config import ConfigError, RuntimeConfig, load_config
    from edge.runtime.status import StatusFileError, format_status, read_status

    path = args.file
    if path is None:
        try:
            cfg = load_config(args.config) if args.config else RuntimeConfig()
        except ConfigError as exc:
            raise CliError(str(exc)) from None
        path = cfg.runtime.status_file
    try:
        status = read_status(path)
    except StatusFileError as exc:
        raise CliError(str(exc)) from None
    if args.json:
        print(json.dumps(status, indent=1))
    else:
        print(format_status(status))
    return 0

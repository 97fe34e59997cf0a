"""`cavatar doctor`: check that this board can run `cavatar run` with a configuration, and say what to fix.

    cavatar doctor --config /etc/cavatar/cavatar.toml     # one line per check: ok / warn / FAIL
    cavatar doctor --config cavatar.toml --no-open        # leave the board closed (no INFO probe)
    cavatar doctor --config cavatar.toml --json           # the findings as JSON

Exit 0 when nothing FAILed (warnings allowed), 1 otherwise. The checks are listed in
edge/runtime/doctor.py. Paths and devices are checked for the user running it: run it as the
service user to see what the service sees (docs/install-pi.md shows how).
"""

from __future__ import annotations

import argparse
import json

from edge.cli import command_name


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        command_name(__name__),
        help="check an installation: packages, configuration, board, calibration, model, sinks (ok / warn / FAIL)",
        description="Checks everything `cavatar run` needs, one line per check (ok, warn or FAIL; a line that is not "
        "ok says what to do): Python and packages, onnxruntime (and that torch is not needed), the configuration, "
        "the source (device present and accessible; the board's INFO packet within 2 s), the calibration (hash, "
        "age, that it belongs to the board), the model bundle (hashes, body model, grid), each sink (folder "
        "writable and disk space; MQTT broker reachable and the login accepted) and the status file's folder. "
        "Exit 0 when nothing FAILed, 1 otherwise.",
        epilog=__doc__.split("\n\n")[1],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--config", metavar="FILE", help="TOML configuration to check (default, as `cavatar run`: "
                   "$CAVATAR_CONFIG, else /etc/cavatar/cavatar.toml when it exists, else the built-in defaults)")
    p.add_argument("--no-open", action="store_true", help="do not open the board to wait for its INFO packet")
    p.add_argument("--json", action="store_true", help="print the findings as JSON")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from edge.runtime.config_choice import choose_config
    from edge.runtime.doctor import FAIL, OK, WARN, as_json, diagnose, exit_code

    choice = choose_config(args.config)
    findings = diagnose(choice.path, open_board=not args.no_open, config_reason=choice.reason)
    if args.json:
        print(json.dumps(as_json(findings, choice.path), indent=1))
        return exit_code(findings)
    for f in findings:
        print(f.line())
    counts = {level: sum(f.level == level for f in findings) for level in (OK, WARN, FAIL)}
    verdict = "ready" if not counts[FAIL] else "NOT ready: fix the FAIL lines"
    print(f"doctor: {counts[OK]} ok, {counts[WARN]} warn, {counts[FAIL]} FAIL — {verdict}")
    return exit_code(findings)

"""`cavatar config`: check a runtime configuration file, or describe every key.

    cavatar config validate /etc/cavatar/cavatar.toml     # exit 0 and a summary, or exit 2 and every problem
    cavatar config show                                   # every key: type, default, description
    cavatar config show --toml > cavatar.toml             # the defaults as a commented TOML file
    cavatar config show --file cavatar.toml --toml        # the effective configuration of a file
"""

from __future__ import annotations

import argparse
import textwrap

from edge.cli import CliError, command_name


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        command_name(__name__),
        help="validate a runtime configuration file or describe every key",
        description=textwrap.fill(
            "The runtime's TOML configuration is typed: unknown keys and wrong types are refused with the key path; "
            "secrets (the MQTT password) come only from the environment (CAVATAR_MQTT_PASSWORD). `validate FILE` "
            "checks a file, `show` describes every key or prints the defaults as TOML.", 88),
        epilog=__doc__.split("\n\n")[1],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    actions = p.add_subparsers(dest="config_action", metavar="ACTION", title="actions")
    v = actions.add_parser("validate", help="check a configuration file: exit 0 and a summary, or 2 and every problem")
    v.add_argument("file", help="TOML configuration file")
    v.set_defaults(func=validate)
    s = actions.add_parser("show", help="describe every key (type, default, description) or print TOML")
    s.add_argument("--toml", action="store_true", help="print a commented TOML file instead of the table")
    s.add_argument("--file", metavar="FILE", help="show this file's effective values (defaults filled in)")
    s.set_defaults(func=show)
    p.set_defaults(func=lambda args: (p.print_help(), 2)[1])


def _load(path: str):
    from edge.runtime.config import ConfigError, load_config

    try:
        return load_config(path)
    except ConfigError as exc:
        raise CliError(str(exc)) from None


def validate(args: argparse.Namespace) -> int:
    from edge.sinks import redact

    cfg = _load(args.file)
    cal = cfg.calibration.file or "(none: a sim:// source is calibrated automatically; a real carpet is refused)"
    bundle = cfg.model.bundle or f"(the shipped bundle, {cfg.bundle_path()})"
    print(f"{args.file}: valid")
    print(f"  device {cfg.device.id}; source {redact(cfg.source.url)} (queue {cfg.source.queue_frames} frames)")
    print(f"  calibration {cal}; due after {cfg.calibration.max_age_days:g} days")
    print(f"  model {bundle}, {cfg.model.threads} thread(s)")
    print(f"  sinks: {', '.join(redact(u) for u in cfg.sinks.urls)}")
    run_for = "until stopped" if cfg.runtime.seconds <= 0 else f"{cfg.runtime.seconds:g} s"
    print(f"  status {cfg.runtime.status_file} every {cfg.runtime.status_s:g} s; heartbeat every "
          f"{cfg.runtime.heartbeat_s:g} s while empty; runs {run_for}")
    return 0


def show(args: argparse.Namespace) -> int:
    from edge.runtime.config import RuntimeConfig
    from edge.runtime.config_docs import describe, section_docs, to_toml, toml_value

    cfg = _load(args.file) if args.file else RuntimeConfig()
    if args.toml:
        print(to_toml(cfg), end="")
        return 0
    docs = section_docs()
    current = None
    for row in describe():
        section = row.key.rsplit(".", 1)[0]
        if section != current:
            print(f"\n[{section}]  {docs.get(section, '')}")
            current = section
        value = row.default
        if args.file:
            node = cfg.to_dict()
            for part in row.key.split("."):
                node = node.get(part, {}) if isinstance(node, dict) else {}
            value = "(unset)" if node == {} else toml_value(node)
        print(f"  {row.key} ({row.type}) = {value}")
        print(textwrap.fill(row.doc, 100, initial_indent="      ", subsequent_indent="      "))
    print("\nSecrets are never in the file: the MQTT password comes from $CAVATAR_MQTT_PASSWORD "
          "(or the variable a sink URL names with password_env=).")
    return 0

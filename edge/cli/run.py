"""`cavatar run`: the edge runtime — frames from a carpet, private 3D bodies to MQTT or files.

    cavatar run                                        # /etc/cavatar/cavatar.toml if installed, else the virtual carpet
    cavatar run --config /etc/cavatar/cavatar.toml
    cavatar run --source serial:///dev/ttyACM0 --calibration cal.npz --sink mqtt://cavatar@broker/cavatar

Without --config, $CAVATAR_CONFIG or else /etc/cavatar/cavatar.toml (when it exists) is used,
and the first line says which. Flags override the configuration file; without either, the shipped model bundle
(edge/models/lean-96), the virtual carpet and a JSON-lines file out/cavatar/bodies.jsonl
(status in out/cavatar/status.json). One summary line per second on stderr. SIGTERM or
Ctrl-C stops cleanly: the reader stops, queued records are published, the sinks say
"offline" and close, the status file says "stopped", exit 0. A bad configuration, a
tampered bundle or a calibration of another carpet: one paragraph, exit 2, no output written.

A broker that is down does not stop the run (records are queued or spooled, it reconnects),
but a sink that never connected during the whole run ends it with a WARNING line and exit 1.
--require-sinks [S] refuses to start unless every MQTT sink connects within S seconds
(default 10): one line, exit 1, the carpet never read.
"""

from __future__ import annotations

import argparse
import signal
import sys
import threading
import time
from typing import Any

from edge.cli import CliError, command_name

REQUIRE_SINKS_S = 10.0


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        command_name(__name__),
        help="run the edge runtime: carpet → calibrated pressure → people → 3D bodies → MQTT / files",
        description=__doc__.split("\n\n", 1)[1].split("\n\n", 1)[1],
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("--config", metavar="FILE", help="TOML configuration (see `cavatar config show`, deploy/cavatar.example.toml); "
                   "default: $CAVATAR_CONFIG, else /etc/cavatar/cavatar.toml when it exists, else the built-in defaults")
    p.add_argument("--source", metavar="URL", help="source URL (overrides [source] url), e.g. 'sim://?people=2&seed=7'")
    p.add_argument("--calibration", metavar="FILE", help="calibration file from `cavatar calibrate` (overrides [calibration] file)")
    p.add_argument("--bundle", metavar="DIR", help="model bundle folder (overrides [model] bundle; default: the shipped one)")
    p.add_argument("--sink", metavar="URL", action="append",
                   help="sink URL, repeatable (replaces [sinks] urls), e.g. jsonl://out/bodies.jsonl or mqtt://host/cavatar")
    p.add_argument("--seconds", type=float, metavar="S", help="stop after S seconds (overrides [runtime] seconds; 0 = forever)")
    p.add_argument("--device", metavar="ID", help="device id in records and MQTT topics (overrides [device] id)")
    p.add_argument("--status-file", metavar="FILE", help="status file (overrides [runtime] status_file)")
    p.add_argument("--quiet", action="store_true", help="no per-second summary line")
    p.add_argument("--require-sinks", type=float, nargs="?", const=REQUIRE_SINKS_S, default=None, metavar="S",
                   help=f"refuse to start (exit 1) unless every MQTT sink connects within S seconds (default "
                        f"{REQUIRE_SINKS_S:g}); without it a broker that is down at start is waited for in the background")
    p.set_defaults(func=run)


def config_from_args(args: argparse.Namespace) -> Any:
    """The configuration: the file (or the defaults) with the flags applied; CliError listing every problem."""
    return config_and_choice(args)[0]


def config_and_choice(args: argparse.Namespace) -> tuple[Any, Any]:
    """(configuration with the flags applied, :class:`~edge.runtime.config_choice.ConfigChoice`); CliError."""
    from edge.runtime.config import ConfigError
    from edge.runtime.config_choice import load_chosen

    try:
        cfg, choice = load_chosen(args.config)
        return cfg.with_overrides(source=args.source, calibration=args.calibration, bundle=args.bundle, sinks=args.sink,
                                  seconds=args.seconds, device=args.device,
                                  status_file=getattr(args, "status_file", None)), choice
    except ConfigError as exc:
        raise CliError(f"{exc}\nFix the configuration (`cavatar config validate FILE` checks it; `cavatar config show` "
                       "describes every key).") from None


def summary_line(s: dict[str, Any], previous: dict[str, Any] | None, dt_s: float) -> str:
    """One line: time, frames, fps, people, drops, ms/frame, published."""
    fr, pub, q = s["frames"], s["publish"], s["source"]["queue"]
    asm = s["source"]["assembly"]
    if previous is not None and dt_s > 0:
        fps = (fr["frames_in"] - previous["frames"]["frames_in"]) / dt_s
    else:  # the whole run
        fps = fr["frames_in"] / s["uptime_s"] if s.get("uptime_s") else 0.0
    lost = asm.get("crc_mismatch", 0) + asm.get("torn_dropped", 0) + asm.get("missed_frames", 0)
    frame_ms = s["stages_ms"]["frame"]
    ms = "-" if frame_ms["median_ms"] is None else f"{frame_ms['median_ms']:.1f} ms/frame (p99 {frame_ms['p99_ms']:.1f})"
    extra = ""
    if fr["frames_invalid"]:
        extra += f" invalid {fr['frames_invalid']}"
    if pub["queue_dropped"] or pub["sink_errors"]:
        extra += f" publish-dropped {pub['queue_dropped']} sink-errors {pub['sink_errors']}"
    board = s.get("board_health") or {}
    if board.get("connected") is False:  # say it, rather than a stale "people 1" beside 0.0 fps
        return (f"[{s['uptime_s']:6.1f} s] frames {fr['frames_in']:6d}  BOARD: {board.get('reason') or 'no frames'} "
                f"(unavailable; last frame {board.get('last_frame_age_s', 0):.0f} s ago)  published {pub['published']}"
                f"{extra}")
    return (f"[{s['uptime_s']:6.1f} s] frames {fr['frames_in']:6d} {fps:5.1f} fps  people {s['people']}  "
            f"dropped {q.get('dropped_slow_consumer', 0)} lost {lost}  {ms}  published {pub['published']} "
            f"({pub['heartbeats']} heartbeats){extra}")


def unconnected_sinks(sinks: list, timeout_s: float) -> list[str]:
    """The sinks (described) that connect to something and did not within ``timeout_s`` (waited for together)."""
    from edge.sinks import redact

    deadline = time.monotonic() + timeout_s
    missing = []
    for sink in sinks:
        wait = getattr(sink, "wait_connected", None)
        if wait is not None and not wait(max(0.0, deadline - time.monotonic())):
            missing.append(redact(sink.describe()))
    return missing


def never_connected(final: dict[str, Any]) -> list[str]:
    """Sinks of a finished run that connect to something (they count ``connects``) and never did."""
    return [url for url, st in (final.get("publish", {}).get("sinks") or {}).items()
            if isinstance(st, dict) and st.get("connects") == 0]


def serve(cfg: Any, *, quiet: bool = False, runtime: Any = None, require_sinks_s: float | None = None,
          config_note: str = "") -> tuple[int, dict[str, Any]]:
    """Run until the configured seconds, the end of the source, SIGTERM or Ctrl-C; (exit code, final status).

    Exit code 1 when the run failed or a sink never connected; ``require_sinks_s``: refuse to start (1) unless every
    connecting sink connects within that many seconds."""
    from edge.runtime import Runtime, SetupError
    from edge.sinks import redact

    rt = runtime or Runtime(cfg)
    try:
        rt.setup()
    except SetupError as exc:
        raise CliError(str(exc)) from None
    if require_sinks_s is not None:
        missing = unconnected_sinks(rt.sinks or [], require_sinks_s)
        if missing:
            final = rt.stop()
            print(f"cavatar run: not started: {', '.join(missing)} did not connect within {require_sinks_s:g} s "
                  "(--require-sinks); the WARNING above says why. Check the broker (`cavatar doctor`).",
                  file=sys.stderr)
            return 1, final
    handlers = {}

    def on_signal(signum: int, frame: Any) -> None:
        rt.request_stop()

    if threading.current_thread() is threading.main_thread():
        for sig in (signal.SIGTERM, signal.SIGINT):
            handlers[sig] = signal.signal(sig, on_signal)
    try:
        rt.start()
        sinks = ", ".join(redact(u) for u in cfg.sinks.urls)
        assert rt.bundle is not None  # loaded by setup()
        print(f"cavatar run: {redact(cfg.source.url)} → {sinks}; model {rt.bundle.version}; status "
              f"{cfg.status_path()}{'' if cfg.runtime.seconds <= 0 else f'; stops after {cfg.runtime.seconds:g} s'}"
              f"; Ctrl-C stops{f' ({config_note})' if config_note else ''}", file=sys.stderr, flush=True)
        period = cfg.runtime.summary_s if cfg.runtime.summary_s > 0 and not quiet else 0.5
        previous, t_prev = rt.snapshot(), time.monotonic()
        while not rt.wait(period):
            if quiet or cfg.runtime.summary_s <= 0:
                continue
            s, now = rt.snapshot(), time.monotonic()
            print(summary_line(s, previous, now - t_prev), file=sys.stderr, flush=True)
            previous, t_prev = s, now
    finally:
        final = rt.stop()
        for sig, old in handlers.items():
            signal.signal(sig, old)
    code = 1 if final.get("error") else 0
    silent = never_connected(final)
    if silent:  # a run whose records never reached the broker did not do its job, however cleanly it stopped
        code = 1
        print(f"cavatar run: WARNING: {', '.join(silent)} never connected during the run: no record reached it "
              "(exit 1). Check the broker's host and port (`cavatar doctor`).", file=sys.stderr)
    if not quiet:
        print(summary_line(final, None, 0.0), file=sys.stderr)
        w = final["work"]
        print(f"cavatar run: {final['state']} ({final.get('end_reason')}); {final['frames']['frames_in']} frames, "
              f"{final['publish']['published']} records published (seq up to {final['publish']['last_seq']}); "
              f"encoder runs {w['encoder_runs']}, head runs {w['head_runs']}, still reuses {w['still_reuses']}, "
              f"frames without inference {w['saved']['frames_without_inference']}"
              + (f"; error: {final['error']}" if final.get("error") else ""), file=sys.stderr)
    return code, final


def run(args: argparse.Namespace) -> int:
    cfg, choice = config_and_choice(args)
    code, _ = serve(cfg, quiet=args.quiet, require_sinks_s=args.require_sinks, config_note=choice.describe)
    return code

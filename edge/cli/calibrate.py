"""`cavatar calibrate`: the guided calibration of a carpet (live, from recordings, or on the virtual carpet).

    cavatar calibrate --source serial:///dev/ttyACM0 --mass 72            # guided, live
    cavatar calibrate --empty e.bin --walk w.bin --board b.bin --stance s.bin --holdout h.bin --mass 72
    cavatar calibrate --sim --seed 7 --intruder standing                  # the virtual carpet acts it out
    cavatar calibrate --work calib-work --redo board ...                  # redo one step alone

Writes the calibration file (``--out``), ``<out>.png`` and ``<out>.txt`` (the report).

Before anything is asked or recorded, the destination and the session folder are tested by
writing, and a live board is opened and must answer (calibration/preflight.py): a missing or
busy port, an unwritable --out or a closed stdin is one line and exit 2, never a traceback.

The command lives in edge, above calibration: it opens the sources (edge.sources) and passes
them in, so calibration never imports the runtime. ``--sim`` calibrates the carpet that
``sim://?seed=S&grid=G`` streams, through the source plug-in's sensor model.
"""

from __future__ import annotations

import argparse
from pathlib import Path

from edge.cli import CliError, command_name

STEP_FILES = ("empty", "walk", "board", "stance", "holdout")


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        command_name(__name__),
        help="calibrate a carpet: baseline, faults, gains, response curve; writes the calibration file and a report",
        description="Walks an installer through the calibration steps (self-test, empty capture, coverage walk, "
        "board equilibration, known-weight poses, validation), from a live board (--source), from recordings "
        "(--empty/--walk/--board/--stance/--holdout) or on the virtual carpet (--sim). The session is saved to "
        "--work after every step: running again resumes, --redo STEP redoes one step alone.",
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    src = p.add_mutually_exclusive_group()
    src.add_argument("--source", help="live board URL, e.g. serial:///dev/ttyACM0 (guided, with prompts)")
    src.add_argument("--sim", action="store_true", help="the virtual carpet acts out the session")
    for step in STEP_FILES:
        p.add_argument(f"--{step}", metavar="FILE", help=f"recording of the {step} step (.bin from `cavatar record`, or .npz)")
    p.add_argument("--mass", type=float, help="mass of the person doing the poses, kg")
    p.add_argument("--board-mass", type=float, default=3.0, help="mass of the 60×60 cm board, kg (default 3)")
    p.add_argument("--work", default="calibration-work", help="session folder (resumable; default ./calibration-work)")
    p.add_argument("--redo", metavar="STEP", help="redo one step alone: self_test, empty, walk, board, stance, holdout")
    p.add_argument("--out", default="calibration.npz", help="calibration file to write (default calibration.npz)")
    p.add_argument("--mask", help="(H, W) bool .npy of the sensels that exist (non-rectangular carpet)")
    p.add_argument("--shape-from-walk", action="store_true", help="mark regions never stepped on at the border as outside")
    p.add_argument("--crosstalk-r-norm", type=float, default=0.0, help="line-loading R·g_full of the readout (0 = off)")
    p.add_argument("--seed", type=int, default=7, help="--sim: carpet seed")
    p.add_argument("--grid", type=int, default=96, help="--sim: sensels per side (96, 48, 32)")
    p.add_argument("--intruder", choices=("standing", "walking", "present80"), help="--sim: someone on the carpet during the empty capture")
    p.add_argument("--no-map", action="store_true", help="do not draw the coverage map")
    p.set_defaults(func=run)


def open_frames(url: str):
    """The frame source calibration reads (calibration.capture.OpenFrames): a carpet source with room for a step."""
    from edge.sources import open_source

    return open_source(url, queue_frames=1024)


def _sim_sensor(seed: int, grid: int):
    """The sensor model of ``sim://?seed=&grid=``, from its source plug-in."""
    from edge.sources import SourceError, source_options, source_plugin

    url = f"sim://?seed={seed}&grid={grid}"
    try:
        plugin = source_plugin(url)
        if plugin is None:
            raise ValueError("sim:// is served by no source plug-in here")
        return plugin.calibration_sensor(source_options(url))
    except (ValueError, SourceError) as exc:
        raise CliError(f"--sim: {exc}") from None


def _provider(args):
    from calibration.providers import LiveProvider, RecordingProvider, SimProvider

    files = {s: getattr(args, s) for s in STEP_FILES if getattr(args, s)}
    if args.sim:
        from calibration.actor import Actor

        sensor = _sim_sensor(args.seed, args.grid)
        print(f"virtual carpet: {sensor!r}")
        if args.mass is None:
            args.mass = 72.0
        return SimProvider(Actor(sensor, mass_kg=args.mass, seed=args.seed), args.intruder, live_map=not args.no_map)
    if args.source:
        return LiveProvider(args.source, open_frames)
    if files:
        return RecordingProvider(files, open_frames=open_frames)
    return None


def preflight(args: argparse.Namespace, ask=input) -> None:
    """Destination, session folder, recordings, board — then the mass: CliError (one line) at the first problem."""
    from calibration.preflight import (
        PreflightError,
        ask_mass,
        check_board,
        check_destination,
        check_recordings,
        check_work_folder,
    )

    try:
        check_destination(Path(args.out))
        check_work_folder(Path(args.work))
        check_recordings({s: getattr(args, s) for s in STEP_FILES if getattr(args, s)})
        if args.source:
            check_board(args.source, open_frames)
            if args.mass is None:
                args.mass = ask_mass(ask)
    except PreflightError as exc:
        raise CliError(str(exc)) from None


def run(args: argparse.Namespace) -> int:
    from calibration.file import CalibrationError
    from calibration.report import write_report
    from calibration.session import STEPS, Options, Session, SessionError
    from calibration.terminal import render_map
    from edge.sources import LinkLost, SourceError

    preflight(args)
    provider = _provider(args)
    opts = Options(mass_kg=args.mass, board_mass_kg=args.board_mass, crosstalk_r_norm=args.crosstalk_r_norm,
                   shape_from_walk=args.shape_from_walk, mask_path=args.mask)
    session = Session(Path(args.work), opts)
    if provider is None and not session.done:
        raise CliError("give a source: --source URL (live), --sim, or recordings (--empty FILE --walk FILE …)")
    if args.redo and args.redo not in STEPS:
        raise CliError(f"--redo takes one of {', '.join(STEPS)}, not {args.redo!r}")
    try:
        if provider is not None:
            steps = STEPS if not isinstance(provider, _recording_type()) else tuple(
                s for s in STEPS if s == "self_test" and args.empty or getattr(args, s, None))
            session.run(provider, steps=steps, redo=args.redo)
        cal, val = session.finish(args.out)
    except (SessionError, CalibrationError, FileNotFoundError, ValueError, SourceError, LinkLost, OSError) as exc:
        raise CliError(f"{exc} (the session so far is kept in {args.work}; fix it and run again, or --redo STEP)") from None
    except EOFError:
        raise CliError(f"standard input closed while waiting for Enter: the guided session needs a terminal (the "
                       f"session so far is kept in {args.work}; run again in a terminal to resume)") from None
    results = session.all_results()
    out = Path(args.out)
    png, txt = out.with_suffix(".png"), out.with_suffix(".txt")
    drawn = write_report(cal, results, val, png, txt)
    report = png if drawn else "(no PNG: matplotlib is not installed; pip install 'cavatar-edge[viz]' to draw it)"
    w = results.get("walk")
    if w is not None and not args.no_map:
        print(render_map(w.arrays["coverage"] > 0, title="coverage map (x = masked)", faults=~cal.usable))
    print(val.summary())
    print(f"wrote {out} (sha256 {cal.sha256[:12]}), report {report} and {txt}")
    return 0 if val.ok else 1


def _recording_type():
    from calibration.providers import RecordingProvider

    return RecordingProvider

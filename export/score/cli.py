"""`cavatar score`: run the real runtime on the virtual carpet and score what it publishes against the truth.

    cavatar score --set quick                                   # seconds: one person, one scene
    cavatar score --set standard --out out/score/score          # the committed set (make score), minutes
    cavatar score --source 'sim://?people=2&seed=4' --seconds 30
    cavatar score --render bench/results/score.json --md docs/score/score.md --png docs/score/score.png

Writes PREFIX.json (every number, per scene, per number of people, per activity, and the count
timelines), PREFIX.md and PREFIX.png (true vs published people count over time); --json/--md/--png
put one of them elsewhere. The runtime's records, status files and the virtual carpets'
calibrations go to --work (calibrations are reused by a later score). A scene that cannot run
(the installer's calibration asks for a redo, people that do not fit on the carpet) is reported in
the results, not fatal; the exit code is 1 only when no scene could be scored.
"""

from __future__ import annotations

import argparse
import json
import shlex
import sys
from pathlib import Path
from typing import Any

DEFAULT_OUT = "out/score/score"
DEFAULT_WORK = "out/score/work"


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("score", help="score what the runtime publishes on the virtual carpet against the simulator's truth",
                       description=__doc__.split("\n\n", 1)[1], formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(p)
    p.set_defaults(func=run)


def add_arguments(p: argparse.ArgumentParser) -> None:
    what = p.add_mutually_exclusive_group()
    what.add_argument("--set", choices=("quick", "standard"), help="a fixed scene set (default: standard)")
    what.add_argument("--source", metavar="URL", help="one scene instead: sim://?people=P&seed=S (needs --seconds)")
    what.add_argument("--render", metavar="JSON", help="no run: write the Markdown and PNG of an earlier score's JSON")
    p.add_argument("--seconds", type=float, metavar="S", help="with --source: frames to score, in simulated seconds")
    p.add_argument("--out", default=DEFAULT_OUT, metavar="PREFIX", help=f"PREFIX.json, .md, .png (default {DEFAULT_OUT})")
    p.add_argument("--json", metavar="FILE", help="the JSON here instead of PREFIX.json")
    p.add_argument("--md", metavar="FILE", help="the Markdown here instead of PREFIX.md")
    p.add_argument("--png", metavar="FILE", help="the PNG here instead of PREFIX.png")
    p.add_argument("--work", default=DEFAULT_WORK, metavar="DIR", help=f"records, status, calibrations (default {DEFAULT_WORK})")
    p.add_argument("--match-m", type=float, default=0.5, metavar="M",
                   help="CLEAR MOT: a published and a true pelvis farther apart than M metres on the carpet never match (0.5)")
    p.add_argument("--calibration", default="installer", metavar="installer|truth|FILE",
                   help="installer (default): the runtime's own, the scripted session on the virtual carpet; truth: the one a "
                        "perfect procedure would make; or a calibration file")
    p.add_argument("--config", metavar="FILE", help="a runtime configuration (e.g. other [scene] settings); source, sinks, "
                                                    "status and seconds are the score's")


def _error(text: str) -> Exception:
    from cavatar_common.errors import CliError

    return CliError(text)


def _scenes(args: argparse.Namespace) -> tuple[str, tuple]:
    from export.score.capture import Scene
    from export.score.scenes import SETS

    if args.source is None:
        if args.seconds is not None:
            raise _error("--seconds goes with --source; a --set has its own lengths")
        name = args.set or "standard"
        return name, SETS[name]
    from edge.sources import source_options
    from sim import source as sim_scheme

    if not args.source.startswith("sim://"):
        raise _error(f"--source {args.source}: only the virtual carpet has a truth to score against; give "
                     f"{sim_scheme.FORM}")
    if args.seconds is None or not args.seconds > 0:
        raise _error("--source needs --seconds S (> 0): how much of the scene to score")
    try:
        o = source_options(args.source)
    except ValueError as exc:
        raise _error(str(exc)) from None
    fixed = {"world": "bodies", "grid": 96, "pitch_mm": 19.05, "rate": 14.0}
    odd = [f"{k}={o[k]}" for k, v in fixed.items() if o[k] != v]
    if odd:
        raise _error(f"--source: {', '.join(odd)} is not scored; the score runs the shipped 96×96 carpet at 14 Hz "
                     "(world=bodies); speed is always 0")
    if o["people"] < 1:
        raise _error("--source: people must be 1..3 (nobody on the carpet has nothing to score)")
    return "custom", (Scene(people=o["people"], seed=o["seed"], seconds=args.seconds, scene_s=o["scene_s"]),)


def _config(args: argparse.Namespace) -> Any:
    if not args.config:
        return None
    from edge.runtime.config import ConfigError, load_config

    try:
        return load_config(args.config)
    except ConfigError as exc:
        raise _error(f"{exc}\nFix the configuration (`cavatar config validate FILE` checks it).") from None


def _paths(args: argparse.Namespace) -> dict[str, Path]:
    return {k: Path(getattr(args, k) or f"{args.out}.{k}") for k in ("json", "md", "png")}


def write_outputs(result: dict[str, Any], paths: dict[str, Path], say=print) -> None:
    """JSON (unless it is the one being rendered), Markdown, PNG (skipped, said, without matplotlib)."""
    from export.score.markdown import markdown

    for p in paths.values():
        p.parent.mkdir(parents=True, exist_ok=True)
    if "json" in paths:
        paths["json"].write_text(json.dumps(result, indent=1) + "\n")
    png = paths["png"]
    paths["md"].write_text(markdown(result, png_name=_relative(png, paths["md"].parent)))
    try:
        from export.score.plot import timeline_png
    except ImportError:
        say("score: no PNG (matplotlib missing: pip install -e '.[viz]')")
        return
    try:
        timeline_png(result, png)
    except ImportError:
        say("score: no PNG (matplotlib missing: pip install -e '.[viz]')")
    except ValueError as exc:
        say(f"score: no PNG ({exc})")


def _write(result: dict[str, Any], paths: dict[str, Path]) -> None:
    try:
        write_outputs(result, paths)
    except OSError as exc:
        raise _error(f"cannot write {exc.filename or 'the results'}: {exc.strerror}; give --out (or --json/--md/--png) "
                     "in a writable place") from None


def _relative(target: Path, start: Path) -> str:
    import os

    return os.path.relpath(target.resolve(), start.resolve())


def _command(args: argparse.Namespace, set_name: str) -> str:
    """The command line that reproduces this score (recorded in the results)."""
    parts = ["cavatar", "score"]
    parts += ["--source", args.source, "--seconds", f"{args.seconds:g}"] if args.source else ["--set", set_name]
    if args.match_m != 0.5:
        parts += ["--match-m", f"{args.match_m:g}"]
    if args.calibration != "installer":
        parts += ["--calibration", args.calibration]
    if args.config:
        parts += ["--config", args.config]
    return " ".join(shlex.quote(p) for p in parts)


def run(args: argparse.Namespace) -> int:
    paths = _paths(args)
    if args.render:
        try:
            result = json.loads(Path(args.render).read_text())
        except (OSError, json.JSONDecodeError) as exc:
            raise _error(f"--render {args.render}: cannot read it ({exc})") from None
        if not isinstance(result, dict) or result.get("schema") != "cavatar.score/1":
            raise _error(f"--render {args.render}: not a cavatar.score/1 result (written by `cavatar score`)")
        del paths["json"]
        _write(result, paths)
        print(f"score: wrote {paths['md']} and {paths['png']}")
        return 0
    if not args.match_m > 0:
        raise _error(f"--match-m must be > 0 metres; got {args.match_m}")
    if args.calibration not in ("installer", "truth") and not Path(args.calibration).is_file():
        raise _error(f"--calibration {args.calibration}: no such file; give installer, truth or a calibration file")
    set_name, scenes = _scenes(args)
    config = _config(args)
    for folder in (Path(args.work), *(p.parent for p in paths.values())):
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise _error(f"cannot create {folder}: {exc.strerror}; give --work/--out in a writable place") from None
    from edge.runtime.errors import SetupError
    from export.score.session import score_scenes

    command = _command(args, set_name)
    try:
        result = score_scenes(scenes, Path(args.work), threshold_m=args.match_m, calibration=args.calibration,
                              config=config, set_name=set_name, command=command)
    except SetupError as exc:
        raise _error(str(exc)) from None
    _write(result, paths)
    o = result["overall"]
    if o is None:
        print(f"score: no scene could be scored; see {paths['json']}", file=sys.stderr)
        return 1
    print(f"score: {o['frames']} frames: count right {o['count_right_pct']} %, extra-track frames {o['extra_frames_pct']} %, "
          f"MOTA {o['mota_pct']} %, MPJPE {o['mpjpe_cm']} cm, PA-MPJPE {o['pa_mpjpe_cm']} cm, heading >90° "
          f"{o['heading_over_90_pct']} %, ms/frame {o['frame_ms_median']}; wrote {paths['json']}, {paths['md']}, {paths['png']}")
    return 0

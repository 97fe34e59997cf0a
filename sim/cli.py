"""`cavatar sim`: generate synthetic datasets and look at their frames."""

from __future__ import annotations

import argparse

from cavatar_common.errors import CliError


def _people(text: str) -> tuple[int, int]:
    lo, _, hi = text.partition("..")
    try:
        rng = (int(lo), int(hi or lo))
    except ValueError:
        raise argparse.ArgumentTypeError(f"people must be N or LO..HI within 1..3, got {text!r}") from None
    if not 1 <= rng[0] <= rng[1] <= 3:
        raise argparse.ArgumentTypeError(f"people must be within 1..3, got {text!r}")
    return rng


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("sim", help="the synthetic carpet: generate datasets, show frames",
                       description="The synthetic carpet: procedural motion of the paper's activities, contact "
                       "physics and a realistic sensor model, with exact ground truth.")
    s = p.add_subparsers(dest="sim_command", metavar="SUBCOMMAND")
    g = s.add_parser("generate", help="generate a sharded dataset with ground truth",
                     description="Generate a dataset: subjects split 80/10/10 by subject, every subject does every "
                     "activity alone, plus multi-person scenes when --people allows. Deterministic for a seed.")
    g.add_argument("--out", required=True, help="output folder (must not already hold a dataset)")
    g.add_argument("--subjects", type=int, default=12, help="number of subjects (default 12)")
    g.add_argument("--seconds-per-activity", type=float, default=10.0,
                   help="seconds of each activity, at least (default 10): one that needs longer at the person's own "
                   "tempo (a push-up: getting down, a repetition, getting up) gets it")
    g.add_argument("--people", type=_people, default=(1, 1), help="people per scene, N or LO..HI within 1..3 (default 1)")
    g.add_argument("--grid", type=int, default=96, choices=(96, 48, 32), help="sensels per side (default 96)")
    g.add_argument("--pitch-mm", type=float, default=None, help="sensel pitch; default keeps the 1.83 m carpet (19.05 mm at 96)")
    g.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    g.add_argument("--workers", type=int, default=2, help="processes (default 2)")
    g.add_argument("--activities", default=None, help="comma-separated subset of the activities (default: the paper's ten)")
    g.add_argument("--calibration", choices=("installer", "truth"), default=None,
                   help="also write each carpet's calibration: the guided procedure acted out on it (installer) or its "
                   "true parameters (truth), so training and evaluation can read counts → calibration → kPa")
    g.set_defaults(func=run_generate)
    sh = s.add_parser("show", help="draw one frame: raw counts, true pressure and the bodies",
                      description="Draw frame I of a dataset to a PNG: raw counts, true pressure, bodies from above and the side.")
    sh.add_argument("dataset", help="dataset folder")
    sh.add_argument("--frame", type=int, default=0, help="frame index over the whole dataset")
    sh.add_argument("--png", required=True, help="output PNG")
    sh.set_defaults(func=run_show)
    au = s.add_parser("audit", help="measure the simulator against the literature (fidelity report)",
                      description="Generate a few subjects of every activity and check balance, force, foot roll, region "
                      "loads and variety against published ranges; writes audit.json and audit.md.")
    au.add_argument("--out", default="docs/sim/audit", help="output folder (default docs/sim/audit)")
    au.add_argument("--subjects", type=int, default=3, help="subjects per activity (default 3)")
    au.add_argument("--seconds", type=float, default=8.0,
                    help="seconds per activity, at least (default 8: what `make model`'s main training set uses; "
                         "an activity that needs longer at the person's own tempo gets it, as in datasets)")
    au.add_argument("--seed", type=int, default=0, help="random seed (default 0)")
    au.set_defaults(func=run_audit)
    p.set_defaults(func=lambda args: (p.print_help(), 2)[1])


def run_generate(args: argparse.Namespace) -> int:
    from sim.dataset import DatasetError
    from sim.dataset.generate import PAPER_ACTIVITIES, generate

    pitch = args.pitch_mm if args.pitch_mm else 19.05 * 96 / args.grid
    acts = tuple(a.strip() for a in args.activities.split(",")) if args.activities else PAPER_ACTIVITIES
    if args.subjects < 1:
        raise CliError("--subjects must be at least 1")
    try:
        out = generate(args.out, subjects=args.subjects, seconds_per_activity=args.seconds_per_activity, people=args.people,
                       grid=args.grid, pitch_mm=pitch, seed=args.seed, activities=acts, workers=args.workers,
                       calibration=args.calibration)
    except (DatasetError, ValueError) as exc:
        raise CliError(str(exc)) from None
    from sim.dataset import Dataset

    ds = Dataset(out)
    print(f"wrote {len(ds)} frames in {len(ds.manifest['shards'])} shards to {out}")
    return 0


def run_audit(args: argparse.Namespace) -> int:
    import sys

    from sim.audit import run_audit as audit
    from sim.audit import write_report

    if args.subjects < 1 or args.seconds < 6:
        raise CliError("--subjects must be at least 1 and --seconds at least 6 (the floor activities need the time)")
    report = audit(subjects=args.subjects, seconds=args.seconds, seed=args.seed,
                   progress=lambda msg: print(msg, file=sys.stderr, flush=True))
    j, m = write_report(report, args.out)
    print(f"{report['summary']['in_range']} of {report['summary']['total']} checks in range; wrote {j} and {m}")
    return 0


def run_show(args: argparse.Namespace) -> int:
    from sim.dataset import Dataset, DatasetError
    from sim.show import draw_frame

    try:
        ds = Dataset(args.dataset)
        frame = ds.frame(args.frame)
    except (DatasetError, IndexError) as exc:
        raise CliError(str(exc)) from None
    draw_frame(frame, ds.manifest, args.png, title=f"{args.dataset} frame {args.frame}")
    print(f"wrote {args.png}")
    return 0

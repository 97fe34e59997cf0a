"""`cavatar render`: draw the bodies of one published record to a PNG.

    cavatar render RECORD.json --png out.png
    cavatar render bodies.jsonl --index -1 --png last.png --views front,side,top

RECORD is a JSON file holding one record of the stream format
(``{"schema":"cavatar.bodies/1", ..., "people":[{"transl_m":…,"pose_aa":…,"betas":…}]}``)
or a JSON-lines file of them (``--index`` picks the line, 0-based, negative from the end).
Needs matplotlib (the ``viz`` extra).
"""

from __future__ import annotations

import json
from pathlib import Path

import numpy as np

from edge.cli import CliError, command_name


def register(subparsers) -> None:
    p = subparsers.add_parser(command_name(__name__), help="draw the bodies of a published record to PNG",
                              description=__doc__.split("\n\n")[0])
    p.add_argument("record", type=Path, help="a .json record or a .jsonl file of records")
    p.add_argument("--png", type=Path, required=True, help="output PNG path")
    p.add_argument("--index", type=int, default=None, help="which record of a JSON-lines file (default 0; -1 is the last)")
    p.add_argument("--model", default="full", help="body model: 'full', 'lite' or a path to an SMPL-layout .npz/.pkl (default full)")
    p.add_argument("--views", default="front,side", help="comma-separated views among front, side, top (default front,side)")
    p.add_argument("--skeleton", action="store_true", help="draw the joints over the mesh")
    p.set_defaults(func=run)


def read_record(path: Path, index: int | None) -> dict:
    """One record from a .json file (one object) or a JSON-lines file (``index``)."""
    try:
        text = path.read_text()
    except OSError as exc:
        raise CliError(f"cannot read {path}: {exc.strerror or exc}") from None
    lines = [line for line in text.splitlines() if line.strip()]
    try:
        whole = json.loads(text) if text.strip() else None
    except json.JSONDecodeError:
        whole = None
    if isinstance(whole, dict) and index in (None, 0, -1):
        return whole
    if isinstance(whole, dict):
        raise CliError(f"{path} holds a single record; --index {index} is out of range")
    if not lines:
        raise CliError(f"{path} is empty")
    i = 0 if index is None else index
    if not -len(lines) <= i < len(lines):
        raise CliError(f"{path} has {len(lines)} record(s); --index {i} is out of range")
    try:
        record = json.loads(lines[i])
    except json.JSONDecodeError as exc:
        raise CliError(f"{path}: record {i} is not JSON: {exc}") from None
    if not isinstance(record, dict):
        raise CliError(f"{path}: record {i} is not a JSON object")
    return record


def people_arrays(record: dict, num_joints: int = 24):
    """(pose_aa (P,3J), betas (P,NB), transl_m (P,3), track ids) from a record; CliError if malformed."""
    people = record.get("people")
    if not isinstance(people, list):
        raise CliError("record has no 'people' list (is it a cavatar.bodies/1 record?)")
    if not people:
        raise CliError("record has no people (a heartbeat): nothing to draw")
    poses, betas, transls, ids = [], [], [], []
    for k, person in enumerate(people):
        try:
            pose = np.asarray(person["pose_aa"], dtype=np.float64)
            transl = np.asarray(person["transl_m"], dtype=np.float64)
            beta = np.asarray(person.get("betas", []), dtype=np.float64)
        except (KeyError, TypeError, ValueError) as exc:
            raise CliError(f"person {k}: missing or non-numeric field {exc}") from None
        if pose.shape != (3 * num_joints,):
            raise CliError(f"person {k}: pose_aa has {pose.size} values, expected {3 * num_joints}")
        if transl.shape != (3,):
            raise CliError(f"person {k}: transl_m has {transl.size} values, expected 3")
        if beta.ndim != 1:
            raise CliError(f"person {k}: betas must be a flat list")
        poses.append(pose)
        betas.append(beta)
        transls.append(transl)
        ids.append(person.get("track_id", k))
    width = max(len(b) for b in betas)
    padded = np.stack([np.pad(b, (0, width - len(b))) for b in betas]) if width else None
    return np.stack(poses), padded, np.stack(transls), ids


def run(args) -> int:
    from edge.body import BodyModel, BodyModelFileError

    views = tuple(v.strip() for v in args.views.split(",") if v.strip())
    try:
        from edge.body.render import VIEWS, render_png
    except ImportError as exc:  # matplotlib missing
        raise CliError(f"rendering needs matplotlib (pip install 'cavatar-edge[viz]'): {exc}") from None
    unknown = [v for v in views if v not in VIEWS]
    if unknown or not views:
        raise CliError(f"unknown view(s) {unknown}; choose from {', '.join(VIEWS)}")
    record = read_record(args.record, args.index)
    try:
        model = BodyModel.load(args.model)
    except (BodyModelFileError, ValueError) as exc:
        raise CliError(str(exc)) from None
    pose, betas, transl, ids = people_arrays(record, model.num_joints)
    try:
        out = model.forward(pose, betas, transl, vertices=True)
    except ValueError as exc:
        raise CliError(f"bad body parameters: {exc}") from None
    title = f"{record.get('device', '?')} seq {record.get('seq', '?')}: tracks {', '.join(map(str, ids))}"
    try:
        render_png(
            args.png, list(out["vertices"]), model.faces, views=views, title=title,
            joints=list(out["joints"]) if args.skeleton else None, parents=model.parents,
        )
    except OSError as exc:
        raise CliError(f"cannot write {args.png}: {exc.strerror or exc}; give --png a path in a folder you can write") from None
    print(args.png)
    return 0

"""`cavatar record`: write a board's raw byte stream to a file, for replay and bug reports."""

from __future__ import annotations

import argparse
import os
import time

from cavatar_common.atomic import atomic_path
from edge.cli import CliError, command_name


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser(
        command_name(__name__),
        help="record the raw byte stream of a source to a file",
        description="Record exactly the bytes the board sends (INFO first) until N whole frames have "
        "arrived. The file is written beside its final name and renamed when complete, so an "
        "interrupted recording never leaves a half-written file. Replay it with "
        "--source replay://FILE, summarise it with `cavatar inspect FILE`.",
    )
    p.add_argument("out", help="capture file to write (e.g. capture.bin)")
    p.add_argument("--source", required=True, help="source URL, e.g. serial:///dev/ttyACM0 or sim://?people=1")
    p.add_argument("--frames", type=int, default=140, help="whole frames to record (default 140 = 10 s at 14 Hz)")
    p.add_argument("--timeout", type=float, default=30.0, help="give up after this many seconds without enough frames")
    p.add_argument("--force", action="store_true", help="overwrite an existing file")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from edge.sources import SourceError, open_source

    if args.frames < 1:
        raise CliError("--frames must be at least 1")
    if os.path.exists(args.out) and not args.force:
        raise CliError(f"{args.out} exists; pass --force to overwrite it")
    got = 0
    try:
        with atomic_path(args.out) as part:  # renamed into place, fsynced, only once every frame is in
            try:
                fh = open(part, "wb")  # before the board is opened: an unwritable destination wastes no recording
            except OSError as exc:
                raise CliError(f"cannot write {args.out}: {exc.strerror or exc}; give a path in a folder you can write") from None
            with fh:
                try:
                    source = open_source(args.source, record_to=fh, queue_frames=1024)
                    source.start()
                except (SourceError, ValueError) as exc:
                    raise CliError(str(exc)) from None
                deadline = time.monotonic() + args.timeout
                try:
                    for _ in source.frames(timeout_s=max(0.1, args.timeout)):
                        got += 1
                        if got >= args.frames or time.monotonic() > deadline:
                            break
                finally:
                    source.stop()
            if got < args.frames:
                raise CliError(f"only {got} of {args.frames} frames arrived within {args.timeout} s; nothing written")
    except OSError as exc:
        if got < args.frames:
            raise  # not the file's: what the source raised while recording, as before
        # every frame was in, the file could not be made durable or renamed (disk full, folder gone): nothing written
        raise CliError(f"cannot write {args.out}: {exc.strerror or exc}") from None
    size = os.path.getsize(args.out)
    print(f"recorded {got} frames, {size} bytes from {args.source} to {args.out}")
    return 0

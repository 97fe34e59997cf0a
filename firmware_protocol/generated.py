"""Files generated from protocol.toml and committed (the C header, the test vectors).

``main`` is the command line both generators share: write the file, or with ``--check``
exit 1 when the committed copy differs from what the generator makes now.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Callable


def main(prog: str, description: str, default_path: Path, render: Callable[[], str], argv: list[str] | None = None,
         summary: Callable[[str], str] = lambda text: "") -> int:
    ap = argparse.ArgumentParser(prog=prog, description=description)
    ap.add_argument("--check", action="store_true", help="do not write; exit 1 if the committed file differs")
    ap.add_argument("--output", type=Path, default=default_path, help=f"file to write or check (default {default_path})")
    args = ap.parse_args(argv)
    text = render()
    extra = summary(text)
    if args.check:
        if not args.output.exists() or args.output.read_text() != text:
            print(f"{args.output} is stale: run `{prog}`", file=sys.stderr)
            return 1
        print(f"{args.output} is current{extra}")
        return 0
    args.output.parent.mkdir(parents=True, exist_ok=True)
    args.output.write_text(text)
    print(f"wrote {args.output}{extra}")
    return 0

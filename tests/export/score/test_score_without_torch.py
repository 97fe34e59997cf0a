"""`cavatar score` needs no torch: it runs the board's runtime and numpy metrics, so it works where `cavatar run` does."""

from __future__ import annotations

import subprocess
import sys
import textwrap


def test_score_imports_and_parses_without_torch():
    code = textwrap.dedent("""
        import importlib.abc, sys

        class NoTorch(importlib.abc.MetaPathFinder):
            def find_spec(self, name, path, target=None):
                if name == "torch" or name.startswith("torch."):
                    raise ImportError("torch is not installed here")

        sys.meta_path.insert(0, NoTorch())
        import export.score.capture, export.score.judge, export.score.session, export.score.readme
        from edge.cli import build_parser
        parser, _ = build_parser()
        args = parser.parse_args(["score", "--set", "quick"])
        assert args.func.__module__ == "export.score.cli"
        assert "torch" not in sys.modules
        print("ok")
    """)
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0 and proc.stdout.strip() == "ok", proc.stderr

"""`edge/` must import and run with no torch installed (the board never has it)."""

import subprocess
import sys
import textwrap

BLOCK_TORCH = textwrap.dedent(
    """
    import importlib.abc, sys

    class NoTorch(importlib.abc.MetaPathFinder):
        def find_spec(self, name, path=None, target=None):
            if name == "torch" or name.startswith("torch."):
                raise ModuleNotFoundError(f"No module named {name!r} (blocked: the board has no torch)")
            return None

    sys.meta_path.insert(0, NoTorch())
    for mod in [m for m in sys.modules if m == "torch" or m.startswith("torch.")]:
        del sys.modules[mod]
    """
)


def run_python(code: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", BLOCK_TORCH + textwrap.dedent(code)], capture_output=True, text=True, timeout=120)


def test_the_blocker_really_blocks_torch():
    proc = run_python("import torch")
    assert proc.returncode != 0 and "blocked: the board has no torch" in proc.stderr


def test_every_edge_module_imports_without_torch():
    proc = run_python(
        """
        import importlib, pkgutil, edge
        names = [m.name for m in pkgutil.walk_packages(edge.__path__, "edge.") if not m.name.endswith("__main__")]
        failed = {}
        for name in names:
            try:
                importlib.import_module(name)
            except ImportError as exc:
                failed[name] = str(exc)
        torch_failures = {k: v for k, v in failed.items() if "torch" in v}
        assert not torch_failures, torch_failures
        assert "torch" not in sys.modules
        print(len(names), "modules")
        """
    )
    assert proc.returncode == 0, proc.stderr
    assert int(proc.stdout.split()[0]) >= 10


def test_cli_help_works_without_torch():
    proc = run_python(
        """
        from edge.cli import main
        try:
            main(["--help"])
        except SystemExit as exc:
            assert exc.code == 0
        """
    )
    assert proc.returncode == 0, proc.stderr
    assert "stream" in proc.stdout

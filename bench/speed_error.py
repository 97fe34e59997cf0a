"""Speed against error (issue 8): every model variant's latency, throughput, peak memory and size beside its
MPJPE/PVE/translation error, and the measured ratios (onnxruntime vs PyTorch, feature cache vs re-encoding,
joints vs mesh, scene-adaptive vs always-infer, runtime vs the frame interval). The logic is
export/benchmark.py; `cavatar bench` is the same run. See bench/README.md.

    python bench/speed_error.py --data /work/data/many48 --split test --stride 8
    python bench/speed_error.py                      # speed only: errors "not evaluated"

Writes bench/results/speed_error.json, docs/bench/speed_error.md and docs/bench/pareto.png.
"""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")  # before numpy loads BLAS

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from export.benchmark import BenchmarkError, add_arguments, run_from_args, summary  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(ap)
    args = ap.parse_args(argv)
    try:
        result = run_from_args(args, prog="python bench/speed_error.py")
    except BenchmarkError as exc:
        print(f"speed_error: {exc}", file=sys.stderr)
        return 2
    print(summary(result))
    print(f"wrote {args.json}, {args.markdown}, {args.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

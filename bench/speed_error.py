"""Speed against error: every model variant's cost per frame beside its error, and the measured
ratios behind the runtime's design (issue 8). `cavatar bench` is the same run.

    python -m bench.speed_error --data /work/data/many48 --split test --stride 8
    python -m bench.speed_error                      # speed only: errors "not evaluated"

Writes bench/results/speed_error.json, docs/bench/speed_error.md and docs/bench/pareto.png. From Python:

    result = run_speed_error(SpeedErrorConfig(bundles=["edge/models/lean-96"], data=["/work/data/many48"]))
    write_outputs(result, "bench/results/speed_error.json", "docs/bench/speed_error.md", "docs/bench/pareto.png")

Each part in its own module: bench.speed_error_run (the run and its options), bench.variants (what is
timed), bench.model_speed (latency, memory, the model-side ratios), bench.accuracy (errors),
bench.simulated_day (scene-adaptive vs always-infer, the runtime against the frame interval),
bench.speed_error_report (JSON, Markdown, plot).

Variants: each bundle as it ships (the first is the reference) and its fp32 twin, exported from the bundle's
weights.npz; an untrained architecture (the paper's ResNet18 + 6-layer transformer, random weights) in fp32
and int8, for speed only ("not trained": never on the error axis). Per variant and onnxruntime thread count:

- latency of one published frame as the board does it: encoder (batch 1, the new frame) + head (batch 1,
  the (1,T,F) window of cached features); median and p99 over the timed frames, frames/s = 1000 / mean.
  Variants and thread counts are timed round-robin, a few frames each per round, so load hits all alike;
- peak memory: ru_maxrss of a fresh subprocess that loads the two graphs and runs N frames, minus that of a
  subprocess that only imports onnxruntime and numpy (MiB);
- size: bytes of the two ONNX files;
- error (trained variants): MPJPE, PVE, translation (cm) from export.tables.evaluate_bundle, the variant
  loaded as the board loads it, on the SAME unseen-subject tracks (one set per grid).

Ratios, each measured side by side: per round both sides run (alternating which goes first) and the
round's ratio is taken; reported as the median and interquartile range over rounds.
- PyTorch eager / onnxruntime, same fp32 weights, one thread, encoder + head per frame;
- re-encoding all T frames (encoder batch T + head) / the feature cache (encoder batch 1 + head);
- full mesh / joints only (BodyModel "full", batch 1);
- always-infer / scene-adaptive on a simulated day through the real FrameStages (model time and total
  per-frame time), with the inferences each did;
- the runtime's per-frame cost / the frame interval (bench/results/runtime_latency.json when present,
  else the adaptive day's FrameStages time: calibrate → record, decoding and publishing not included).
"""

from __future__ import annotations

import os

for _var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(_var, "1")  # before numpy loads BLAS

import argparse  # noqa: E402
import sys  # noqa: E402

from bench import BenchmarkError  # noqa: E402
from bench.speed_error_run import add_arguments, run_from_args, summary  # noqa: E402

PROG = "python -m bench.speed_error"


def main(argv: list[str] | None = None) -> int:
    argv = sys.argv[1:] if argv is None else argv
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    add_arguments(ap)
    args = ap.parse_args(argv)
    try:
        result = run_from_args(args, prog=PROG)
    except BenchmarkError as exc:
        print(f"speed_error: {exc}", file=sys.stderr)
        return 2
    print(summary(result))
    print(f"wrote {args.json}, {args.markdown}, {args.plot}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

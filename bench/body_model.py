"""Per-frame cost of the body model: numpy joints-only and full mesh at batch 1 and 40,
one BLAS thread, and the torch twin for comparison. Writes bench/results/body_model.json.

    OMP_NUM_THREADS=1 python bench/body_model.py
"""

from __future__ import annotations

import json
import os
import platform
import sys
import time
from pathlib import Path

for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
    os.environ.setdefault(var, "1")  # before numpy loads BLAS

import numpy as np  # noqa: E402

from edge.body import BodyModel  # noqa: E402

REPEATS = 7


def median_ms(fn, min_time_s=0.3) -> float:
    """Median over REPEATS rounds of the mean time of one call, in ms."""
    fn()
    n = 1
    while True:
        t = time.perf_counter()
        for _ in range(n):
            fn()
        if time.perf_counter() - t > min_time_s / REPEATS or n > 1_000_000:
            break
        n *= 2
    rounds = []
    for _ in range(REPEATS):
        t = time.perf_counter()
        for _ in range(n):
            fn()
        rounds.append((time.perf_counter() - t) / n * 1000)
    return float(np.median(rounds))


def main() -> int:
    rng = np.random.default_rng(0)
    results = []
    inputs = {b: (rng.normal(size=(b, 72)) * 0.5, rng.normal(size=(b, 10)), rng.normal(size=(b, 3))) for b in (1, 40)}
    for name in ("lite", "full"):
        model = BodyModel.load(name)
        for b, (pose, betas, transl) in inputs.items():
            for vertices in (False, True):
                if not vertices and name == "full":
                    continue  # joints-only does not depend on the mesh
                ms = median_ms(lambda: model.forward(pose, betas, transl, vertices=vertices))
                results.append({"impl": "numpy", "model": name, "vertices": model.num_vertices, "path": "mesh" if vertices else "joints",
                                "batch": b, "ms_per_call": round(ms, 4), "ms_per_frame": round(ms / b, 4)})
    try:
        import torch

        from export.body.torch_body import TorchBodyModel

        torch.set_num_threads(1)
        for name in ("lite", "full"):
            twin = TorchBodyModel.load(name, dtype=torch.float32)
            for b, (pose, betas, transl) in inputs.items():
                tp, tb, tt = (torch.tensor(x, dtype=torch.float32) for x in (pose, betas, transl))
                for vertices in (False, True):
                    with torch.no_grad():
                        ms = median_ms(lambda: twin(tp, tb, tt, vertices=vertices))
                    results.append({"impl": "torch-twin float32 no_grad", "model": name, "vertices": twin.v_template.shape[0],
                                    "path": "mesh" if vertices else "joints", "batch": b, "ms_per_call": round(ms, 4),
                                    "ms_per_frame": round(ms / b, 4)})
        torch_version = torch.__version__
    except ImportError:
        torch_version = None
    out = {
        "benchmark": "body_model",
        "command": "OMP_NUM_THREADS=1 python bench/body_model.py",
        "machine": {
            "platform": platform.platform(), "processor": platform.processor() or platform.machine(),
            "cpus": os.cpu_count(), "python": platform.python_version(), "numpy": np.__version__, "torch": torch_version,
            "blas_threads": os.environ.get("OPENBLAS_NUM_THREADS"),
            "load_average_1_5_15_at_end": [round(x, 2) for x in os.getloadavg()],
        },
        "method": f"median of {REPEATS} rounds, each the mean of enough calls to last ~{0.3 / REPEATS:.2f} s; "
                  "float32 vertex products, float64 chain",
        "results": results,
    }
    path = Path(__file__).resolve().parent / "results" / "body_model.json"
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps(out, indent=1) + "\n")
    for r in results:
        print(f"{r['impl']:28s} {r['model']:5s} {r['path']:6s} B={r['batch']:<3d} "
              f"{r['ms_per_call']:9.4f} ms/call {r['ms_per_frame']:8.4f} ms/frame")
    return 0


if __name__ == "__main__":
    sys.exit(main())

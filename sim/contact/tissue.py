"""Soft-tissue stiffness by region: the compliant layer under the body is not one material.

``regional_tissue(model)`` starts from the per-joint blend (``mesh.tissue_stiffness``) and
overrides regions found on the body model's template (canonical Y up, facing +Z), as
vertex weights that fade smoothly (the lite mesh has 3–5 cm edges):

- foot, along its length from the heel (``FOOT_ZONES``): a stiff heel pad (thin, dense
  fat under the calcaneus), a medial arch that barely loads and a lateral midfoot band
  that does, stiff metatarsal heads, softer toes;
- the ischial tuberosities (the sitting bones: ~39 mm of tissue under them, the rest of
  the buttock thick and soft), the sacrum and the scapulae (bony prominences that carry
  the supine body);
- everything else keeps its part's value;
- a soft layer over all that where the flesh is thick (``SOFT_LAYER_MM``: back, shoulders,
  shanks, a little on the buttocks; thinner over the bones; none on soles and palms): a
  bed of ``SOFT_KPA_PER_MM`` on the skin in parallel with the deep bed, which starts that
  many mm into the body (``Tissue``; docs/sim-contact.md).

Stiffness is kPa per mm of indentation of tissue and rug in series (Winkler layer); the
contact model interpolates its inverse (compliance) across a triangle, so a soft vertex
stays soft between stiff neighbours.
Values were fitted so that the audit's plantar, sitting and lying checks land in their
published ranges (see docs/sim-contact.md and ``cavatar sim audit``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sim.contact.mesh import TISSUE_KPA_PER_MM, tissue_stiffness

# Foot zones by fraction of the foot's length from the heel: (start, end, kPa/mm medial, kPa/mm lateral).
FOOT_ZONES = (
    (0.00, 0.24, 11.0, 11.0),  # heel pad
    (0.24, 0.68, 0.05, 0.3),   # midfoot: medial longitudinal arch, lateral band
    (0.68, 0.88, 8.0, 8.0),    # metatarsal heads
    (0.88, 1.01, 3.0, 3.0),    # toes
)
# Bony prominences: centre in the template relative to a joint (m), Gaussian radius (m), kPa/mm.
PROMINENCES = {
    "ischial_tuberosity": (("left_hip", (-0.055, -0.105, -0.08)), ("right_hip", (0.055, -0.105, -0.08)), 0.04, 4.0),
    "sacrum": (("pelvis", (0.0, 0.03, -0.11)), None, 0.045, 1.6),
    "scapula": (("spine3", (0.09, 0.03, -0.06)), ("spine3", (-0.09, 0.03, -0.06)), 0.05, 1.6),
}
# The soft layer: the skin side of the flesh gives far more than what lies deeper (it flattens
# under a sitting or lying body), then the deep bed (the stiffnesses above) takes over.
SOFT_KPA_PER_MM = 0.15
SOFT_LAYER_MM = {"pelvis": 8.0, "spine1": 30.0, "spine2": 30.0, "spine3": 30.0,
                 "left_knee": 25.0, "right_knee": 25.0, "left_collar": 30.0, "right_collar": 30.0,
                 "left_shoulder": 30.0, "right_shoulder": 30.0, "neck": 25.0, "head": 10.0}  # mm, skinning-weighted
PROMINENCE_LAYER_MM = {"ischial_tuberosity": 10.0, "sacrum": 8.0, "scapula": 20.0}  # thinner over bone
HAND_JOINTS = ("left_wrist", "right_wrist", "left_hand", "right_hand")
BUTTOCK_KPA_PER_MM = 0.5  # gluteal soft tissue away from the bones (was 0.2: the floor-sitting body sank 63 mm)


@dataclass(frozen=True)
class Tissue:
    """Per-vertex tissue for ``ContactModel.pressure_kpa``: a deep bed of ``kpa_per_mm`` that
    starts ``soft_layer_mm`` into the body, under a soft bed of ``soft_kpa_per_mm`` on the skin
    where that layer is thicker than 0 (two Winkler beds in parallel)."""

    kpa_per_mm: np.ndarray  # (V,)
    soft_layer_mm: np.ndarray  # (V,) 0: no soft layer
    soft_kpa_per_mm: float = SOFT_KPA_PER_MM


def _joints(model) -> np.ndarray:
    a = model.arrays
    return np.asarray(a.J_regressor) @ np.asarray(a.v_template)


def foot_fraction(model) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Per foot vertex: (mask (V,) any foot, fraction of the foot's length from the heel (V,),
    medial (V,) bool) on the template."""
    v = np.asarray(model.arrays.v_template, np.float64)
    j = _joints(model)
    names = list(model.joint_names)
    dominant = np.argmax(np.asarray(model.arrays.weights), axis=1)
    frac = np.full(len(v), np.nan)
    medial = np.zeros(len(v), bool)
    mask = np.zeros(len(v), bool)
    for side, sign in (("left", 1.0), ("right", -1.0)):
        ankle, ball = j[names.index(f"{side}_ankle")], j[names.index(f"{side}_foot")]
        on = np.isin(dominant, [names.index(f"{side}_ankle"), names.index(f"{side}_foot")])
        u = ball - ankle
        u[1] = 0.0
        u /= np.linalg.norm(u)
        proj = (v[on] - ball) @ u
        frac[on] = (proj - proj.min()) / (proj.max() - proj.min())
        # medial: toward the body's midline from the line heel → ball (x < ball's x on the left foot)
        side_dir = np.cross(np.array([0.0, 1.0, 0.0]), u)  # horizontal, perpendicular to the axis
        lateral = ((v[on] - ball) @ side_dir) * sign * np.sign(side_dir[0] or 1.0)
        medial[on] = lateral < 0.0
        mask |= on
    return mask, frac, medial


def regional_tissue(model, table: dict[str, float] | None = None) -> Tissue:
    """Per-vertex tissue with the regions of the module docstring: the deep bed's stiffness and
    the soft layer over it."""
    foot = foot_fraction(model)
    prominence = dict(_prominence_weights(model))
    return Tissue(_deep_stiffness(model, table, foot, prominence), _soft_layer(model, foot[0], prominence))


def _deep_stiffness(model, table: dict[str, float] | None, foot, prominence: dict[str, np.ndarray]) -> np.ndarray:
    """Per-vertex stiffness (V,) kPa/mm of the deep bed: the per-part blend, the foot zones (``foot``:
    ``foot_fraction``), the prominences (their weights) stiffening what lies under them."""
    base_table = dict(TISSUE_KPA_PER_MM if table is None else table)
    base_table["pelvis"] = BUTTOCK_KPA_PER_MM
    k = tissue_stiffness(model, base_table)
    mask, frac, medial = foot
    for lo, hi, k_med, k_lat in FOOT_ZONES:
        zone = mask & (frac >= lo) & (frac < hi)
        k[zone] = np.where(medial[zone], k_med, k_lat)
    for name, w in prominence.items():
        k = k + np.where(mask, 0.0, w) * np.maximum(PROMINENCES[name][3] - k, 0.0)  # prominences only ever stiffen
    return k


def _soft_layer(model, foot_mask: np.ndarray, prominence: dict[str, np.ndarray]) -> np.ndarray:
    """Per-vertex soft-layer thickness (V,) mm: ``SOFT_LAYER_MM`` blended by the skinning weights (the same
    blend as the stiffness), none on soles and palms, thinned to ``PROMINENCE_LAYER_MM`` over the bones."""
    layer = tissue_stiffness(model, {name: SOFT_LAYER_MM.get(name, 0.0) for name in model.joint_names})
    names = list(model.joint_names)
    dominant = np.argmax(np.asarray(model.arrays.weights), axis=1)
    hands = np.isin(dominant, [names.index(n) for n in HAND_JOINTS])
    layer = np.maximum(layer, 0.0)  # (skinning weights may dip a hair below 0)
    layer[foot_mask | hands] = 0.0
    for name, w in prominence.items():
        thin = PROMINENCE_LAYER_MM[name]
        layer = layer + w * (thin - layer) * (layer > thin)
    return layer


def _prominence_weights(model):
    """(name, (V,) weight) of each bony prominence: Gaussian around its centre(s)."""
    v = np.asarray(model.arrays.v_template, np.float64)
    names = list(model.joint_names)
    j = _joints(model)
    for name, (first, second, radius, _) in PROMINENCES.items():
        w = np.zeros(len(v))
        for spec in (first, second):
            if spec is None:
                continue
            centre = j[names.index(spec[0])] + np.asarray(spec[1])
            w = np.maximum(w, np.exp(-0.5 * np.sum((v - centre) ** 2, 1) / radius ** 2))
        yield name, w

"""Contact physics: a posed body mesh pressing into the carpet → true pressure per sensel.

Example::

    from edge.body import BodyModel
    from edge.body.poses import pose_aa
    from edge.body.render import grounded
    from sim.contact import ContactModel, regional_tissue, subject_mass_kg

    body = BodyModel.load("lite")
    mass = subject_mass_kg(body, betas)                 # once per subject (zero pose)
    tissue = regional_tissue(body)                      # once per body model: a Tissue (by region)
    carpet = ContactModel(96, 96, pitch_m=0.01905)      # 4.76 mm cells, rug σ 5 mm
    verts = body.forward(pose, betas, transl, vertices=True)["vertices"][0]
    res = carpet.pressure_kpa(verts, body.faces, mass, acc_z_m_s2=0.0, static=True,
                              tissue_kpa_per_mm=tissue)
    res.pressure_kpa     # (96, 96) float32 kPa      res.force_n, res.cop_m, res.contact_mask
    scene = carpet.scene([res, res_other_person])     # several people: fields add

Method (details, numbers and limitations in docs/sim-contact.md):

1. Lowest surface: the body's downward-facing triangles within a height band above its
   lowest point are rasterised on a fine lattice (cell ≈ 4.8 mm, a whole number per
   pitch) as a z-buffer of the lowest surface, with the per-vertex tissue stiffness
   interpolated alongside (``raster.lowest_surface``).
2. Compliant layer: body tissue and rug in series act as a Winkler foundation:
   p = k·d^n (k kPa/mm per body part from skinning weights, n = 1 by default), d the
   depth of the surface below an indentation plane.
3. Force and balance: the plane z = z_low + h + sx·(x − tx) + sy·(y − ty) is solved so
   that Σ p·A = m·(g + a_z) and, when a COP target t is set (``static=True``: t = the
   COM's ground projection; ``acc_xy_m_s2``: t = com_xy − com_z·a_xy/(g + a_z)), the
   moments about t vanish — three unknowns, Newton with line search on a convex
   potential (exact for force and COP). Tilting the plane is the small rigid rotation
   of the body into the foam that real balance produces. If the target lies outside the
   support (the tilt would exceed ``max_slope``), the tilt stays at that bound — the
   force is still exact and the COP as close to the target as the bound allows — and
   ``balanced`` is False with ``cop_error_m`` saying how far off it is. ``static=False`` without a_xy: uniform indentation
   only, the COP falls where the geometry puts it (dynamic frames).
   Pressure is non-negative by construction (depth clamped at 0).
4. Rug and sensels: the fine field is blurred by a Gaussian (σ = rug_sigma_mm) and
   averaged over each thread crossing (width crossing_frac·pitch) — one exact,
   separable linear map per axis, so 96/48/32 grids and any pitch work unchanged.
5. Off the carpet: force on cells beyond the carpet is lost (``force_off_carpet_n``);
   the solve itself uses the whole body.

Mass comes from the mesh volume (divergence theorem) of the subject's zero pose at
1010 kg/m³ (``subject_mass_kg``, ``body_mass_kg``, ``mesh_report``); the COM from the
posed mesh's volume centroid unless given. Whole tracks (``track.track_dynamics`` /
``track_contacts``, what the dataset generator uses) give it the COM of the segment mass
model (``segments.SegmentMassModel``, de Leva), which does not change with pose, and a
smoothed acceleration; ``tissue.regional_tissue`` sets stiffness by region.
"""

from sim.contact.mesh import (
    DENSITY_KG_M3,
    TISSUE_KPA_PER_MM,
    MeshReport,
    body_mass_kg,
    mesh_centroid_m,
    mesh_report,
    mesh_volume_m3,
    subject_mass_kg,
    tissue_stiffness,
)
from sim.contact.model import G_M_S2, ContactModel
from sim.contact.raster import LowestSurface, lowest_surface
from sim.contact.result import ContactResult, SceneResult
from sim.contact.sampling import sampling_kernel
from sim.contact.tissue import Tissue, regional_tissue

__all__ = [
    "ContactModel", "ContactResult", "SceneResult", "G_M_S2", "DENSITY_KG_M3", "TISSUE_KPA_PER_MM", "MeshReport",
    "body_mass_kg", "mesh_centroid_m", "mesh_report", "mesh_volume_m3", "subject_mass_kg", "tissue_stiffness", "regional_tissue", "Tissue",
    "lowest_surface", "LowestSurface", "sampling_kernel",
]

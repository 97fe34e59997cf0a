"""One person's whole track through the contact physics: posing, centre of mass, its
acceleration, and the pressure of every frame. The dataset generator and ``sim audit``
both call this, so the audit measures exactly what the training data holds.

    fw, dyn = track_dynamics(body, track)          # posed joints/vertices, mass, COM, acceleration
    results = track_contacts(carpet, body, tissue, track, fw, dyn)   # [ContactResult] per frame
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sim.contact.mesh import mesh_centroid_m, subject_mass_kg


@dataclass
class TrackDynamics:
    """mass_kg; com_m (T,3) centre of mass; acc_m_s2 (T,3) its acceleration."""

    mass_kg: float
    com_m: np.ndarray
    acc_m_s2: np.ndarray


def track_dynamics(body, track, fw=None) -> tuple[dict, TrackDynamics]:
    """Pose the track (joints and vertices) and derive its centre of mass and acceleration."""
    n = len(track)
    if fw is None:
        fw = body.forward(track.pose_aa, np.broadcast_to(track.betas, (n, len(track.betas))), track.transl_m, vertices=True)
    dt = 1.0 / track.rate_hz
    mass = subject_mass_kg(body, track.betas)
    com = np.stack([mesh_centroid_m(v, body.faces) for v in fw["vertices"]])
    acc = np.gradient(np.gradient(com, dt, axis=0), dt, axis=0)
    return fw, TrackDynamics(mass, com, acc)


def track_contacts(carpet, body, tissue, track, fw, dyn: TrackDynamics, keep_fine: bool = False, frames=None) -> list:
    """ContactResult of each frame (or of ``frames``): force m·(g + a_z), the COP target
    com_xy − com_z·a_xy/(g + a_z)."""
    out = []
    for t in range(len(track)) if frames is None else frames:
        out.append(carpet.pressure_kpa(fw["vertices"][t], body.faces, dyn.mass_kg, acc_z_m_s2=float(dyn.acc_m_s2[t, 2]),
                                       com_m=dyn.com_m[t], acc_xy_m_s2=dyn.acc_m_s2[t, :2], tissue_kpa_per_mm=tissue,
                                       keep_fine=keep_fine))
    return out

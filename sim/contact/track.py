"""One person's whole track through the contact physics: posing, centre of mass, its
acceleration, and the pressure of every frame. The centre of mass comes from the segment
mass model (``sim.contact.segments``), which does not change with pose; its acceleration
is the second derivative of a local cubic fit (Savitzky–Golay, 0.5 s). The dataset generator and ``sim audit``
both call this, so the audit measures exactly what the training data holds.

    fw, dyn = track_dynamics(body, track)          # posed joints/vertices, mass, COM, acceleration
    results = track_contacts(carpet, body, tissue, track, fw, dyn)   # [ContactResult] per frame
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import savgol_filter

from sim.contact.mesh import subject_mass_kg
from sim.contact.segments import SegmentMassModel

ACC_WINDOW = 7  # frames (0.5 s at 14 Hz) of the smoothed second derivative


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
    com = SegmentMassModel(body, track.betas).com_m(track.pose_aa, track.transl_m)
    if n >= ACC_WINDOW:  # a local cubic over ACC_WINDOW frames: finite differences amplify the motion's jitter
        acc = savgol_filter(com, ACC_WINDOW, 3, deriv=2, delta=dt, axis=0, mode="interp")
    else:
        acc = np.gradient(np.gradient(com, dt, axis=0), dt, axis=0) if n >= 2 else np.zeros_like(com)
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

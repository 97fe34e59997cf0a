"""Balance in the motion: the pelvis moves so that the centre of mass stays over the feet.

Real people keep their centre of pressure (the zero-moment point of the body's motion)
inside the support: they move the hips back when they bend and shift their weight onto
the stance foot before the other one leaves the floor. Here a support point p(t) is
chosen from the contact schedule (the standing COP, ``FOOT_COP_FRAC`` of the foot's
length from the heel, of each loaded foot; ``TOES_COP_FRAC`` on a raised heel; the
mean of both feet in double support) and the centre of mass is given the trajectory
whose zero-moment point is exactly p (linear inverted pendulum of the subject's
standing COM height z):

    x − (z/g)·ẍ = p   →   x = p smoothed by the two-sided kernel e^(−|t|·√(g/z))

solved as one tridiagonal system over the sequence. The COM therefore starts moving
toward the stance foot before the swing foot lifts (an anticipatory weight shift), and
its ZMP, where the contact physics puts the COP, never leaves the support.
``Rig.ground`` shifts the pelvis (feet stay locked, the legs follow by IK) until the
segment-model COM follows x.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_banded

FOOT_COP_FRAC = 0.43  # standing COP along the foot from the heel (40–45 % in plantar-pressure studies)
TOES_COP_FRAC = 0.78  # on a raised heel the COP sits under the metatarsal heads
HEEL_COP_FRAC = 0.12  # toes up (heel strike): under the heel
G_M_S2 = 9.81


def foot_geometry(rest_vertices: np.ndarray, foot_vertices: np.ndarray, ankle: np.ndarray, ball: np.ndarray):
    """Canonical (Y-up) unit axis ankle → ball in the ground plane and the heel and toe ends
    of the foot's vertices along it, measured from the ball (heel < 0 < toe)."""
    u = np.asarray(ball, float) - np.asarray(ankle, float)
    u[1] = 0.0
    u /= np.linalg.norm(u)
    proj = (rest_vertices[foot_vertices] - ball) @ u
    return u, float(proj.min()), float(proj.max())


def support_point(ball_w: np.ndarray, foot_rot: np.ndarray, geometry, heel_rad: np.ndarray) -> np.ndarray:
    """(T,2) ground point of a foot's COP: ball_w (T,3) world ball joint, foot_rot (T,3,3) the
    ankle's world orientation, heel_rad (T,) heel raise (> 10°: on the toes, < −3°: on the heel)."""
    u, heel, toe = geometry
    frac = np.where(heel_rad > np.radians(10.0), TOES_COP_FRAC, np.where(heel_rad < np.radians(-3.0), HEEL_COP_FRAC, FOOT_COP_FRAC))
    off = heel + frac * (toe - heel)
    return (ball_w + (foot_rot @ u) * off[:, None])[:, :2]


def zmp_com(p: np.ndarray, rate_hz: float, height_m: float) -> np.ndarray:
    """The COM path (T,2) whose zero-moment point is p (T,2): x − (z/g)·ẍ = p with finite
    differences at rate_hz and zero velocity at both ends."""
    n = len(p)
    if n < 3:
        return np.asarray(p, float).copy()
    a = height_m / G_M_S2 * rate_hz ** 2
    ab = np.zeros((3, n))
    ab[0, 1:] = -a
    ab[1, :] = 1.0 + 2.0 * a
    ab[1, [0, -1]] = 1.0 + a
    ab[2, :-1] = -a
    return solve_banded((1, 1), ab, np.asarray(p, float))

"""Balance in the motion: the pelvis moves so that the centre of mass stays over the feet.

Real people keep their centre of pressure (the zero-moment point of the body's motion)
inside the support: they move the hips back when they bend and shift their weight onto
the stance foot before the other one leaves the floor. Here a support point p(t) is
chosen from the contact schedule (each loaded foot's COP rolls with its heel angle:
under the heel while the toes are up at heel strike, ``FOOT_COP_FRAC`` of the foot's
length from the heel when flat, under the metatarsal heads once the heel is off; in
double support the weight passes from the foot that carried it to the foot that will,
see ``left_weight``) and the centre of mass is given the trajectory
whose zero-moment point is exactly p (linear inverted pendulum of the subject's
standing COM height z):

    x − (z/g)·ẍ = p   →   x = p smoothed by the two-sided kernel e^(−|t|·√(g/z))

solved as one tridiagonal system over the sequence. The COM therefore starts moving
toward the stance foot before the swing foot lifts (an anticipatory weight shift), and
its ZMP, where the contact physics puts the COP, never leaves the support.
``sim.motion.posture.balance_com`` shifts the pelvis (feet stay locked, the legs follow by IK) until the
segment-model COM follows x.
"""

from __future__ import annotations

import numpy as np
from scipy.linalg import solve_banded

FOOT_COP_FRAC = 0.43  # standing COP along the foot from the heel (40–45 % in plantar-pressure studies)
TOES_COP_FRAC = 0.78  # on a raised heel the COP sits under the metatarsal heads
HEEL_COP_FRAC = 0.12  # toes up (heel strike): under the heel
G_M_S2 = 9.81
# The COP along a loaded foot against its heel raise (degrees; < 0: toes up). Rolling about the
# heel, the ball leaves the floor (by more than the ~5 mm the sole sinks in) at ~3° of toes-up;
# rolling about the ball, the heel does at ~3° of heel raise: the COP runs through the midfoot
# within a few degrees of flat, as it does in a real stance (heel → forefoot, little midfoot).
ROLL_DEG = (-10.0, -3.0, -1.0, 0.0, 1.0, 2.0, 4.0, 10.0)
ROLL_FRAC = (HEEL_COP_FRAC, 0.15, 0.30, FOOT_COP_FRAC, 0.52, 0.62, 0.72, TOES_COP_FRAC)
WEIGHT_RAMP_S = 0.3  # longest time over which weight moves onto (or off) one foot in double support


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
    ankle's world orientation, heel_rad (T,) heel raise (the COP rolls with it: ``ROLL_DEG``)."""
    u, heel, toe = geometry
    frac = np.interp(np.degrees(heel_rad), ROLL_DEG, ROLL_FRAC)
    off = heel + frac * (toe - heel)
    return (ball_w + (foot_rot @ u) * off[:, None])[:, :2]


def zmp_com(p: np.ndarray, rate_hz: float, height_m) -> np.ndarray:
    """The COM path (T,2) whose zero-moment point is p (T,2): x − (z/g)·ẍ = p with finite
    differences at rate_hz and zero velocity at both ends. height_m: z, a scalar or (T,) (where
    the COM moves up and down: its height over 1 + z̈/g, as the ZMP com − z·ẍ/(g + z̈) has it)."""
    n = len(p)
    if n < 3:
        return np.asarray(p, float).copy()
    a = np.broadcast_to(np.asarray(height_m, float) / G_M_S2 * rate_hz ** 2, (n,))
    ab = np.zeros((3, n))  # banded: ab[1 + i − j, j] = A[i, j]
    ab[0, 1:] = -a[:-1]
    ab[1, :] = 1.0 + 2.0 * a
    ab[1, [0, -1]] = 1.0 + a[[0, -1]]
    ab[2, :-1] = -a[1:]
    return solve_banded((1, 1), ab, np.asarray(p, float))


def left_weight(left: np.ndarray, right: np.ndarray, rate_hz: float, ramp_s: float = WEIGHT_RAMP_S) -> np.ndarray:
    """(T,) share of the support point on the left foot from the feet's contact (T,) bools:
    1 on the left foot alone, 0 on the right alone; in double support the weight passes
    from the foot that stood alone before to the one that stands alone after (linearly,
    within ramp_s of either end; both feet equally in between). A double support with no
    single stance on one side (sequence ends, sitting down) keeps the even share there."""
    left, right = np.asarray(left, bool), np.asarray(right, bool)
    n = len(left)
    w = np.where(left & ~right, 1.0, np.where(right & ~left, 0.0, 0.5))
    both = left & right
    d = np.diff(np.r_[0, both.astype(np.int8), 0])
    ramp = max(1, int(round(ramp_s * rate_hz)))
    for s, e in zip(np.flatnonzero(d == 1), np.flatnonzero(d == -1)):
        before = w[s - 1] if s > 0 and left[s - 1] != right[s - 1] else 0.5
        after = w[e] if e < n and left[e] != right[e] else 0.5
        k = e - s
        if k <= 2 * ramp:  # a short double support: straight from one foot to the other
            w[s:e] = before + (after - before) * (np.arange(k) + 1.0) / (k + 1.0)
        else:
            i = np.arange(ramp) + 1.0
            w[s:s + ramp] = before + (0.5 - before) * i / (ramp + 1.0)
            w[e - ramp:e] = 0.5 + (after - 0.5) * i / (ramp + 1.0)
    return w

"""Force and balance: the indentation plane (step 3 of the package docstring).

The plane z = zmin + h + sx·(x − tx) + sy·(y − ty) presses into the lowest surface; a
cell at depth d = max(plane − z, 0) carries K·d^n newtons (K from the cell's stiffness
and area). ``solve_plane`` finds h (and the slopes when a COP target t is set) so that
Σ K·d^n = target force and the moments about t vanish: Newton with backtracking on the
convex potential Σ K·d^(n+1)/(n+1) − F·h, the tilt bounded by ``max_slope``.
"""

from __future__ import annotations

import numpy as np

from sim.contact.raster import LowestSurface


def solve_height(z, kk, target_f, exponent):
    """The uniform indentation alone (no tilt): F(h) = Σ K·max(h − z, 0)^n = target.

    z (N,) cell heights above the lowest point (m); kk (N,) K per cell (N/m^n)."""
    n = exponent
    order = np.argsort(z)
    zs, ks = z[order], kk[order]
    if n == 1.0:  # piecewise linear: exact from cumulative sums at the breakpoints
        ck, ckz = np.cumsum(ks), np.cumsum(ks * zs)
        f_at = ck * zs - ckz  # force with h at each breakpoint (cells before it in contact)
        m = int(np.searchsorted(f_at, target_f))  # cells 0..m-1 in contact
        m = max(1, min(m, zs.size))
        return float((target_f + ckz[m - 1]) / ck[m - 1])
    lo, hi = float(zs[0]), float(zs[0]) + 0.01
    while (ks * np.maximum(hi - zs, 0) ** n).sum() < target_f:
        lo, hi = hi, hi + 2 * (hi - zs[0])
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if (ks * np.maximum(mid - zs, 0) ** n).sum() < target_f:
            lo = mid
        else:
            hi = mid
        if hi - lo < 1e-9:
            break
    return 0.5 * (lo + hi)


def _plane_state(theta, dx, dy, z, kk, n, target_f):
    """Depth d (N,) and force q (N,) of each cell under the plane theta = (h, sx, sy), and
    the convex potential there."""
    d = np.maximum(theta[0] + theta[1] * dx + theta[2] * dy - z, 0.0)
    q = kk * (d ** n if n != 1.0 else d)
    phi = float((q @ d) / (n + 1) - target_f * theta[0])
    return d, q, phi


def _balance(theta, z, kk, dx, dy, target_f, n, max_slope):
    """Newton on (h, sx, sy) from theta (3,) with the moments about the target: dx, dy (N,)
    are the cells' offsets from it. Returns (theta, balanced, iterations)."""
    u = np.stack([np.ones_like(dx), dx, dy])  # (3, N)
    d, q, phi = _plane_state(theta, dx, dy, z, kk, n, target_f)
    free = np.ones(3, bool)  # the slopes leave the set when they reach ±max_slope
    balanced = False
    tol = 1e-5 * target_f  # force within 1e-5, moments within 10 µm × force
    its = 0
    for its in range(1, 120):
        grad = u @ q - np.array([target_f, 0.0, 0.0])
        # a slope held at its bound is released when the potential wants it back inside
        for k in (1, 2):
            if not free[k] and grad[k] * np.sign(theta[k]) > 0:
                free[k] = True
        if (np.abs(grad[free]) < tol).all():
            balanced = bool(free.all())
            break
        w = kk * n * (d ** (n - 1) if n != 1.0 else (d > 0))
        hess = (u * w) @ u.T + np.diag([1e-9, 1e-9, 1e-9]) * max(w.sum(), 1.0)
        step = np.zeros(3)
        step[free] = -np.linalg.solve(hess[np.ix_(free, free)], grad[free])
        big = np.abs(step[1:]).max()
        if big > 0.05:  # trust region on the tilt: new support enters gradually
            step *= 0.05 / big
        alpha = 1.0
        for _ in range(30):  # backtracking on the convex potential
            cand = theta + alpha * step
            cs = _plane_state(cand, dx, dy, z, kk, n, target_f)
            if cs[2] <= phi + 1e-4 * alpha * float(grad @ step):
                break
            alpha *= 0.5
        for k in (1, 2):  # the tilt is bounded: beyond it the COM is outside the support
            if abs(cand[k]) > max_slope:
                cand[k] = np.sign(cand[k]) * max_slope
                free[k] = False
        theta = cand
        d, q, phi = _plane_state(theta, dx, dy, z, kk, n, target_f)
    if not free.all() or not balanced:
        # Closest to balance within the tilt bound: force exact, the COP as near as it gets.
        theta[0] = solve_height(z - theta[1] * dx - theta[2] * dy, kk, target_f, n)
        balanced = False
    return theta, balanced, its


def solve_plane(surf: LowestSurface, zmin: float, z_max: float, target_f: float, target_cop, exponent: float,
                cell_m: float, max_slope: float, soft_kpa_per_mm: float = 0.0) -> dict:
    """Indentation plane z = zmin + h + sx·(x−tx) + sy·(y−ty) over the surface below z_max:
    solve h (and the slopes when a COP target is set) so that Σ p·A = target_f and the
    moments about the target vanish.

    surf.attr holds each cell's compliance (mm/kPa) of the deep bed, or (compliance, soft
    layer mm): two beds in parallel, a soft one (soft_kpa_per_mm) on the surface and the deep
    one that many mm below it (``tissue.Tissue``). Returns h, sx, sy, ref (the target, or
    the cells' mean centre), balanced, iterations and cells = (jj, ii, z, kk, dx, dy), a cell
    listed once per bed it has."""
    xs, ys = surf.centres()
    jj, ii = np.nonzero(surf.z_m < z_max)  # surface above the band is checked after the solve
    z = surf.z_m[jj, ii] - zmin
    n = exponent
    # force per cell in N for d in metres: K·d^n, K = k[kPa/mm]·1e3·(1e3)^n·A
    per_kpa_per_mm = 1e3 * (1e3 ** n) * cell_m ** 2
    attr = surf.attr[jj, ii]
    if attr.ndim == 1:
        kk = per_kpa_per_mm / np.maximum(attr, 1e-12)
    else:
        kk = per_kpa_per_mm / np.maximum(attr[:, 0], 1e-12)
        layer_m = attr[:, 1] * 1e-3
        soft = layer_m > 0.0
        jj, ii = np.r_[jj, jj[soft]], np.r_[ii, ii[soft]]
        z = np.r_[z + layer_m, z[soft]]  # the deep bed starts layer_m into the body
        kk = np.r_[kk, np.full(int(soft.sum()), per_kpa_per_mm * soft_kpa_per_mm)]
    ref = target_cop if target_cop is not None else np.array([xs.mean(), ys.mean()])
    dx, dy = xs[ii] - ref[0], ys[jj] - ref[1]
    h = solve_height(z, kk, target_f, n)
    theta = np.array([h, 0.0, 0.0])
    balanced, its = True, 0
    if target_cop is not None:
        theta, balanced, its = _balance(theta, z, kk, dx, dy, target_f, n, max_slope)
    return {"h": float(theta[0]), "sx": float(theta[1]), "sy": float(theta[2]), "ref": np.asarray(ref, float),
            "balanced": balanced, "iterations": its, "cells": (jj, ii, z, kk, dx, dy)}

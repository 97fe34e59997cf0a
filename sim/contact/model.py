"""ContactModel: posed body mesh → true pressure per sensel (see the package docstring)."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.special import ndtr

from sim.contact.mesh import mesh_centroid_m
from sim.contact.raster import LowestSurface, lowest_surface

G_M_S2 = 9.81
_SQRT_2PI = math.sqrt(2.0 * math.pi)


def _ramp2(t, sigma):
    """Second antiderivative of the unit Gaussian of width sigma (a ramp when sigma = 0)."""
    if sigma <= 0:
        return np.maximum(t, 0.0)
    u = t / sigma
    return t * ndtr(u) + sigma * np.exp(-0.5 * u * u) / _SQRT_2PI


def sampling_kernel(n_sensels: int, pitch_m: float, cell_m: float, pad: int, sigma_m: float, width_m: float) -> np.ndarray:
    """(n_sensels, n_cells) weights: mean over a crossing window of width ``width_m``
    centred on each sensel of the fine pressure (cells uniform) blurred by a Gaussian
    of ``sigma_m``. Column k is lattice cell k − pad. Exact (closed-form double integral)."""
    centres = (np.arange(n_sensels) + 0.5) * pitch_m
    a = (centres - width_m / 2)[:, None]
    b = (centres + width_m / 2)[:, None]
    lo = ((np.arange(int(round(n_sensels * pitch_m / cell_m)) + 2 * pad) - pad) * cell_m)[None, :]
    hi = lo + cell_m
    w = _ramp2(b - lo, sigma_m) - _ramp2(b - hi, sigma_m) - _ramp2(a - lo, sigma_m) + _ramp2(a - hi, sigma_m)
    w /= width_m  # mean over the window; a cell's pressure acts over its whole width
    w[w < 1e-9 * w.max()] = 0.0
    return w


@dataclass
class ContactResult:
    """One person's contact with the carpet (one frame)."""

    pressure_kpa: np.ndarray  # (H, W) float32: true pressure sampled at the sensels
    contact_mask: np.ndarray  # (H, W) bool: pressure_kpa > the model's contact threshold
    force_n: float  # vertical force landing on the carpet (fine grid)
    force_total_n: float  # vertical force the body exerts in all (on + off the carpet)
    target_force_n: float  # m·(g + a_z), what force_total_n was solved to
    force_off_carpet_n: float  # lost beyond the carpet's edges
    cop_m: np.ndarray  # (2,) centre of pressure of the on-carpet force (NaN if none)
    cop_total_m: np.ndarray  # (2,) centre of pressure of the whole force (NaN if none)
    target_cop_m: np.ndarray | None  # (2,) where the COP was made to be (None: free)
    com_m: np.ndarray  # (3,) centre of mass used
    mass_kg: float
    balanced: bool  # COP reached the target (or no target asked); False: see cop_error_m
    cop_error_m: float  # |cop_total − target_cop| (0 when no target)
    airborne: bool  # lowest point above the floor by more than max_gap, or target ≤ 0
    indentation_mm: float  # deepest penetration into the compliant layer
    slope: np.ndarray  # (2,) tilt of the indentation plane (dz/dx, dz/dy)
    contact_area_m2: float  # fine-grid contact area (whole body, also off the carpet)
    sensel_force_n: float  # Σ pressure_kpa·pitch²: what perfect sensels would sum to
    iterations: int
    fine_pressure_kpa: np.ndarray | None = None  # (ny, nx) with keep_fine=True
    fine_origin: tuple[int, int] | None = None  # lattice index (j0, i0) of fine[0, 0]
    fine_cell_m: float | None = None
    info: dict = field(default_factory=dict)

    @property
    def off_carpet_fraction(self) -> float:
        return self.force_off_carpet_n / self.force_total_n if self.force_total_n > 0 else 0.0


@dataclass
class SceneResult:
    pressure_kpa: np.ndarray  # (H, W) float32, the sum of everyone's field
    person_index: np.ndarray  # (H, W) int8: whose pressure dominates a contact sensel, −1 none
    people: list  # the ContactResult of each person


class ContactModel:
    """Posed body mesh pressing into a compliant carpet → true pressure per sensel.

    rows, cols, pitch_m: the carpet. cell_mm: fine lattice (adjusted so that a whole
    number of cells fits a pitch). rug_sigma_mm: Gaussian spread by the rug.
    crossing_frac: effective width of a thread crossing as a fraction of the pitch
    (1.0: the sensel averages its whole square, Σ P·pitch² = force exactly).
    rug_kpa_per_mm: rug stiffness, in series with the body's tissue stiffness.
    exponent: pressure ∝ depth^exponent. band_mm: height band above the lowest point
    that is rasterised first (grown automatically, up to max_band_mm, when the plane
    reaches higher surface or a static balance needs support higher up).
    contact_kpa: threshold of the sensel contact mask. max_gap_mm: a body whose lowest
    point is higher above the floor than this exerts no force (airborne).
    max_slope: steepest tilt of the indentation plane before a static balance is
    declared impossible (COM outside the support).
    """

    def __init__(
        self,
        rows: int = 96,
        cols: int = 96,
        pitch_m: float = 0.01905,
        cell_mm: float = 4.8,
        rug_sigma_mm: float = 5.0,
        crossing_frac: float = 0.5,
        rug_kpa_per_mm: float = 30.0,
        exponent: float = 1.0,
        band_mm: float = 70.0,
        max_band_mm: float = 150.0,
        contact_kpa: float = 0.5,
        max_gap_mm: float = 30.0,
        max_slope: float = 0.25,
        g_m_s2: float = G_M_S2,
        default_tissue_kpa_per_mm: float = 2.0,
    ):
        if rows < 1 or cols < 1 or pitch_m <= 0 or cell_mm <= 0:
            raise ValueError("rows, cols, pitch_m and cell_mm must be positive")
        if not 0 < crossing_frac <= 1:
            raise ValueError(f"crossing_frac must be in (0, 1], got {crossing_frac}")
        if exponent < 1:
            raise ValueError(f"exponent must be ≥ 1, got {exponent}")
        self.rows, self.cols, self.pitch_m = int(rows), int(cols), float(pitch_m)
        self.subdiv = max(1, int(round(pitch_m * 1000.0 / cell_mm)))
        self.cell_m = self.pitch_m / self.subdiv
        self.rug_sigma_m = rug_sigma_mm / 1000.0
        self.crossing_frac = float(crossing_frac)
        self.rug_kpa_per_mm = float(rug_kpa_per_mm)
        self.exponent = float(exponent)
        self.band_m = band_mm / 1000.0
        self.max_band_m = max(max_band_mm, band_mm) / 1000.0
        self.contact_kpa = float(contact_kpa)
        self.max_gap_m = max_gap_mm / 1000.0
        self.max_slope = float(max_slope)
        self.g = float(g_m_s2)
        self.default_tissue = float(default_tissue_kpa_per_mm)
        self.pad = int(math.ceil((5.0 * self.rug_sigma_m + self.pitch_m) / self.cell_m)) + 1
        width = self.crossing_frac * self.pitch_m
        self._ky = sampling_kernel(self.rows, self.pitch_m, self.cell_m, self.pad, self.rug_sigma_m, width)
        self._kx = sampling_kernel(self.cols, self.pitch_m, self.cell_m, self.pad, self.rug_sigma_m, width)
        self._ny_lattice = self.rows * self.subdiv
        self._nx_lattice = self.cols * self.subdiv

    def __repr__(self) -> str:
        return (f"ContactModel({self.rows}x{self.cols}, pitch {self.pitch_m * 1000:.2f} mm, cell {self.cell_m * 1000:.2f} mm, "
                f"rug σ {self.rug_sigma_m * 1000:.1f} mm, crossing {self.crossing_frac:.2f} pitch)")

    # ------------------------------------------------------------------ public
    def pressure_kpa(
        self,
        vertices,
        faces,
        mass_kg: float,
        acc_z_m_s2: float = 0.0,
        com_m=None,
        static: bool = True,
        acc_xy_m_s2=None,
        tissue_kpa_per_mm=None,
        keep_fine: bool = False,
    ) -> ContactResult:
        """One person's pressure field. See the package docstring for the method.

        vertices (V,3) metres in the carpet frame; faces (F,3); mass_kg (from
        ``subject_mass_kg``); acc_z_m_s2: the COM's vertical acceleration; com_m: the
        COM (default: the posed mesh's volume centroid); static: put the COP under the
        COM; acc_xy_m_s2: the COM's horizontal acceleration, which moves the target COP
        to com_xy − com_z·a_xy/(g + a_z) (implies a balanced solve); neither: the COP
        falls where the uniform indentation puts it. tissue_kpa_per_mm: (V,) tissue
        stiffness (``tissue_stiffness(model)``) or a scalar; default uniform.
        """
        v = np.asarray(vertices, dtype=np.float64)
        faces = np.asarray(faces)
        if v.ndim != 2 or v.shape[1] != 3 or not np.isfinite(v).all():
            raise ValueError("vertices must be a finite (V, 3) array")
        if mass_kg <= 0:
            raise ValueError(f"mass_kg must be positive, got {mass_kg}")
        com = mesh_centroid_m(v, faces) if com_m is None else np.asarray(com_m, dtype=np.float64).reshape(3)
        target_f = float(mass_kg) * (self.g + float(acc_z_m_s2))
        target_cop = None
        if acc_xy_m_s2 is not None:
            axy = np.asarray(acc_xy_m_s2, dtype=np.float64).reshape(2)
            target_cop = com[:2] - com[2] * axy / max(self.g + float(acc_z_m_s2), 1e-6)
        elif static:
            target_cop = com[:2].copy()
        k_vertex = self._vertex_stiffness(tissue_kpa_per_mm, len(v))
        zmin = float(v[:, 2].min())
        if target_f <= 0 or zmin > self.max_gap_m:
            return self._empty(com, mass_kg, target_f, target_cop, airborne=True)

        z_max = zmin + self.band_m
        for attempt in range(6):
            # compliance (1/k) is interpolated across a triangle: tissue in series, so a soft vertex
            # (the foot's arch) stays soft between stiff neighbours (heel, metatarsal heads)
            surf = lowest_surface(v, faces, 1.0 / k_vertex, z_max, self.cell_m, faces_t=self._faces_t(faces))
            if surf.empty:
                return self._empty(com, mass_kg, target_f, target_cop, airborne=True)
            sol = self._solve(surf, zmin, z_max, target_f, target_cop)
            if not sol["balanced"] and z_max - zmin < self.max_band_m:
                # Support may lie higher than the band (a foot or hand a few cm up): widen it.
                z_max = zmin + min(2.0 * (z_max - zmin), self.max_band_m)
                continue
            # Did the solved plane reach body surface that was not rasterised?
            h, sx, sy, ref = sol["h"], sol["sx"], sol["sy"], sol["ref"]
            plane_at_v = zmin + h + sx * (v[:, 0] - ref[0]) + sy * (v[:, 1] - ref[1])
            missed = (v[:, 2] >= z_max) & (plane_at_v > v[:, 2])
            if not missed.any():
                break
            z_max = float(plane_at_v[missed].max()) + 0.01
        sol["zmin"] = zmin
        sol["band_m"] = z_max - zmin
        sol["attempts"] = attempt + 1
        return self._finish(surf, sol, com, mass_kg, target_f, target_cop, keep_fine)

    def scene(self, people: list[ContactResult]) -> SceneResult:
        """Sum several people's fields (they never overlap; the rug blur is linear)."""
        shape = (self.rows, self.cols)
        total = np.zeros(shape, np.float32)
        index = np.full(shape, -1, np.int8)
        best = np.zeros(shape, np.float32)
        for k, res in enumerate(people):
            total += res.pressure_kpa
            take = (res.pressure_kpa > best) & res.contact_mask
            index[take] = k
            best = np.maximum(best, res.pressure_kpa)
        return SceneResult(total, index, list(people))

    # ------------------------------------------------------------------ inside
    def _faces_t(self, faces):
        cached = getattr(self, "_faces_cache", None)
        if cached is None or cached[0] is not faces:
            self._faces_cache = (faces, np.ascontiguousarray(np.asarray(faces).T, dtype=np.intp))
        return self._faces_cache[1]

    def _vertex_stiffness(self, tissue, n_vertices):
        if tissue is None:
            tissue = self.default_tissue
        k = np.broadcast_to(np.asarray(tissue, dtype=np.float64), (n_vertices,))
        if (k <= 0).any() or not np.isfinite(k).all():
            raise ValueError("tissue stiffness must be positive and finite")
        return 1.0 / (1.0 / k + 1.0 / self.rug_kpa_per_mm)  # tissue and rug in series

    def _solve(self, surf: LowestSurface, zmin: float, z_max: float, target_f: float, target_cop):
        """Indentation plane z = zmin + h + sx·(x−tx) + sy·(y−ty): solve h (and the
        slopes when a COP target is set) so that Σ p·A = target_f and the moments about
        the target vanish. Newton on the convex potential Σ K·d^(n+1)/(n+1) − F·h."""
        xs, ys = surf.centres()
        jj, ii = np.nonzero(surf.z_m < z_max)  # surface above the band is checked after the solve
        z = surf.z_m[jj, ii] - zmin
        n = self.exponent
        # force per cell in N for d in metres: K·d^n, K = k[kPa/mm]·1e3·(1e3)^n·A
        kk = 1e3 * (1e3 ** n) * self.cell_m ** 2 / np.maximum(surf.attr[jj, ii], 1e-12)
        ref = target_cop if target_cop is not None else np.array([xs.mean(), ys.mean()])
        dx, dy = xs[ii] - ref[0], ys[jj] - ref[1]
        h = self._solve_height(z, kk, target_f)
        theta = np.array([h, 0.0, 0.0])
        balanced, its = True, 0
        if target_cop is not None:
            u = np.stack([np.ones_like(dx), dx, dy])  # (3, N)

            def state(t):
                d = np.maximum(t[0] + t[1] * dx + t[2] * dy - z, 0.0)
                q = kk * (d ** n if n != 1.0 else d)
                phi = float((q @ d) / (n + 1) - target_f * t[0])
                return d, q, phi

            d, q, phi = state(theta)
            free = np.ones(3, bool)  # the slopes leave the set when they reach ±max_slope
            balanced = False
            tol = 1e-5 * target_f  # force within 1e-5, moments within 10 µm × force
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
                    cs = state(cand)
                    if cs[2] <= phi + 1e-4 * alpha * float(grad @ step):
                        break
                    alpha *= 0.5
                for k in (1, 2):  # the tilt is bounded: beyond it the COM is outside the support
                    if abs(cand[k]) > self.max_slope:
                        cand[k] = np.sign(cand[k]) * self.max_slope
                        free[k] = False
                theta = cand
                d, q, phi = state(theta)
            if not free.all() or not balanced:
                # Closest to balance within the tilt bound: force exact, the COP as near as it gets.
                theta[0] = self._solve_height(z - theta[1] * dx - theta[2] * dy, kk, target_f)
                balanced = False
        return {"h": float(theta[0]), "sx": float(theta[1]), "sy": float(theta[2]), "ref": np.asarray(ref, float),
                "balanced": balanced, "iterations": its, "cells": (jj, ii, z, kk, dx, dy)}

    def _solve_height(self, z, kk, target_f):
        """The uniform indentation alone (no tilt): F(h) = Σ K·max(h − z, 0)^n = target."""
        n = self.exponent
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

    def _finish(self, surf, sol, com, mass_kg, target_f, target_cop, keep_fine):
        jj, ii, z, kk, dx, dy = sol["cells"]
        d = sol["h"] + sol["sx"] * dx + sol["sy"] * dy - z
        pos = d > 0
        jj, ii, d, kk = jj[pos], ii[pos], d[pos], kk[pos]
        n = self.exponent
        f_cell = kk * (d ** n if n != 1.0 else d)  # N per cell
        area = self.cell_m ** 2
        if f_cell.size == 0:
            return self._empty(com, mass_kg, target_f, target_cop, airborne=False)
        # crop to the contact's bounding box
        jlo, ilo = int(jj.min()), int(ii.min())
        ny, nx = int(jj.max()) - jlo + 1, int(ii.max()) - ilo + 1
        j0, i0 = surf.origin[0] + jlo, surf.origin[1] + ilo
        jj, ii = jj - jlo, ii - ilo
        p_kpa = np.zeros((ny, nx))
        p_kpa[jj, ii] = f_cell / (1e3 * area)
        gj, gi = jj + j0, ii + i0  # lattice indices
        on = (gj >= 0) & (gj < self._ny_lattice) & (gi >= 0) & (gi < self._nx_lattice)
        x = (gi + 0.5) * self.cell_m
        y = (gj + 0.5) * self.cell_m
        f_total = float(f_cell.sum())
        f_on = float(f_cell[on].sum())

        def cop(w):
            s = w.sum()
            return np.array([w @ x / s, w @ y / s]) if s > 0 else np.array([np.nan, np.nan])

        cop_total = cop(f_cell)
        cop_on = cop(np.where(on, f_cell, 0.0))
        # Sensels: blur + crossing window, separable, only lattice columns that can reach a sensel.
        lo_j, hi_j = max(j0, -self.pad), min(j0 + ny, self._ny_lattice + self.pad)
        lo_i, hi_i = max(i0, -self.pad), min(i0 + nx, self._nx_lattice + self.pad)
        sensels = np.zeros((self.rows, self.cols))
        if lo_j < hi_j and lo_i < hi_i:
            sub = p_kpa[lo_j - j0:hi_j - j0, lo_i - i0:hi_i - i0]
            ky = self._ky[:, lo_j + self.pad:hi_j + self.pad]
            kx = self._kx[:, lo_i + self.pad:hi_i + self.pad]
            r = np.flatnonzero(ky.any(1))
            c = np.flatnonzero(kx.any(1))
            if r.size and c.size:
                sensels[r[0]:r[-1] + 1, c[0]:c[-1] + 1] = ky[r[0]:r[-1] + 1] @ sub @ kx[c[0]:c[-1] + 1].T
        pressure = sensels.astype(np.float32)
        cop_err = float(np.hypot(*(cop_total - target_cop))) if target_cop is not None else 0.0
        res = ContactResult(
            pressure_kpa=pressure,
            contact_mask=pressure > self.contact_kpa,
            force_n=f_on,
            force_total_n=f_total,
            target_force_n=target_f,
            force_off_carpet_n=f_total - f_on,
            cop_m=cop_on,
            cop_total_m=cop_total,
            target_cop_m=None if target_cop is None else np.asarray(target_cop, float),
            com_m=com,
            mass_kg=float(mass_kg),
            balanced=bool(sol["balanced"]),
            cop_error_m=cop_err,
            airborne=False,
            indentation_mm=float(d.max() * 1e3),
            slope=np.array([sol["sx"], sol["sy"]]),
            contact_area_m2=float(d.size * area),
            sensel_force_n=float(sensels.sum() * 1e3 * self.pitch_m ** 2),
            iterations=int(sol["iterations"]),
            info={"band_mm": sol["band_m"] * 1e3, "raster_attempts": sol["attempts"], "samples": surf.samples,
                  "fine_shape": (ny, nx)},
        )
        if keep_fine:
            res.fine_pressure_kpa = p_kpa.astype(np.float32)
            res.fine_origin = (j0, i0)
            res.fine_cell_m = self.cell_m
        return res

    def _empty(self, com, mass_kg, target_f, target_cop, airborne):
        shape = (self.rows, self.cols)
        nan2 = np.array([np.nan, np.nan])
        return ContactResult(
            pressure_kpa=np.zeros(shape, np.float32), contact_mask=np.zeros(shape, bool), force_n=0.0, force_total_n=0.0,
            target_force_n=target_f, force_off_carpet_n=0.0, cop_m=nan2, cop_total_m=nan2.copy(),
            target_cop_m=None if target_cop is None else np.asarray(target_cop, float), com_m=com, mass_kg=float(mass_kg),
            balanced=target_f <= 0, cop_error_m=0.0, airborne=airborne, indentation_mm=0.0, slope=np.zeros(2),
            contact_area_m2=0.0, sensel_force_n=0.0, iterations=0,
        )

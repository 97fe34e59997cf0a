"""ContactModel: posed body mesh → true pressure per sensel (see the package docstring).

The model holds the carpet and the compliant layer; the indentation plane's solve lives in
``plane``, the rug and sensel sampling in ``sampling``, what it returns in ``result``.
"""

from __future__ import annotations

import math

import numpy as np

from sim.contact.mesh import mesh_centroid_m
from sim.contact.plane import solve_plane
from sim.contact.raster import lowest_surface
from sim.contact.result import ContactResult, SceneResult
from sim.contact.sampling import sample_sensels, sampling_kernel
from sim.contact.tissue import Tissue

G_M_S2 = 9.81


def _cop(force_n, x_m, y_m):
    """(2,) centre of pressure of per-cell forces at cell centres (x_m, y_m); NaN when no force."""
    s = force_n.sum()
    return np.array([force_n @ x_m / s, force_n @ y_m / s]) if s > 0 else np.array([np.nan, np.nan])


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
        stiffness (``tissue_stiffness(model)``) or a scalar, or a ``tissue.Tissue`` (a soft
        layer over that stiffness, by vertex: ``regional_tissue(model)``); default uniform.
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
        attr, soft_kpa_per_mm = self._tissue_attr(tissue_kpa_per_mm, len(v))
        zmin = float(v[:, 2].min())
        if target_f <= 0 or zmin > self.max_gap_m:
            return self._empty(com, mass_kg, target_f, target_cop, airborne=True)

        z_max = zmin + self.band_m
        for attempt in range(6):
            # compliance (1/k) is interpolated across a triangle: tissue in series, so a soft vertex
            # (the foot's arch) stays soft between stiff neighbours (heel, metatarsal heads)
            surf = lowest_surface(v, faces, attr, z_max, self.cell_m, faces_t=self._faces_t(faces))
            if surf.empty:
                return self._empty(com, mass_kg, target_f, target_cop, airborne=True)
            sol = solve_plane(surf, zmin, z_max, target_f, target_cop, self.exponent, self.cell_m, self.max_slope,
                              soft_kpa_per_mm)
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

    def _tissue_attr(self, tissue, n_vertices):
        """What the raster interpolates per vertex: the compliance (mm/kPa) of tissue and rug in
        series, with the soft layer's thickness (mm) as a second column when there is one; and
        the soft layer's stiffness with the rug's (kPa/mm, 0 without one)."""
        layer, soft_kpa_per_mm = None, 0.0
        if isinstance(tissue, Tissue):
            tissue, layer, soft_kpa_per_mm = tissue.kpa_per_mm, tissue.soft_layer_mm, tissue.soft_kpa_per_mm
        if tissue is None:
            tissue = self.default_tissue
        k = np.broadcast_to(np.asarray(tissue, dtype=np.float64), (n_vertices,))
        if (k <= 0).any() or not np.isfinite(k).all():
            raise ValueError("tissue stiffness must be positive and finite")
        compliance = 1.0 / k + 1.0 / self.rug_kpa_per_mm  # tissue and rug in series
        if layer is None:
            return compliance, 0.0
        layer = np.asarray(layer, dtype=np.float64)
        if layer.shape != (n_vertices,) or (layer < 0).any() or not np.isfinite(layer).all():
            raise ValueError("the soft layer must be a finite, non-negative (V,) array in mm")
        if not soft_kpa_per_mm > 0:
            raise ValueError("the soft layer's stiffness must be positive")
        if not (layer > 0).any():
            return compliance, 0.0
        return np.stack([compliance, layer], 1), 1.0 / (1.0 / soft_kpa_per_mm + 1.0 / self.rug_kpa_per_mm)

    def _finish(self, surf, sol, com, mass_kg, target_f, target_cop, keep_fine):
        """The solved plane's field: cell forces, cropped fine field, COPs, sensels → ContactResult."""
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
        np.add.at(p_kpa, (jj, ii), f_cell / (1e3 * area))  # a cell with a soft layer has two beds
        f_total, f_on, cop_total, cop_on = self._forces_and_cops(jj + j0, ii + i0, f_cell)
        sensels = sample_sensels(p_kpa, (j0, i0), self._ky, self._kx, self.pad)
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
            contact_area_m2=float(np.count_nonzero(p_kpa) * area),
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

    def _forces_and_cops(self, gj, gi, f_cell):
        """Total and on-carpet force (N) and their COPs (2,) of cell forces f_cell at lattice cells (gj, gi)."""
        on = (gj >= 0) & (gj < self._ny_lattice) & (gi >= 0) & (gi < self._nx_lattice)
        x = (gi + 0.5) * self.cell_m
        y = (gj + 0.5) * self.cell_m
        f_total = float(f_cell.sum())
        f_on = float(f_cell[on].sum())
        return f_total, f_on, _cop(f_cell, x, y), _cop(np.where(on, f_cell, 0.0), x, y)

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

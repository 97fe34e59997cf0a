"""Z-buffer of the lowest body surface on a fine lattice (cells of ``cell_m``).

The lattice is global: cell (j, i) covers x ∈ [i·c, (i+1)·c), y ∈ [j·c, (j+1)·c) with
the carpet origin at (0, 0), so cell indices line up with sensels when c divides the
pitch. Only triangles with a vertex below ``z_max`` and an outward normal pointing down
are drawn: on a closed surface the lowest point over any (x, y) lies on such a
triangle. Each triangle is sampled at the cell centres inside it (exact barycentric
interpolation of height and of a per-vertex attribute); the lowest sample per cell
wins. Vertices alone would leave holes on the lite mesh (edges of 3–5 cm).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass
class LowestSurface:
    z_m: np.ndarray  # (ny, nx) lowest surface height, +inf where nothing was drawn
    attr: np.ndarray  # (ny, nx) or (ny, nx, C): the per-vertex attribute(s) at that surface (0 where none)
    origin: tuple[int, int]  # lattice index (j0, i0) of z_m[0, 0]
    cell_m: float
    samples: int  # cell centres tested (cost measure)

    @property
    def empty(self) -> bool:
        return self.z_m.size == 0

    def centres(self):
        """Cell-centre coordinates (x (nx,), y (ny,)) in metres."""
        ny, nx = self.z_m.shape
        j0, i0 = self.origin
        return (np.arange(nx) + i0 + 0.5) * self.cell_m, (np.arange(ny) + j0 + 0.5) * self.cell_m


def lowest_surface(vertices, faces, attr, z_max: float, cell_m: float, faces_t=None) -> LowestSurface:
    """Rasterise the downward-facing triangles touching z < z_max (see module doc).

    faces_t: optional precomputed ``faces.T`` as intp (speed only)."""
    v = np.asarray(vertices, dtype=np.float64)
    near = v[:, 2] < z_max
    ft = faces_t if faces_t is not None else np.asarray(faces).T.astype(np.intp)
    f = np.asarray(faces)[near[ft[0]] | near[ft[1]] | near[ft[2]]]
    tri = v[f]
    ax, ay = tri[:, 0, 0], tri[:, 0, 1]
    ux, uy = tri[:, 1, 0] - ax, tri[:, 1, 1] - ay
    wx, wy = tri[:, 2, 0] - ax, tri[:, 2, 1] - ay
    det = ux * wy - uy * wx  # 2·signed area seen from above; < 0: normal points down
    down = det < -1e-14
    if not down.any():
        return LowestSurface(np.zeros((0, 0)), np.zeros((0, 0)), (0, 0), cell_m, 0)
    tri, f = tri[down], f[down]
    ax, ay, ux, uy, wx, wy, det = ax[down], ay[down], ux[down], uy[down], wx[down], wy[down], det[down]
    xy = tri[:, :, :2] / cell_m - 0.5  # cell-centre index units
    lo = np.ceil(xy.min(1)).astype(np.int64)
    n = np.floor(xy.max(1)).astype(np.int64) - lo + 1
    n = np.maximum(n, 0)
    cnt = n[:, 0] * n[:, 1]
    keep = cnt > 0
    if not keep.any():
        return LowestSurface(np.zeros((0, 0)), np.zeros((0, 0)), (0, 0), cell_m, 0)
    if not keep.all():
        tri, f, lo, n, cnt = tri[keep], f[keep], lo[keep], n[keep], cnt[keep]
        ax, ay, ux, uy, wx, wy, det = ax[keep], ay[keep], ux[keep], uy[keep], wx[keep], wy[keep], det[keep]
    # Barycentric coordinates, height and attribute are affine in the cell indices:
    # q = A·ix + B·iy + C per triangle (12 coefficients, gathered once per sample).
    c = cell_m
    inv = 1.0 / det
    h = 0.5 * c
    a1, b1 = c * wy * inv, -c * wx * inv
    c1 = (h * wy - h * wx - ax * wy + ay * wx) * inv
    a2, b2 = -c * uy * inv, c * ux * inv
    c2 = (h * ux - h * uy - ux * ay + uy * ax) * inv
    attr = np.asarray(attr, dtype=np.float64)
    columns = attr.shape[1:]  # () one attribute per vertex, (C,) several
    attr = attr.reshape(len(attr), -1)
    z0, dz1, dz2 = tri[:, 0, 2], tri[:, 1, 2] - tri[:, 0, 2], tri[:, 2, 2] - tri[:, 0, 2]
    at = attr[f]  # (F, 3, C)
    t0, dt1, dt2 = at[:, 0], at[:, 1] - at[:, 0], at[:, 2] - at[:, 0]
    az, bz, cz = a1 * dz1 + a2 * dz2, b1 * dz1 + b2 * dz2, z0 + c1 * dz1 + c2 * dz2
    a1c, a2c, b1c, b2c, c1c, c2c = (x[:, None] for x in (a1, a2, b1, b2, c1, c2))
    aa, ba, ca = a1c * dt1 + a2c * dt2, b1c * dt1 + b2c * dt2, t0 + c1c * dt1 + c2c * dt2
    total = int(cnt.sum())
    tid = np.repeat(np.arange(cnt.size), cnt)
    k = np.arange(total) - np.repeat(np.cumsum(cnt) - cnt, cnt)
    row, col = np.divmod(k, np.take(n[:, 0], tid))
    ix = np.take(lo[:, 0], tid) + col
    iy = np.take(lo[:, 1], tid) + row
    fx, fy = ix.astype(np.float64), iy.astype(np.float64)
    l1 = np.take(a1, tid) * fx + np.take(b1, tid) * fy + np.take(c1, tid)
    l2 = np.take(a2, tid) * fx + np.take(b2, tid) * fy + np.take(c2, tid)
    eps = -1e-9
    sel = np.flatnonzero((l1 >= eps) & (l2 >= eps) & (l1 + l2 <= 1.0 - eps))
    tid, ix, iy, fx, fy = tid[sel], ix[sel], iy[sel], fx[sel], fy[sel]
    z = np.take(az, tid) * fx + np.take(bz, tid) * fy + np.take(cz, tid)
    a = aa[tid] * fx[:, None] + ba[tid] * fy[:, None] + ca[tid]
    i0, j0 = int(ix.min()), int(iy.min())
    shape = (int(iy.max()) - j0 + 1, int(ix.max()) - i0 + 1)
    flat = (iy - j0) * shape[1] + (ix - i0)
    zbuf = np.full(shape[0] * shape[1], np.inf)
    np.minimum.at(zbuf, flat, z)
    win = z <= zbuf[flat]
    abuf = np.zeros((zbuf.size, a.shape[1]))
    abuf[flat[win]] = a[win]
    return LowestSurface(zbuf.reshape(shape), abuf.reshape(shape + columns), (j0, i0), cell_m, total)

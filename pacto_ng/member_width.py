"""The smallest member width of a thresholded design (the length scale that the robust
formulation, :mod:`pacto_ng.robust`, is meant to impose).

Method (local thickness, Hildebrand & Rüegsegger 1997): the nodal ρ̄ of a run's design.vtu is
interpolated linearly onto a square pixel grid (``pixel``, default an eighth of the smallest
triangle edge's median) and thresholded at 0.5 -- the iso-line ``pacto analyse`` cuts the part
along.  The Euclidean distance transform gives each solid pixel its distance ``d`` to the void;
the local thickness of a solid pixel is the largest diameter ``2 d(c)`` of the disks centred
at a solid pixel ``c`` with radius ``d(c)`` that cover it (the largest disk inside the solid
through that point).  The smallest member width is the least local thickness over the solid;
the 5 % quantile (by area) is reported beside it because a sharp convex corner is covered by
small disks only.  Outside the design domain counts as solid: an edge of the domain (the
symmetry line, a clamp) is not a free surface of the part.
"""
from __future__ import annotations

import numpy as np


def local_thickness(solid: np.ndarray, pixel: float) -> np.ndarray:
    """Local thickness (m) of every pixel of the boolean image ``solid`` (0 in void)."""
    from scipy import ndimage

    d = ndimage.distance_transform_edt(solid) * pixel
    # disk centres: the pixels whose disk no neighbour's disk contains (d(n) >= d(c) + |c - n|
    # for a neighbour n); a contained disk adds nothing to the maxima
    ridge = solid.copy()
    padded = np.pad(d, 1)
    ny, nx = d.shape
    for dy in (-1, 0, 1):
        for dx in (-1, 0, 1):
            if dy or dx:
                nb = padded[1 + dy:1 + dy + ny, 1 + dx:1 + dx + nx]
                ridge &= nb < d + np.hypot(dy, dx) * pixel - 1e-9 * pixel
    out = np.zeros_like(d)
    ys, xs = np.nonzero(ridge)
    order = np.argsort(d[ys, xs])
    ny, nx = solid.shape
    for iy, ix in zip(ys[order], xs[order]):
        r = d[iy, ix]
        k = int(np.floor(r / pixel))
        y0, y1, x0, x1 = max(iy - k, 0), min(iy + k + 1, ny), max(ix - k, 0), min(ix + k + 1, nx)
        yy, xx = np.mgrid[y0:y1, x0:x1]
        inside = ((yy - iy) ** 2 + (xx - ix) ** 2) * pixel ** 2 <= r * r
        win = out[y0:y1, x0:x1]
        win[inside] = np.maximum(win[inside], 2.0 * r)
    out[~solid] = 0.0
    return out


def member_width(points: np.ndarray, triangles: np.ndarray, rho: np.ndarray, *,
                 pixel: float = 0.0, threshold: float = 0.5) -> dict:
    """``min`` and ``q05`` (m): the smallest local thickness over the solid ``rho >= threshold``
    of the nodal field ``rho`` on a triangle mesh, and its 5 % area quantile (module
    docstring); ``pixel`` (m) the raster's size."""
    from matplotlib.tri import LinearTriInterpolator, Triangulation

    pts = np.asarray(points, dtype=float)[:, :2]
    tri = Triangulation(pts[:, 0], pts[:, 1], np.asarray(triangles))
    if pixel <= 0:
        e = pts[tri.edges]
        pixel = float(np.median(np.linalg.norm(e[:, 0] - e[:, 1], axis=1))) / 8.0
    lo, hi = pts.min(axis=0), pts.max(axis=0)
    xs = np.arange(lo[0] + pixel / 2, hi[0], pixel)
    ys = np.arange(lo[1] + pixel / 2, hi[1], pixel)
    X, Y = np.meshgrid(xs, ys)
    field = LinearTriInterpolator(tri, np.asarray(rho, dtype=float))(X, Y)
    outside = np.ma.getmaskarray(field)
    solid = np.where(outside, True, np.ma.filled(field, 0.0) >= threshold)
    # one pixel of solid around the raster: the domain's edges are no free surfaces
    padded = np.pad(solid, 1, constant_values=True)
    lt = local_thickness(padded, pixel)[1:-1, 1:-1]
    part = solid & ~outside
    if not part.any():
        raise ValueError("the design has no solid at this threshold")
    values = lt[part]
    return {"min": float(values.min()), "q05": float(np.quantile(values, 0.05)),
            "pixel": pixel, "threshold": threshold}


def member_width_of_run(folder, **kw) -> dict:
    """:func:`member_width` of a run folder's design.vtu (its nodal ρ̄).  A 3D design (a file
    of tetrahedra or hexahedra) is not measured: ``min`` and ``q05`` are None and ``reason``
    says why (the method rasterises a 2D design)."""
    from pathlib import Path

    import meshio

    m = meshio.read(Path(folder) / "design.vtu")
    if any(c.type in ("tetra", "hexahedron") for c in m.cells):
        return {"min": None, "q05": None, "pixel": None, "threshold": None,
                "reason": "a 3D design: the member width is measured on 2D designs only"}
    tris = np.vstack([c.data for c in m.cells if c.type == "triangle"])
    rho = np.asarray(m.point_data["rho_bar"], dtype=float).reshape(len(m.points))
    # the file holds each triangle's own corners (ρ̄ constant per element): merge the corners
    # and average ρ̄ over the triangles at a node, weighted by their area (as pacto analyse)
    pts, inv = np.unique(np.round(m.points[:, :2], 12), axis=0, return_inverse=True)
    inv = inv.ravel()
    t = inv[tris]
    e1, e2 = pts[t[:, 1]] - pts[t[:, 0]], pts[t[:, 2]] - pts[t[:, 0]]
    area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
    rho_el = rho[tris].mean(axis=1)
    num, den = np.zeros(len(pts)), np.zeros(len(pts))
    for k in range(3):
        np.add.at(num, t[:, k], area * rho_el)
        np.add.at(den, t[:, k], area)
    return member_width(pts, t, num / den, **kw)


if __name__ == "__main__":
    import sys

    for folder in sys.argv[1:]:
        w = member_width_of_run(folder)
        if w["min"] is None:
            print(f"{folder}: {w['reason']}")
            continue
        print(f"{folder}: smallest member width {w['min'] * 1e3:.2f} mm, 5 % quantile "
              f"{w['q05'] * 1e3:.2f} mm (pixel {w['pixel'] * 1e3:.3f} mm, threshold "
              f"{w['threshold']})")

"""The part of a 3D design: the solid {ρ̄ >= threshold} as a closed, smoothed surface.

:func:`part3d` smooths the element densities to the vertices (the volume-weighted mean of the
elements around a vertex, over the elements outside the passive void regions ``exclude``),
clips the tetrahedra at the threshold with pyvista's ``clip_scalar`` (linear along the element
edges: the cut is the ρ̄ = threshold iso-surface of the nodal field, and the clipped cells fill
{ρ̄ >= threshold} exactly), keeps the connected pieces that touch a ``clamp`` face or point
(the others would float), and takes the boundary of the kept cells: a closed surface by
construction, made of the iso-surface and the pieces of the domain's faces (outer faces, void
regions' walls) that the solid reaches.  That surface is smoothed by Taubin's λ|μ scheme
(Taubin 1995: a Laplacian step λ > 0 followed by a step μ < -λ, a low-pass filter that shrinks
far less than Laplacian smoothing), with the points on the domain's faces constrained: a point
on one flat face slides in that face's plane, a point on a face's edge or corner stays put, so
the part's faces on the domain's boundary stay exactly on it (the remesh names them by
position, :mod:`.reanalysis3d`).

Smoothing shrinks a surface a little; :func:`keep_volume` then moves the free points along
their normals by one common offset until the surface holds the clipped solid's volume again.
Measured (tests/post/test_3d_post.py, 2026-12-03): a hand-made pneunet-3d design +0.006 %, a
30-iteration pneunet-3d design -0.28 %, an 80-iteration one -0.04 % of the thresholded volume
of the kept pieces; closed (no open edges) and manifold.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .export import UNITS, write_binary_stl
from .grid import area_weighted_nodal, cell_volumes, mesh_to_pyvista

#: Taubin's steps (pass band about 0.1) and the number of λ|μ pairs
TAUBIN_LAMBDA, TAUBIN_MU, TAUBIN_ITERATIONS = 0.5, -0.53, 15
#: a point whose interpolated indicator is this close to 1 lies on the domain's boundary
_ON = 1.0 - 1e-9


@dataclass
class Part3D:
    """The result of :func:`part3d`."""

    surface: object  # pyvista PolyData: closed, triangulated, smoothed
    solid: object  # pyvista UnstructuredGrid: the kept clipped cells (not smoothed)
    threshold: float
    volume_thresholded: float  # ∫ [ρ̄ >= threshold] over the mesh (every piece)
    volume_kept: float  # the pieces on the clamp
    pieces: int  # connected pieces of the thresholded solid
    dropped: int  # of which not touching the clamp
    excluded: tuple = ()

    @property
    def volume(self) -> float:
        """The closed surface's enclosed volume."""
        return float(self.surface.volume)

    @property
    def volume_error(self) -> float:
        """(surface volume - thresholded volume of the kept pieces) / the latter."""
        return self.volume / self.volume_kept - 1.0


def element_materials_3d(mesh) -> np.ndarray:
    """The material name of every 3D element (NGSolve element order)."""
    idx = np.asarray(mesh.ngmesh.Elements3D().NumPy()["index"], dtype=int)
    return np.array(mesh.GetMaterials(), dtype=object)[idx - 1]


def included_grid(mesh, exclude=()):
    """``(grid, keep)``: the pyvista grid of the mesh's elements outside the materials
    ``exclude`` (cell data ``cid``: the NGSolve element number) and the boolean mask of them."""
    grid = mesh_to_pyvista(mesh)
    grid.cell_data["cid"] = np.arange(grid.n_cells)
    keep = ~np.isin(element_materials_3d(mesh), list(exclude))
    if not keep.any():
        raise ValueError(f"every element of the mesh is in an excluded material "
                         f"({', '.join(sorted(exclude))})")
    return (grid if keep.all() else grid.extract_cells(np.flatnonzero(keep))), keep


def void_regions(mesh, setup) -> tuple[str, ...]:
    """The case's passive void regions (``setup.void``) that are materials of the 3D mesh."""
    mats = set(mesh.GetMaterials())
    return tuple(n for n in getattr(setup, "void", ()) if n in mats)


def boundary_vertices(mesh, names) -> np.ndarray:
    """The vertex numbers (0-based) of the mesh's boundary faces and named points (a pinned
    support) named in ``names``."""
    from ngsolve import BBBND, BND

    names = set(names)
    return np.array(sorted({v.nr for vb in (BND, BBBND) for el in mesh.Elements(vb)
                            if el.mat in names for v in el.vertices}), dtype=int)


def _original_ids(grid, n):
    ids = grid.point_data.get("vtkOriginalPointIds")
    return np.arange(n) if ids is None else np.asarray(ids)


def part3d(mesh, rho, threshold: float, *, clamp=(), exclude=(), fields=None) -> Part3D:
    """The part {ρ̄ >= threshold} of the element densities ``rho`` of a 3D mesh (see the module
    docstring).  ``fields``: further element fields ``{name: values}`` (e.g. a two-material
    design's ρ̄2), smoothed to the vertices as ρ̄ is and carried into the solid's point data
    under their names (interpolated by the clip).  ValueError when nothing is solid or no
    piece touches the clamp."""
    rho = np.asarray(rho, dtype=float).ravel()
    if rho.size != mesh.ne:
        raise ValueError(f"rho has {rho.size} values but the mesh has {mesh.ne} elements")
    grid, _ = included_grid(mesh, exclude)
    cid = np.asarray(grid.cell_data["cid"])
    r = rho[cid]
    nodal = area_weighted_nodal(grid, r, cell_volumes(grid))
    for name, values in (fields or {}).items():
        values = np.asarray(values, dtype=float).ravel()
        if values.size != mesh.ne:
            raise ValueError(f"{name} has {values.size} values but the mesh has {mesh.ne} "
                             "elements")
        grid.point_data[name] = area_weighted_nodal(grid, values[cid], cell_volumes(grid))
    # a vertex exactly at the threshold counts as solid (as in 2D: no zero-size cuts)
    nodal[np.abs(nodal - threshold) < 1e-9] += 1e-9
    grid.point_data["rho"] = nodal
    # indicators, interpolated by the clip: on the included region's boundary, on the clamp
    orig = _original_ids(grid, grid.n_points)
    outer = grid.extract_surface(pass_pointid=True, algorithm="dataset_surface")
    onb = np.zeros(grid.n_points)
    onb[np.asarray(outer.point_data["vtkOriginalPointIds"])] = 1.0
    grid.point_data["onb"] = onb
    grid.point_data["onclamp"] = np.isin(orig, boundary_vertices(mesh, clamp)).astype(float)
    solid = grid.clip_scalar(scalars="rho", value=threshold, invert=False)
    if solid.n_cells == 0:
        raise ValueError(f"nothing is solid at threshold {threshold:g}")
    vol_all = float(cell_volumes(solid).sum())
    conn = solid.connectivity(extraction_mode="all")
    region = np.asarray(conn.cell_data["RegionId"])
    pregion = np.asarray(conn.point_data["RegionId"])
    n_pieces = int(region.max()) + 1
    on_clamp = np.unique(pregion[np.asarray(conn.point_data["onclamp"]) >= _ON])
    if clamp and on_clamp.size == 0:
        raise ValueError(f"no solid touches the clamp ({', '.join(clamp)}) at threshold "
                         f"{threshold:g}")
    kept = conn if not clamp else conn.extract_cells(np.flatnonzero(np.isin(region, on_clamp)))
    surface = boundary_surface(kept)
    vol_kept = float(cell_volumes(kept).sum())
    smooth(surface)
    keep_volume(surface, vol_kept)
    return Part3D(surface, kept, float(threshold), vol_all, vol_kept, n_pieces,
                  n_pieces - (on_clamp.size if clamp else n_pieces), tuple(exclude))


def boundary_surface(cells):
    """The closed, triangulated boundary of the cells (pyvista UnstructuredGrid), its normals
    outward (the clipped cells' faces come in either orientation)."""
    surface = cells.extract_surface(pass_pointid=False, pass_cellid=False,
                                    algorithm="dataset_surface").triangulate().clean()
    return surface.compute_normals(cell_normals=True, point_normals=False,
                                   consistent_normals=True, auto_orient_normals=True,
                                   split_vertices=False)


def _faces(surface) -> np.ndarray:
    return np.asarray(surface.faces).reshape(-1, 4)[:, 1:]


def smooth(surface, iterations: int = TAUBIN_ITERATIONS) -> None:
    """Taubin-smooth a closed triangulated surface in place, the points on the domain's faces
    (point data ``onb`` = 1) constrained as the module docstring says."""
    from scipy import sparse

    tri = _faces(surface)
    n = surface.n_points
    e = np.r_[tri[:, [0, 1]], tri[:, [1, 2]], tri[:, [2, 0]]]
    A = sparse.coo_matrix((np.ones(2 * len(e)), (np.r_[e[:, 0], e[:, 1]],
                                                  np.r_[e[:, 1], e[:, 0]])), shape=(n, n)).tocsr()
    A.data[:] = 1.0  # each neighbour once
    W = sparse.diags(1.0 / np.asarray(A.sum(axis=1)).ravel()) @ A
    pts = np.asarray(surface.points, dtype=float).copy()
    onb = np.asarray(surface.point_data["onb"]) >= _ON
    # the domain's faces: triangles with every vertex on them; their unit normals
    dom = onb[tri].all(axis=1)
    nrm = np.cross(pts[tri[:, 1]] - pts[tri[:, 0]], pts[tri[:, 2]] - pts[tri[:, 0]])
    nrm /= np.maximum(np.linalg.norm(nrm, axis=1, keepdims=True), 1e-300)
    plane = np.zeros((n, 3))
    fixed = onb.copy()  # boundary points without a flat face of their own stay put
    if dom.any():
        owners = np.repeat(np.flatnonzero(dom), 3)
        verts = tri[dom].ravel()
        first = np.full(n, -1)
        first[verts[::-1]] = owners[::-1]
        plane[verts] = nrm[first[verts]]
        parallel = np.abs(np.einsum("ij,ij->i", nrm[owners], plane[verts])) > 1.0 - 1e-6
        flat = np.ones(n, dtype=bool)
        np.logical_and.at(flat, verts, parallel)
        fixed = onb & ~(flat & (first >= 0))
    for _ in range(iterations):
        for step in (TAUBIN_LAMBDA, TAUBIN_MU):
            d = step * (W @ pts - pts)
            d -= np.einsum("ij,ij->i", d, plane)[:, None] * plane
            d[fixed] = 0.0
            pts += d
    surface.points = pts


def keep_volume(surface, volume: float, steps: int = 3) -> None:
    """Move the free points (off the domain's faces) of a closed, outward-oriented surface
    along their normals by one common offset so that it encloses ``volume`` (the smoothing's
    shrinkage undone: δ = ΔV / the area of the free triangles, repeated ``steps`` times)."""
    free = np.asarray(surface.point_data["onb"]) < _ON
    tri = _faces(surface)
    for _ in range(steps):
        nrm = surface.compute_normals(cell_normals=True, point_normals=True,
                                      split_vertices=False, consistent_normals=False)
        area = np.asarray(nrm.compute_cell_sizes(length=False, volume=False).cell_data["Area"])
        a_free = float(area[free[tri].any(axis=1)].sum())
        if a_free == 0.0:
            return
        delta = (volume - float(surface.volume)) / a_free
        pts = np.asarray(surface.points, dtype=float).copy()
        pts[free] += delta * np.asarray(nrm.point_data["Normals"])[free]
        surface.points = pts


def closed_checks(surface) -> dict:
    """``n_open_edges``, ``non_manifold_edges`` and ``manifold`` of a surface."""
    nm = surface.extract_feature_edges(boundary_edges=False, feature_edges=False,
                                       manifold_edges=False, non_manifold_edges=True)
    return dict(n_open_edges=int(surface.n_open_edges), non_manifold_edges=int(nm.n_cells),
                manifold=bool(surface.is_manifold))


def write_part_stl(path, surface, units: str = "m", header: str = ""):
    """A part's closed surface (pyvista PolyData, e.g. :attr:`Part3D.surface`) as a binary STL
    (its facets oriented outward), coordinates in ``units`` (``m`` or ``mm``:
    :data:`~pacto_ng.post.export.UNITS`), stated in the header."""
    surf = surface.copy().triangulate()
    surf.clear_data()
    unit = f"units {units}"
    write_binary_stl(path, surf, f"{header}; {unit}" if header else unit, 1.0 / UNITS[units])
    return surf

"""The optimisation mesh as a pyvista grid, and its element densities smoothed to the vertices.

:func:`mesh_to_pyvista` gives the 2D elements of an NGSolve mesh as a pyvista grid in NGSolve's
element order (the order of ρ̄); :func:`cell_areas`, :func:`element_size` and
:func:`element_materials` measure and name its elements; :func:`nodal_density` is the
area-weighted mean of the element densities around every vertex, the field whose iso-line
:func:`~pacto_ng.post.threshold.threshold` traces.  :func:`included_elements` is the mask of
the elements outside the excluded materials (passive void faces).
"""
from __future__ import annotations

import numpy as np

def mesh_to_pyvista(mesh):
    """The volume elements of an NGSolve mesh as a pyvista UnstructuredGrid (z = 0 in 2D).

    Cells follow NGSolve's element order; triangles and quadrilaterals (also mixed) in 2D,
    tetrahedra and hexahedra in 3D (:func:`mesh_to_pyvista_3d`).  Curved (high-order)
    geometry is ignored: only the vertices are used.
    """
    import pyvista as pv

    if mesh.dim == 3:
        return mesh_to_pyvista_3d(mesh)
    pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    if pts.shape[1] != 2:
        raise ValueError("only 2D and 3D meshes are supported")
    cells = [[v.nr - 1 for v in el.vertices] for el in mesh.ngmesh.Elements2D()]
    sizes = np.array([len(c) for c in cells])
    if not np.all((sizes == 3) | (sizes == 4)):
        raise ValueError("only triangles and quadrilaterals are supported")
    flat = np.concatenate([np.r_[len(c), c] for c in cells]).astype(np.int64)
    types = np.where(sizes == 3, pv.CellType.TRIANGLE, pv.CellType.QUAD).astype(np.uint8)
    return pv.UnstructuredGrid(flat, types, np.c_[pts, np.zeros(len(pts))])


def mesh_to_pyvista_3d(mesh):
    """The tetrahedra and hexahedra of a 3D NGSolve mesh as a pyvista UnstructuredGrid, in
    NGSolve's element order (Netgen's vertex order of both is VTK's)."""
    import pyvista as pv

    pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    els = mesh.ngmesh.Elements3D().NumPy()
    nodes = np.asarray(els["nodes"], dtype=np.int64) - 1  # 0: unused slot (now -1)
    sizes = np.count_nonzero(nodes >= 0, axis=1)
    if not np.all((sizes == 4) | (sizes == 8)):
        raise ValueError("only tetrahedra and hexahedra are supported")
    # each row: its size, then its nodes; the unused slots of the tetrahedra dropped
    table = np.c_[sizes, nodes]
    flat = table[np.arange(table.shape[1])[None, :] <= sizes[:, None]]
    types = np.where(sizes == 4, pv.CellType.TETRA, pv.CellType.HEXAHEDRON).astype(np.uint8)
    return pv.UnstructuredGrid(flat.astype(np.int64), types, pts)


def grid_and_densities(mesh, rho):
    """The mesh as a pyvista grid and ``rho`` as a flat float array, one value per element."""
    grid = mesh_to_pyvista(mesh)
    rho = np.asarray(rho, dtype=float).ravel()
    if rho.shape[0] != grid.n_cells:
        raise ValueError(f"rho has {rho.shape[0]} values but the mesh has {grid.n_cells} elements")
    return grid, rho


def cell_volumes(grid) -> np.ndarray:
    """The volume of every cell of a 3D pyvista grid."""
    return np.abs(np.asarray(grid.compute_cell_sizes(length=False, area=False, volume=True)
                             .cell_data["Volume"], dtype=float))


def cell_areas(grid) -> np.ndarray:
    """The area of every cell of a pyvista grid."""
    return np.asarray(grid.compute_cell_sizes(length=False, area=True, volume=False)
                      .cell_data["Area"], dtype=float)


def nodal_density(mesh, rho) -> np.ndarray:
    """Area-weighted mean of the element densities around every vertex.

    Parameters
    ----------
    mesh : ngsolve.Mesh
    rho : array_like, shape (mesh.ne,)
        Element densities in NGSolve element order.

    Returns
    -------
    ndarray, shape (mesh.nv,)
        ``ρ_i = Σ_e A_e ρ_e / Σ_e A_e`` over the elements ``e`` sharing vertex ``i``.
    """
    grid, rho = grid_and_densities(mesh, rho)
    return area_weighted_nodal(grid, rho, cell_areas(grid))


def area_weighted_nodal(grid, rho, area):
    """``Σ_e area_e ρ_e / Σ_e area_e`` over the cells ``e`` around every point of ``grid``."""
    conn = grid.cell_connectivity
    offs = grid.cell_offsets
    counts = np.diff(offs)
    owner = np.repeat(np.arange(grid.n_cells), counts)
    num = np.bincount(conn, weights=(area * rho)[owner], minlength=grid.n_points)
    den = np.bincount(conn, weights=area[owner], minlength=grid.n_points)
    return num / den


def element_size(grid, area) -> float:
    """The median element size: the side of the equilateral triangle or square of an
    element's area."""
    counts = np.diff(grid.cell_offsets)
    side = np.where(counts == 3, np.sqrt(4.0 * area / np.sqrt(3.0)), np.sqrt(area))
    return float(np.median(side))


def element_materials(mesh) -> np.ndarray:
    """The material name of every 2D element (NGSolve element order)."""
    ngm = mesh.ngmesh
    return np.array([ngm.GetMaterial(el.index) for el in ngm.Elements2D()], dtype=object)


def included_elements(mesh, exclude) -> np.ndarray | None:
    """Boolean mask of the elements whose material is not in ``exclude`` (None: all)."""
    exclude = set((exclude,) if isinstance(exclude, str) else (exclude or ()))
    if not exclude:
        return None
    keep = ~np.isin(element_materials(mesh), list(exclude))
    if not keep.any():
        raise ValueError(f"every element of the mesh is in an excluded material "
                         f"({', '.join(sorted(exclude))})")
    return keep


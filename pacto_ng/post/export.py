"""Files of a post-analysis: STL of the part, VTU of the fields, conversions between formats.

* ``design.stl`` — the solid extruded by the thickness with pyvista's ``extrude(...,
  capping=True)``, normals oriented consistently outward (:func:`write_stl`);
* ``remeshed.vtu`` / ``deformed.vtu`` — the analysed part (2D or 3D) in the reference /
  deformed configuration with point data ``u`` and cell data ``J`` (det F), ``stress``
  (Cauchy, 3x3, row-major, from the analysis's own energy by automatic differentiation) and
  ``von_mises`` (:func:`write_vtu`, written with meshio);
* :func:`convert` — any of stl | vtk | vtu | msh to another, through meshio;
* the fabricable part of ``pacto export`` (the whole mechanism, its fields, in the unit of
  :data:`UNITS`): :mod:`~pacto_ng.post.part2d`.

The pictures of a post-analysis (``deformed.png``, ``analysis.png``, ``materials.png``) are
:mod:`.pictures`.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from ..files import atomic_path
from ..physics.materials import first_piola_kirchhoff
from .grid import mesh_to_pyvista

FORMATS = {".stl": "stl", ".vtk": "vtk", ".vtu": "vtu", ".msh": "gmsh"}

#: the length units ``pacto export`` writes in: metres per unit
UNITS = {"mm": 1e-3, "m": 1.0}


# ---------------------------------------------------------------------------------------
#: meshio's cell types by (dimension, vertices per element)
_CELL_TYPES = {(2, 3): "triangle", (2, 4): "quad", (3, 4): "tetra", (3, 5): "pyramid",
               (3, 6): "wedge", (3, 8): "hexahedron"}


def _elements(mesh):
    """``(nodes, counts)``: the volume elements of a 2D or 3D NGSolve mesh as 0-based vertex
    rows (padded with -1) and their vertex counts, in NGSolve's element order."""
    ngm = mesh.ngmesh
    els = (ngm.Elements2D() if mesh.dim == 2 else ngm.Elements3D()).NumPy()
    nodes = np.asarray(els["nodes"], dtype=np.int64) - 1
    return nodes, np.count_nonzero(nodes >= 0, axis=1)


def mesh_arrays(mesh):
    """Vertex coordinates (nv, dim) and meshio cell blocks of a 2D or 3D NGSolve mesh (one
    block per element type, in the order of :func:`_block_order`)."""
    pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    nodes, counts = _elements(mesh)
    blocks = []
    for n in sorted(set(counts.tolist())):
        kind = _CELL_TYPES.get((mesh.dim, n))
        if kind is None:
            raise ValueError(f"elements of {n} vertices in {mesh.dim}D are not written")
        blocks.append((kind, nodes[counts == n][:, :n]))
    return pts, blocks


def solid_surface(source):
    """A triangulated pyvista surface (z = 0) of an NGSolve mesh or a pyvista dataset."""
    import pyvista as pv

    if isinstance(source, pv.DataSet):
        surf = source.extract_surface(algorithm="dataset_surface") \
            if not isinstance(source, pv.PolyData) else source
    else:
        surf = mesh_to_pyvista(source).extract_surface(algorithm="dataset_surface")
    surf = surf.triangulate().clean()
    surf.clear_data()  # bookkeeping arrays (vtkOriginalCellIds) would not survive extrusion
    return surf


def extrude_solid(source, thickness: float):
    """The closed 3D solid: ``source`` (2D, z = 0) extruded by ``thickness`` along z.

    Returns a triangulated pyvista PolyData with consistent, outward normals.
    """
    if thickness <= 0:
        raise ValueError("thickness must be positive")
    surf = solid_surface(source)
    solid = surf.extrude((0.0, 0.0, float(thickness)), capping=True).triangulate().clean()
    return solid.compute_normals(consistent_normals=True, auto_orient_normals=True,
                                 split_vertices=False, cell_normals=True, point_normals=False)


def write_stl(path, source, thickness: float):
    """Write the extruded solid as a binary STL; returns the PolyData written."""
    solid = extrude_solid(source, thickness)
    with atomic_path(path) as tmp:
        solid.save(str(tmp), binary=True)
    return solid


# ---------------------------------------------------------------------------------------
def cauchy_stress(phi, G, plane: str = "strain"):
    """The Cauchy stress ``σ = P Fᵀ / J`` (3x3) of the energy density ``phi`` (``G -> CF``,
    per unit reference volume, 2D or 3D: a part's :meth:`~.part_analysis.PartAnalysis.
    energy_density`) at the displacement gradient ``G``, with ``P = ∂φ/∂F`` by automatic
    differentiation (:func:`~pacto_ng.physics.materials.first_piola_kirchhoff`), and
    ``J = det F``.  In 2D plane strain ``G`` is embedded in 3x3 with ``F33 = 1`` (the energy
    of the embedded gradient is the plane-strain energy), so ``σ_zz = P33 / J`` comes out of
    the same derivative; in plane stress ``σ_zz = 0`` and ``J`` is the in-plane one (the
    change of thickness is not followed).  Returns ``(σ, J)`` as CFs."""
    from ngsolve import CF, Det, Id

    if G.dims[0] == 2:
        if plane == "strain":
            G = CF((G[0, 0], G[0, 1], 0.0, G[1, 0], G[1, 1], 0.0, 0.0, 0.0, 0.0), dims=(3, 3))
        else:
            P2 = first_piola_kirchhoff(phi, G)
            F2 = Id(2) + G
            J = Det(F2)
            s2 = P2 * F2.trans / J
            return CF((s2[0, 0], s2[0, 1], 0.0, s2[1, 0], s2[1, 1], 0.0, 0.0, 0.0, 0.0),
                      dims=(3, 3)), J
    P = first_piola_kirchhoff(phi, G)
    F = Id(3) + G
    J = Det(F)
    return P * F.trans / J, J


def deformation_fields(mesh, u, phi=None, plane: str = "strain") -> tuple[np.ndarray, dict]:
    """Vertex displacements and, with the energy density ``phi``, element-centroid ``J``,
    Cauchy stress and von Mises stress (:func:`cauchy_stress`), of a 2D or 3D mesh.

    Returns
    -------
    u_vertices : ndarray, shape (nv, 3)
        z = 0 in 2D.
    cell_data : dict of ndarray
        ``J`` (ne,), ``stress`` (ne, 9, row-major), ``von_mises`` (ne,); empty without ``phi``.
    """
    from ngsolve import Grad

    d = mesh.dim
    pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    uv = np.asarray(u(mesh(*(pts[:, i].copy() for i in range(d))))).reshape(-1, d)
    uv = np.c_[uv, np.zeros((len(uv), 3 - d))]
    if phi is None:
        return uv, {}
    nodes, counts = _elements(mesh)
    cen = np.array([pts[row[:n]].mean(axis=0) for row, n in zip(nodes, counts)])
    mips = mesh(*(cen[:, i].copy() for i in range(d)))
    sig, J = cauchy_stress(phi, Grad(u), plane)
    s3 = np.asarray(sig(mips)).reshape(-1, 3, 3)
    dev = s3 - np.einsum("ijj->i", s3)[:, None, None] / 3.0 * np.eye(3)
    vm = np.sqrt(1.5 * np.einsum("ijk,ijk->i", dev, dev))
    return uv, {"J": np.asarray(J(mips)).ravel(), "stress": s3.reshape(-1, 9), "von_mises": vm}


def write_vtu(path, mesh, u=None, *, phi=None, plane: str = "strain", E=None,
              deformed: bool = False, point_data=None):
    """Write a 2D or 3D NGSolve mesh (and its displacement fields) as VTU with meshio.

    A mesh of named materials other than ``solid`` (a two-material part, an as-built part of
    several regions) gets cell data ``material`` (1, 2, ... in the order of the sorted
    names), one indicator array ``material_<name>`` per material (1 in its cells, else 0)
    and, with ``E`` a dict ``{material: E}``, ``E`` (Pa).

    Parameters
    ----------
    path : str or Path
    mesh : ngsolve.Mesh
    u : GridFunction, optional
        Displacement (point data ``u``, 3 components); with ``phi`` the cell data ``J``,
        ``stress`` and ``von_mises`` too (:func:`deformation_fields`).
    phi : callable ``G -> CF``, optional
        The energy density the stress comes from; ``plane`` its 2D model.
    deformed : bool
        Move the points by ``u`` (``deformed.vtu``); otherwise the reference configuration.
    point_data : dict, optional
        More point data (one value or row per vertex).

    Returns
    -------
    meshio.Mesh
    """
    import meshio

    pts, blocks = mesh_arrays(mesh)
    pts = np.c_[pts, np.zeros((len(pts), 3 - mesh.dim))]
    pdata, cdata = dict(point_data or {}), {}
    order = _block_order(mesh)
    if u is not None:
        uv, cells = deformation_fields(mesh, u, phi, plane)
        for key, val in cells.items():
            cdata[key] = [val[idx] for idx in order]
        pdata["u"] = uv
        if deformed:
            pts = pts + uv
    elif deformed:
        raise ValueError("a deformed configuration needs the displacement u")
    names = material_names(mesh)
    if len(names) > 1 or names[0] != "solid":
        # the material of every cell: its number in the sorted names, and (VTK and VTU keep no
        # names of their own) one indicator array per material, material_<name>; with E given
        # as {material: E}, its Young's modulus
        ids, _ = material_ids(mesh)
        cdata["material"] = [ids[idx] for idx in order]
        for i, n in enumerate(names):
            cdata[f"material_{n}"] = [(ids[idx] == i + 1).astype(np.int64) for idx in order]
        if isinstance(E, dict):
            mod = np.array([E.get(n, np.nan) for n in names], dtype=float)[ids - 1]
            cdata["E"] = [mod[idx] for idx in order]
    out = meshio.Mesh(pts, blocks, point_data=pdata, cell_data=cdata)
    with atomic_path(path) as tmp:
        out.write(str(tmp), file_format="vtu")
    return out


def material_names(mesh) -> list[str]:
    """The distinct materials of the elements of a 2D or 3D NGSolve mesh (several regions may
    share a name; a name without elements, e.g. a void region cut out of an as-built part,
    is left out), sorted."""
    region = mesh.GetMaterials()
    nodes = (mesh.ngmesh.Elements2D() if mesh.dim == 2 else mesh.ngmesh.Elements3D()).NumPy()
    return sorted({region[i - 1] for i in np.unique(nodes["index"])})


def material_ids(mesh) -> tuple[np.ndarray, dict]:
    """``(ids, field_data)``: every element's material as its 1-based number in
    :func:`material_names` (NGSolve element order) and ``{name: [id, dim]}`` (the Gmsh
    convention of named physical groups)."""
    names = material_names(mesh)
    region = mesh.GetMaterials()  # region index - 1 -> name
    number = {n: i + 1 for i, n in enumerate(names)}
    els = (mesh.ngmesh.Elements2D() if mesh.dim == 2 else mesh.ngmesh.Elements3D()).NumPy()
    ids = np.array([number[region[i - 1]] for i in els["index"]], dtype=np.int64)
    return ids, {n: np.array([i, mesh.dim]) for n, i in number.items()}


def _block_order(mesh):
    """Element indices of each block of :func:`mesh_arrays` (meshio's cell order)."""
    _, counts = _elements(mesh)
    return [np.flatnonzero(counts == n) for n in sorted(set(counts.tolist()))]


def write_binary_stl(path, solid, header: str = "", scale: float = 1.0):
    """Write a triangulated pyvista surface as a binary STL, coordinates times ``scale``,
    with ``header`` (ASCII, at most 80 characters, not starting with ``solid``) in its
    header; facet normals from the vertex order."""
    faces = np.asarray(solid.faces).reshape(-1, 4)
    if not np.all(faces[:, 0] == 3):
        raise ValueError("the STL surface must be triangles")
    v = np.asarray(solid.points, dtype=float)[faces[:, 1:]] * scale
    n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
    n /= np.maximum(np.linalg.norm(n, axis=1), 1e-300)[:, None]
    head = header.encode("ascii", "replace")[:80]
    if head[:5].lower() == b"solid":
        raise ValueError("a binary STL header must not start with 'solid'")
    rec = np.zeros(len(v), dtype=[("n", "<f4", (3,)), ("v", "<f4", (3, 3)), ("a", "<u2")])
    rec["n"], rec["v"] = n, v
    with atomic_path(path) as tmp:
        with open(tmp, "wb") as f:
            f.write(head.ljust(80, b" "))
            f.write(np.uint32(len(v)).tobytes())
            f.write(rec.tobytes())
    return path


def convert(src, dst):
    """Convert a mesh file between stl, vtk, vtu and msh (by extension) with meshio.

    Raises
    ------
    ValueError
        For another extension, or when meshio cannot write the cells to the target format
        (e.g. an STL of a mesh without triangles).
    """
    import meshio

    src, dst = Path(src), Path(dst)
    for p in (src, dst):
        if p.suffix.lower() not in FORMATS:
            raise ValueError(f"unsupported format '{p.suffix}' (use {', '.join(FORMATS)})")
    m = meshio.read(str(src), file_format=FORMATS[src.suffix.lower()])
    fmt = FORMATS[dst.suffix.lower()]
    if fmt == "stl":
        tri = [b for b in m.cells if b.type == "triangle"]
        if not tri:
            raise ValueError(f"{src.name} has no triangles to write as STL")
        m = meshio.Mesh(m.points, tri)
    with atomic_path(dst) as tmp:
        try:
            meshio.write(str(tmp), m, file_format=fmt, **({"binary": True} if fmt == "stl" else {}))
        except OSError:
            raise  # a failed write (atomic_path: one line naming dst)
        except Exception as exc:  # meshio raises assorted types for unsupported cells
            raise ValueError(f"meshio cannot write {src.name} as {fmt}: {exc}") from exc
    return dst

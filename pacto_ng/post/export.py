"""Files and pictures of a post-analysis: STL of the part, VTU of the fields, PNG figures.

* ``design.stl`` — the solid extruded by the thickness with pyvista's ``extrude(...,
  capping=True)``, normals oriented consistently outward (:func:`write_stl`);
* ``remeshed.vtu`` / ``deformed.vtu`` — the remeshed solid in the reference / deformed
  configuration with point data ``u`` and cell data ``J`` (det F), ``stress`` (Cauchy, 3x3,
  row-major) and ``von_mises`` (:func:`write_vtu`, written with meshio);
* :func:`convert` — any of stl | vtk | vtu | msh to another, through meshio;
* :class:`PartMesh` / :func:`part_mesh` — a 2D part as arrays, the half a case is solved on
  merged with its mirror image about the symmetry line (one vertex on the line, no edge
  inside), for ``pacto export``'s whole mechanism; :func:`part_fields` — the run's final state
  on it (ρ̄, u, p, strain and stress); :func:`write_part_stl` / :func:`write_part_vtu` — the
  fabricable part in the unit asked (:data:`UNITS`);
* ``deformed.png`` (:func:`plot_deformed`) and ``analysis.png`` (:func:`plot_sweeps`), drawn
  with matplotlib's Agg canvas (no screen, no change of the global backend).
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..files import atomic_path

FORMATS = {".stl": "stl", ".vtk": "vtk", ".vtu": "vtu", ".msh": "gmsh"}

#: the length units ``pacto export`` writes in: metres per unit
UNITS = {"mm": 1e-3, "m": 1.0}


# ---------------------------------------------------------------------------------------
def _mesh_arrays(mesh):
    """Vertex coordinates (nv, 2) and meshio cell blocks of a 2D NGSolve mesh."""
    pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    tris, quads = [], []
    for el in mesh.ngmesh.Elements2D():
        vs = [v.nr - 1 for v in el.vertices]
        (tris if len(vs) == 3 else quads).append(vs)
    blocks = []
    if tris:
        blocks.append(("triangle", np.array(tris, dtype=np.int64)))
    if quads:
        blocks.append(("quad", np.array(quads, dtype=np.int64)))
    return pts, blocks


def solid_surface(source):
    """A triangulated pyvista surface (z = 0) of an NGSolve mesh or a pyvista dataset."""
    import pyvista as pv

    if isinstance(source, pv.DataSet):
        surf = source.extract_surface(algorithm="dataset_surface") \
            if not isinstance(source, pv.PolyData) else source
    else:
        from .grid import mesh_to_pyvista

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
def deformation_fields(mesh, u, E, nu: float) -> tuple[np.ndarray, dict]:
    """Vertex displacements and element-centroid ``J``, Cauchy stress and von Mises stress.

    ``E`` is a number, or ``{material: E}`` (a part of two materials).  The first
    Piola–Kirchhoff stress is ``∂φ/∂F`` of the Neo-Hookean energy, by automatic
    differentiation; ``σ = P Fᵀ / J`` in plane, and ``σ_zz = λ ln J / J`` (F33 = 1).

    Returns
    -------
    u_vertices : ndarray, shape (nv, 2)
    cell_data : dict of ndarray
        ``J`` (ne,), ``stress`` (ne, 9), ``von_mises`` (ne,)
    """
    from ngsolve import Grad, Id, log

    from ..physics.materials import first_piola_kirchhoff, jacobian, lame, neohookean_energy
    from .materials import modulus_cf

    E = modulus_cf(mesh, E)
    pts, _ = _mesh_arrays(mesh)
    uv = np.asarray(u(mesh(pts[:, 0].copy(), pts[:, 1].copy()))).reshape(-1, 2)
    cen = []
    for el in mesh.ngmesh.Elements2D():
        cen.append(pts[[v.nr - 1 for v in el.vertices]].mean(axis=0))
    cen = np.array(cen)
    mips = mesh(cen[:, 0].copy(), cen[:, 1].copy())
    Pk = first_piola_kirchhoff(lambda G: neohookean_energy(G, E, nu, "strain"), Grad(u))
    F = Id(2) + Grad(u)
    J = jacobian(Grad(u))
    sig = (Pk * F.trans) / J
    _, lam = lame(E, nu)
    szz = lam * log(J) / J
    Jv = np.asarray(J(mips)).ravel()
    s2 = np.asarray(sig(mips)).reshape(-1, 2, 2)
    sz = np.asarray(szz(mips)).ravel()
    s3 = np.zeros((len(cen), 3, 3))
    s3[:, :2, :2] = s2
    s3[:, 2, 2] = sz
    dev = s3 - np.einsum("ijj->i", s3)[:, None, None] / 3.0 * np.eye(3)
    vm = np.sqrt(1.5 * np.einsum("ijk,ijk->i", dev, dev))
    return uv, {"J": Jv, "stress": s3.reshape(-1, 9), "von_mises": vm}


def write_vtu(path, mesh, u=None, *, E: float | None = None, nu: float | None = None,
              deformed: bool = False):
    """Write a 2D NGSolve mesh (and its displacement fields) as VTU with meshio.

    A mesh of named materials other than ``solid`` (a two-material part) gets cell data
    ``material`` (1, 2, ... in the order of the sorted names: ``soft``, ``stiff``), one
    indicator array ``material_<name>`` per material (1 in its cells, else 0) and, with ``E``
    a dict, ``E`` (Pa).

    Parameters
    ----------
    path : str or Path
    mesh : ngsolve.Mesh
    u : GridFunction, optional
        Displacement; with ``E`` and ``nu`` the cell data ``J``, ``stress``, ``von_mises`` are
        written too.
    deformed : bool
        Move the points by ``u`` (``deformed.vtu``); otherwise the reference configuration.

    Returns
    -------
    meshio.Mesh
    """
    import meshio

    pts, blocks = _mesh_arrays(mesh)
    point_data, cell_data = {}, {}
    if u is not None:
        if E is not None and nu is not None:
            uv, cells = deformation_fields(mesh, u, E, nu)
            order = _block_order(mesh)
            for key, val in cells.items():
                cell_data[key] = [val[idx] for idx in order]
        else:
            uv = np.asarray(u(mesh(pts[:, 0].copy(), pts[:, 1].copy()))).reshape(-1, 2)
        point_data["u"] = np.c_[uv, np.zeros(len(uv))]
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
        order = _block_order(mesh)
        cell_data["material"] = [ids[idx] for idx in order]
        for i, n in enumerate(names):
            cell_data[f"material_{n}"] = [(ids[idx] == i + 1).astype(np.int64) for idx in order]
        if isinstance(E, dict):
            mod = np.array([E[n] for n in names], dtype=float)[ids - 1]
            cell_data["E"] = [mod[idx] for idx in order]
    out = meshio.Mesh(np.c_[pts, np.zeros(len(pts))], blocks, point_data=point_data,
                      cell_data=cell_data)
    with atomic_path(path) as tmp:
        out.write(str(tmp), file_format="vtu")
    return out


def material_names(mesh) -> list[str]:
    """The distinct materials of a 2D NGSolve mesh (several faces may share a name), sorted."""
    return sorted(set(mesh.GetMaterials()))


def material_ids(mesh) -> tuple[np.ndarray, dict]:
    """``(ids, field_data)``: every element's material as its 1-based number in
    :func:`material_names` (NGSolve element order) and ``{name: [id, 2]}`` (the Gmsh convention
    of named physical groups)."""
    names = material_names(mesh)
    region = mesh.GetMaterials()  # region index - 1 -> name
    number = {n: i + 1 for i, n in enumerate(names)}
    ids = np.array([number[region[el.index - 1]] for el in mesh.ngmesh.Elements2D()],
                   dtype=np.int64)
    return ids, {n: np.array([i, 2]) for n, i in number.items()}


def _block_order(mesh):
    """Element indices of the triangle block and the quad block (meshio's cell order)."""
    tri, quad = [], []
    for k, el in enumerate(mesh.ngmesh.Elements2D()):
        (tri if len(el.vertices) == 3 else quad).append(k)
    return [np.array(b, dtype=np.int64) for b in (tri, quad) if b]


# ---------------------------------------------------------------------------------------
# the fabricable part: the whole mechanism, in the unit asked, with the run's fields
@dataclass
class PartMesh:
    """A 2D part as arrays (coordinates in m), possibly the half a case is solved on merged
    with its mirror image (:func:`part_mesh`).

    ``elements`` are vertex lists (triangles, quads), counter-clockwise; ``source_cell`` and
    ``source_point`` give for every element and vertex the one of the half it is (or is the
    mirror image of), ``mirrored_cell`` / ``mirrored_point`` whether it is an image;
    ``material`` the 1-based material number of every element (:func:`material_ids`) and
    ``material_groups`` their names; ``edges`` / ``edge_names`` the boundary edges and their
    names (the ``symmetry`` edges, inside the whole part, are gone); ``line`` the symmetry
    line mirrored about (None: the part as solved).
    """

    points: np.ndarray
    elements: list
    source_cell: np.ndarray
    mirrored_cell: np.ndarray
    source_point: np.ndarray
    mirrored_point: np.ndarray
    material: np.ndarray
    material_groups: dict
    edges: np.ndarray
    edge_names: list
    line: object = None

    @property
    def n_points(self) -> int:
        return len(self.points)

    def block_order(self) -> list:
        """Element indices of the triangle block and of the quad block (meshio's order)."""
        tri = [k for k, e in enumerate(self.elements) if len(e) == 3]
        quad = [k for k, e in enumerate(self.elements) if len(e) == 4]
        return [np.array(b, dtype=np.int64) for b in (tri, quad) if b]

    def blocks(self) -> list:
        """meshio cell blocks, in the order of :meth:`block_order`."""
        out = []
        for idx in self.block_order():
            kind = "triangle" if len(self.elements[idx[0]]) == 3 else "quad"
            out.append((kind, np.array([self.elements[k] for k in idx], dtype=np.int64)))
        return out

    def triangles(self) -> np.ndarray:
        """Every element as triangles (a quad split along its first diagonal)."""
        tris = []
        for e in self.elements:
            tris.append(e[:3])
            if len(e) == 4:
                tris.append([e[0], e[2], e[3]])
        return np.array(tris, dtype=np.int64).reshape(-1, 3)

    def area(self) -> float:
        """The part's area (m²), the sum of its triangles'."""
        p, t = self.points, self.triangles()
        a, b = p[t[:, 1]] - p[t[:, 0]], p[t[:, 2]] - p[t[:, 0]]
        return float(0.5 * np.abs(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum())

    def centroids(self) -> np.ndarray:
        return np.array([self.points[e].mean(axis=0) for e in self.elements]).reshape(-1, 2)


def part_mesh(mesh, line=None, rtol: float = 1e-9) -> PartMesh:
    """The 2D NGSolve ``mesh`` as a :class:`PartMesh`, with ``line`` (a
    :class:`~pacto_ng.post.domain.Line`) its mirror image appended and merged.

    A vertex within ``rtol`` times the part's diameter of the line is its own mirror image (one
    vertex, shared by both halves), so the halves join along the line without duplicate
    vertices; the images of the elements are reversed (counter-clockwise like the originals);
    the boundary edges on the line (both vertices on it) lie inside the whole part and are left
    out.  A part that does not reach the line gives two pieces.
    """
    from ngsolve import BND

    pts, _ = _mesh_arrays(mesh)
    pts = pts[:, :2].copy()
    elements = [[v.nr - 1 for v in el.vertices] for el in mesh.ngmesh.Elements2D()]
    ids, groups = material_ids(mesh)
    edges = [[v.nr for v in el.vertices] for el in mesh.Elements(BND)]
    names = [el.mat for el in mesh.Elements(BND)]
    ne, nv = len(elements), len(pts)
    if line is None:
        return PartMesh(pts, elements, np.arange(ne), np.zeros(ne, bool), np.arange(nv),
                        np.zeros(nv, bool), ids, groups,
                        np.array(edges, dtype=np.int64).reshape(-1, 2), names, None)
    diam = float(np.ptp(pts, axis=0).max()) or 1.0
    p0 = np.asarray(line.point, dtype=float)
    d = np.asarray(line.direction, dtype=float)
    dist = np.abs((pts - p0) @ np.array([-d[1], d[0]]))
    on = dist <= rtol * diam
    image = np.empty(nv, dtype=np.int64)  # the image of every vertex
    image[on] = np.flatnonzero(on)
    off = np.flatnonzero(~on)
    image[off] = nv + np.arange(len(off))
    refl = line.reflect(pts[off])
    points = np.vstack([pts, refl])
    elements = elements + [list(image[e][::-1]) for e in elements]
    kept = [k for k, e in enumerate(edges) if not (on[e[0]] and on[e[1]])]
    edges2 = [edges[k] for k in kept] + [list(image[edges[k]][::-1]) for k in kept]
    names2 = [names[k] for k in kept] * 2
    return PartMesh(points, elements, np.r_[np.arange(ne), np.arange(ne)],
                    np.r_[np.zeros(ne, bool), np.ones(ne, bool)],
                    np.r_[np.arange(nv), off], np.r_[np.zeros(nv, bool), np.ones(len(off), bool)],
                    np.r_[ids, ids], groups, np.array(edges2, dtype=np.int64).reshape(-1, 2),
                    names2, line)


def _reflection(line) -> np.ndarray:
    """The 2x2 matrix R = 2 d dᵀ − I of the reflection about ``line`` (vectors: R v, tensors:
    R T Rᵀ)."""
    d = np.asarray(line.direction, dtype=float)
    return 2.0 * np.outer(d, d) - np.eye(2)


def _locate(mesh, xy, inward):
    """MeshPoints of ``xy`` (n, 2) in the 2D NGSolve ``mesh``.  A point not found (a vertex of
    the part on the domain's boundary, outside by round-off) is moved towards ``inward`` (n, 2),
    a point inside the part, by 1e-9, 1e-6, 1e-3 of the way and at last onto it.

    Raises
    ------
    ValueError
        When a point is not found even there.
    """
    xy = np.array(xy, dtype=float)
    mips = mesh(xy[:, 0].copy(), xy[:, 1].copy())
    for frac in (1e-9, 1e-6, 1e-3, 1.0):
        bad = np.flatnonzero(mips["nr"] < 0)
        if not len(bad):
            return mips
        q = xy[bad] + frac * (inward[bad] - xy[bad])
        again = mesh(q[:, 0].copy(), q[:, 1].copy())
        mips[bad] = again
    if np.any(mips["nr"] < 0):
        raise ValueError(f"{int(np.sum(mips['nr'] < 0))} points of the part lie outside the "
                         f"run's mesh: its fields cannot be sampled there")
    return mips


def part_fields(problem, part: PartMesh) -> tuple[dict, dict, list]:
    """The run's final state (``problem`` rebuilt and analysed: :func:`~pacto_ng.post.runs.
    rebuild`) on the part: ``(point_data, cell_data, notes)`` in SI units.

    * cell data ``rho_bar`` (``rho_bar1``, ``rho_bar2`` for two materials): the filtered
      (projected) density of the optimisation element holding the part cell's centroid;
    * point data ``u`` (m, (n, 2)) and ``p`` (Pa, the Darcy pressure at the run's load, for a
      pressure case): the run's fields at the part's vertices;
    * cell data of the run model's strain and stress measures (as ``design.vtu``:
      :func:`~pacto_ng.outputs.strain_stress_measures`; e.g. ``E_GL_xx``, ``S_xx`` …, or
      ``strain_*``/``stress_*`` for a linear run), the element means of the element holding
      the centroid, in-plane components ``xx``, ``yy``, ``xy``.

    The mirror image's values are those of the original, vectors reflected (R u) and tensors
    rotated (R T Rᵀ).  A run that stopped on a Newton failure has no equilibrium at its load:
    only ρ̄ and p are given, and ``notes`` says so.
    """
    from ngsolve import GridFunction

    from ..outputs import strain_stress_measures, tensor_components

    mesh, mech = problem.mesh, problem.mech
    half_p = ~part.mirrored_point
    half_c = ~part.mirrored_cell
    cen = part.centroids()
    # a point inside the part next to every vertex: the centroid of one of its elements
    inward = np.empty_like(part.points)
    for k, e in enumerate(part.elements):
        inward[e] = cen[k]
    vp = part.source_point[half_p]  # the half's vertices, in the order of their numbers
    vc = part.source_cell[half_c]
    mp_v = _locate(mesh, part.points[vp], inward[vp])
    mp_c = _locate(mesh, cen[vc], cen[vc])
    R = _reflection(part.line) if part.line is not None else None
    point, cell, notes = {}, {}, []

    def on_points(vals):  # the half's values -> every vertex of the part
        vals = np.asarray(vals, dtype=float).reshape(len(vp), -1)
        out = np.empty((part.n_points, vals.shape[1]))
        out[vp] = vals
        if R is not None and part.mirrored_point.any():
            img = vals[np.searchsorted(vp, part.source_point[part.mirrored_point])]
            out[part.mirrored_point] = img @ R.T if vals.shape[1] == 2 else img
        return out if vals.shape[1] > 1 else out[:, 0]

    def on_cells(vals):
        vals = np.asarray(vals, dtype=float).ravel()
        return vals[part.source_cell]

    def l2(arr):
        gf = GridFunction(mech.l2)
        gf.vec.FV().NumPy()[:] = np.asarray(arr, dtype=float)
        return gf

    vals = problem.values
    for key in ("rho_bar", "rho_bar1", "rho_bar2"):
        if key in vals:
            cell[key] = on_cells(np.asarray(l2(vals[key])(mp_c)).ravel())
    if "p" in vals and problem.pressure_block is not None:
        point["p"] = on_points(np.asarray(problem.pressure_block.gfp(mp_v)).ravel())
    if getattr(problem, "failure", None):
        notes.append("no displacement, strain or stress: the run's own model has no "
                     f"equilibrium on its final design at the full load ({problem.failure})")
        return point, cell, notes
    point["u"] = on_points(np.asarray(mech.gfu(mp_v)).reshape(-1, 2))
    comps = tensor_components(2)
    for name, cf in strain_stress_measures(problem).items():
        T = np.empty((len(vc), 2, 2))
        for (i, j), _ in comps:
            gf = GridFunction(mech.l2)
            gf.Set(cf[i, j])  # element mean (P0 projection), as design.vtu
            T[:, i, j] = np.asarray(gf(mp_c)).ravel()
        T[:, 1, 0] = T[:, 0, 1]
        full = T[part.source_cell]
        if R is not None:
            m = part.mirrored_cell
            full[m] = np.einsum("ij,njk,lk->nil", R, full[m], R)
        for (i, j), comp in comps:
            cell[f"{name}_{comp}"] = full[:, i, j].copy()
    for key, val in {**point, **cell}.items():
        if not np.all(np.isfinite(val)):
            raise ValueError(f"the field {key} on the part has non-finite values")
    return point, cell, notes


def part_polydata(part: PartMesh):
    """The part as a triangulated pyvista surface at z = 0 (m)."""
    import pyvista as pv

    tris = part.triangles()
    faces = np.c_[np.full(len(tris), 3), tris].ravel()
    return pv.PolyData(np.c_[part.points, np.zeros(part.n_points)], faces)


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


def write_part_stl(path, part: PartMesh, thickness: float, *, units: str = "mm",
                   header: str = ""):
    """The part extruded by ``thickness`` (m) as a closed binary STL in ``units``; the
    header states the unit.  Returns the solid (pyvista, in m)."""
    solid = extrude_solid(part_polydata(part), thickness)
    unit = f"units {units}"
    write_binary_stl(path, solid, f"{header}; {unit}" if header else unit, 1.0 / UNITS[units])
    return solid


def write_part_vtu(path, part: PartMesh, *, point_data=None, cell_data=None,
                   units: str = "m", fmt: str = "vtu", E=None):
    """The part's 2D cells with its fields as VTU (or legacy VTK: ``fmt="vtk"``) through
    meshio.  Coordinates and ``u`` in ``units``, every other field as given (SI).  A part of
    named materials other than ``solid`` gets cell data ``material``, ``material_<name>`` and,
    with ``E`` = {name: modulus}, ``E`` (as :func:`write_vtu`)."""
    import meshio

    s = 1.0 / UNITS[units]
    order = part.block_order()
    pdata, cdata = {}, {}
    for key, val in (point_data or {}).items():
        val = np.asarray(val, dtype=float)
        if val.ndim == 2 and val.shape[1] == 2:  # a vector in the plane: a length (u)
            val = np.c_[val * s, np.zeros(len(val))]
        pdata[key] = val
    for key, val in (cell_data or {}).items():
        cdata[key] = [np.asarray(val)[idx] for idx in order]
    names = sorted(part.material_groups, key=lambda n: part.material_groups[n][0])
    if len(names) > 1 or names[0] != "solid":
        cdata["material"] = [part.material[idx] for idx in order]
        for i, n in enumerate(names):
            cdata[f"material_{n}"] = [(part.material[idx] == i + 1).astype(np.int64)
                                      for idx in order]
        if isinstance(E, dict):
            mod = np.array([E[n] for n in names], dtype=float)[part.material - 1]
            cdata["E"] = [mod[idx] for idx in order]
    out = meshio.Mesh(np.c_[part.points * s, np.zeros(part.n_points)], part.blocks(),
                      point_data=pdata, cell_data=cdata)
    with atomic_path(path) as tmp:
        out.write(str(tmp), file_format=fmt)
    return out


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


# ---------------------------------------------------------------------------------------
def _figure(figsize):
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=figsize, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def _framed(lo, hi):
    """A figure and axes sized to the box ``[lo, hi]`` (m), equal aspect, a 3 % margin."""
    aspect = (hi[1] - lo[1]) / max(hi[0] - lo[0], 1e-300)
    fig = _figure((7.0, float(np.clip(5.6 * aspect + 1.4, 3.0, 9.0))))
    ax = fig.add_subplot()
    ax.set_aspect("equal")
    pad = 0.03 * (hi - lo).max()
    ax.set_xlim(lo[0] - pad, hi[0] + pad)
    ax.set_ylim(lo[1] - pad, hi[1] + pad)
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    return fig, ax


def plot_deformed(path, mesh, u, *, title: str | None = None, dpi: int = 150, mirror=True):
    """``deformed.png``: the deformed solid coloured by |u| over the undeformed outline.

    True scale (no magnification), equal axes; the outline is every boundary edge of the
    reference mesh.  ``mirror``: a :class:`~pacto_ng.post.domain.Line` to draw the mirror
    image about too (a part solved on a symmetric half), True for the line of ``mesh``'s own
    straight ``symmetry`` boundary if it has one, False for the half alone.
    """
    from .plots import mirror_line
    from matplotlib.collections import LineCollection
    from matplotlib.tri import Triangulation
    from ngsolve import BND

    pts, blocks = _mesh_arrays(mesh)
    uv = np.asarray(u(mesh(pts[:, 0].copy(), pts[:, 1].copy()))).reshape(-1, 2)
    tris = [b for t, b in blocks if t == "triangle"]
    for t, b in blocks:
        if t == "quad":
            tris.append(np.r_[b[:, [0, 1, 2]], b[:, [0, 2, 3]]])
    tri = np.vstack(tris)
    mag = np.linalg.norm(uv, axis=1)
    line = mirror_line(mesh, mirror)
    # mirrored, the symmetry boundary is inside the whole part: not drawn
    segs = np.array([[mesh[v].point for v in el.vertices] for el in mesh.Elements(BND)
                     if line is None or el.mat != "symmetry"]).reshape(-1, 2, 2)
    def_pts = pts + uv
    if line is not None:  # the mirror image: reflected positions, same |u|
        n = len(pts)
        tri = np.vstack([tri, tri[:, ::-1] + n])
        mag = np.r_[mag, mag]
        segs = np.concatenate([segs, line.reflect(segs)])
        pts = np.vstack([pts, line.reflect(pts)])
        def_pts = np.vstack([def_pts, line.reflect(def_pts)])
    lo = np.minimum(pts.min(axis=0), def_pts.min(axis=0))
    hi = np.maximum(pts.max(axis=0), def_pts.max(axis=0))
    fig, ax = _framed(lo, hi)
    tc = ax.tripcolor(Triangulation(def_pts[:, 0], def_pts[:, 1], tri), mag, shading="gouraud",
                      cmap="viridis")
    ax.add_collection(LineCollection(segs, colors="k", linewidths=0.8, label="undeformed"))
    ax.legend(loc="upper center", bbox_to_anchor=(0.5, -0.14), frameon=False)
    fig.colorbar(tc, ax=ax, label="|u| (m), deformed solid", shrink=0.9)
    ax.set_title(title or "deformed solid (true scale) over the undeformed outline")
    with atomic_path(path) as tmp:
        fig.savefig(str(tmp), dpi=dpi)
    return path


_STYLE = {"expected": ("o", "expected (optimisation)"),
          "fixed": ("s", "fixed pressure (deformation independent)"),
          "follower": ("^", "follower pressure"),
          "darcy": ("D", "Darcy pressure (deformation independent)")}


def plot_sweeps(path, sweeps, *, expected=None, title: str | None = None, dpi: int = 150,
                log: bool = False):
    """``analysis.png``: output displacement Δ against pressure.

    Parameters
    ----------
    sweeps : dict ``kind -> Sweep`` or iterable of Sweep
        Non-converged points are left out.
    expected : tuple ``(pressures, deltas)``, optional
        The displacements the optimisation predicted.
    log : bool
        Logarithmic pressure axis, and logarithmic Δ axis when every plotted Δ is positive.
    """
    fig = _figure((6.5, 4.5))
    ax = fig.add_subplot()
    if expected is not None:
        pe, de = (np.asarray(a, dtype=float) for a in expected)
        m, lab = _STYLE["expected"]
        ax.plot(pe, de, m, ls="none", mfc="none", ms=8, label=lab)
    items = sweeps.values() if isinstance(sweeps, dict) else sweeps
    for sw in items:
        ok = sw.converged.astype(bool)
        m, lab = _STYLE.get(sw.kind, ("x", sw.kind))
        ax.plot(sw.pressures[ok], sw.delta[ok], marker=m, label=lab)
    if log:
        ax.set_xscale("log")
        ys = np.concatenate([ln.get_ydata() for ln in ax.get_lines()] or [np.zeros(0)])
        if ys.size and np.all(ys > 0):
            ax.set_yscale("log")
    ax.set_xlabel("pressure (Pa)")
    ax.set_ylabel("output displacement Δ (m)")
    ax.grid(True, alpha=0.3)
    ax.legend()
    ax.set_title(title or "output displacement against pressure")
    with atomic_path(path) as tmp:
        fig.savefig(str(tmp), dpi=dpi)
    return path


_MATERIAL_COLOURS = {"soft": "#ee8c2c", "stiff": "#2a4fb0"}


def plot_materials(path, mesh, *, title: str | None = None, dpi: int = 150, mirror=True):
    """``materials.png``: the remeshed part's elements coloured by material (soft orange,
    stiff blue, the colours of the run's ``materials.png``), the part's boundary in black and
    the ``interface`` between the materials in red; mirrored like :func:`plot_deformed`."""
    from matplotlib.collections import LineCollection, PolyCollection
    from matplotlib.patches import Patch
    from ngsolve import BND

    from .materials import INTERFACE
    from .plots import mirror_line

    pts, _ = _mesh_arrays(mesh)
    ids, names = material_ids(mesh)
    name_of = {int(v[0]): k for k, v in names.items()}
    polys = [pts[[v.nr - 1 for v in el.vertices]] for el in mesh.ngmesh.Elements2D()]
    colours = [_MATERIAL_COLOURS.get(name_of[i], "0.6") for i in ids]
    outline = np.array([[mesh[v].point for v in el.vertices] for el in mesh.Elements(BND)
                        if el.mat != INTERFACE]).reshape(-1, 2, 2)
    inner = np.array([[mesh[v].point for v in el.vertices] for el in mesh.Elements(BND)
                      if el.mat == INTERFACE]).reshape(-1, 2, 2)
    line = mirror_line(mesh, mirror)
    if line is not None:
        polys = polys + [line.reflect(p) for p in polys]
        colours = colours + colours
        outline = np.concatenate([outline, line.reflect(outline)])
        inner = np.concatenate([inner, line.reflect(inner)])
    allp = np.vstack(polys)
    lo, hi = allp.min(axis=0), allp.max(axis=0)
    fig, ax = _framed(lo, hi)
    ax.add_collection(PolyCollection(polys, facecolors=colours, edgecolors="none"))
    ax.add_collection(LineCollection(outline, colors="k", linewidths=0.8))
    if len(inner):
        ax.add_collection(LineCollection(inner, colors="r", linewidths=0.8))
    handles = [Patch(color=_MATERIAL_COLOURS.get(n, "0.6"), label=n) for n in names]
    if len(inner):
        handles.append(Patch(color="r", label=INTERFACE))
    ax.legend(handles=handles, loc="upper center", bbox_to_anchor=(0.5, -0.14), frameon=False,
              ncol=len(handles))
    ax.set_title(title or "the remeshed part's materials")
    with atomic_path(path) as tmp:
        fig.savefig(str(tmp), dpi=dpi)
    return path

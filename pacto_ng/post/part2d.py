"""The fabricable 2D part of ``pacto export``: the whole mechanism, in the unit asked, with the
run's fields.

* :class:`PartMesh` / :func:`part_mesh` — a 2D part as arrays, the half a case is solved on
  merged with its mirror image about the symmetry line (one vertex on the line, no edge
  inside);
* :func:`part_fields` — the run's final state on it (ρ̄, u, p, strain and stress);
* :func:`write_part_stl` / :func:`write_part_vtu` — the part in the unit asked
  (:data:`~pacto_ng.post.export.UNITS`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..files import atomic_path
from ..measures import strain_stress_measures, tensor_components
from .export import UNITS, extrude_solid, material_ids, mesh_arrays, write_binary_stl


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

    pts, _ = mesh_arrays(mesh)
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
      :func:`~pacto_ng.measures.strain_stress_measures`; e.g. ``E_GL_xx``, ``S_xx`` …, or
      ``strain_*``/``stress_*`` for a linear run), the element means of the element holding
      the centroid, in-plane components ``xx``, ``yy``, ``xy``.

    The mirror image's values are those of the original, vectors reflected (R u) and tensors
    rotated (R T Rᵀ).  A run that stopped on a Newton failure has no equilibrium at its load:
    only ρ̄ and p are given, and ``notes`` says so.
    """
    from ngsolve import GridFunction

    mesh, mech = problem.mesh, problem.mech
    vp, vc, mp_v, mp_c = _sampling_points(mesh, part)
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
        point["p"] = on_points(np.asarray(problem.pressure_block.pressure(mp_v)).ravel())
    if getattr(problem, "failure", None):
        notes.append("no displacement, strain or stress: the run's own model has no "
                     f"equilibrium on its final design at the full load ({problem.failure})")
        return point, cell, notes
    point["u"] = on_points(np.asarray(mech.u(mp_v)).reshape(-1, 2))
    cell.update(_measure_cells(problem, part, mp_c, len(vc), R))
    for key, val in {**point, **cell}.items():
        if not np.all(np.isfinite(val)):
            raise ValueError(f"the field {key} on the part has non-finite values")
    return point, cell, notes


def _sampling_points(mesh, part: PartMesh) -> tuple:
    """``(vp, vc, mp_v, mp_c)``: the half's vertices and cells (in the order of their numbers)
    and the run mesh's points where the fields are read for them: every vertex (moved towards
    an element's centroid where it falls outside by round-off, :func:`_locate`), every cell's
    centroid."""
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
    return vp, vc, mp_v, mp_c


def _measure_cells(problem, part: PartMesh, mp_c, n_half: int, R) -> dict:
    """The run model's strain and stress measures on the part's cells: element means read at
    ``mp_c`` (the ``n_half`` cells of the half), the mirror image's rotated by ``R``; in-plane
    components ``{name}_xx``, ``_yy``, ``_xy``."""
    from ngsolve import GridFunction

    mech, cell = problem.mech, {}
    comps = tensor_components(2)
    for name, cf in strain_stress_measures(problem).items():
        T = np.empty((n_half, 2, 2))
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
    return cell


def part_polydata(part: PartMesh):
    """The part as a triangulated pyvista surface at z = 0 (m)."""
    import pyvista as pv

    tris = part.triangles()
    faces = np.c_[np.full(len(tris), 3), tris].ravel()
    return pv.PolyData(np.c_[part.points, np.zeros(part.n_points)], faces)


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

"""The 3D part remeshed with Netgen tetrahedra, its boundary faces named by position.

:func:`remesh_part` writes the closed surface of :mod:`.part3d` as STL, meshes it with Netgen's
STL geometry (``netgen.stl.STLGeometry(...).GenerateMesh(maxh=...)``: the surface is
remeshed, then the volume; where that fails at every size tried, the surface's own triangles
are kept and Netgen fills the volume, and where the smoothed surface touches itself, the
unsmoothed one's) and names the new mesh's boundary faces by position:

* a face lying on a face of the source mesh that bounds its material region (the outer faces
  and the walls of the passive void regions) takes that face's name (``fixed``,
  ``symmetry_z``, ``inlet``, ``tip``, ...): the case's supports and output ports carry over
  by name;
* **the wetting rule** (as in 2D, :mod:`.remesh`): a face on a source face named in
  ``wet_boundaries`` (the inlet: the fluid is beyond it), or a face inside the source domain
  where the run's final Darcy pressure, sampled one source element size outside the part
  along its outward normal, is at least ``wet_fraction`` P_in, is named ``pressure``;
* the other faces are ``free``;

and the source's named points become the nearest vertices of the part; a clamped named point
(a pin support) only where the part reaches it, within :data:`PIN_REACH` source element sizes.

A two-material part (``stiff_at``, :mod:`.materials`): every tetrahedron of the remesh takes the
material of the nodal ρ̄2 interpolated at its centroid, ``stiff`` (E2) where it reaches the
threshold, else ``soft`` (E1), as the 2D part's element-wise assignment: the interface is a
staircase of tetrahedron faces, at most one remeshed element from the iso-surface
ρ̄2 = threshold2 (``materials`` ``"element-wise"``; a body-fitted interface, as the 2D part's,
would need Netgen to mesh a two-region surface: not done).

The part is analysed by :class:`~.part_analysis.PartAnalysis`, as a 2D part is.
"""
from __future__ import annotations

import json
import subprocess
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from scipy import sparse
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from .boundary import point_sets
from .materials import MATERIALS

PRESSURE, FREE = "pressure", "free"
#: a clamped named point pins the part's piece whose nearest vertex lies within this many
#: source element sizes of it (the smoothed surface moves off the source's corners and edges
#: by a fraction of an element)
PIN_REACH = 0.5


@dataclass
class Remeshed3D:
    """The result of :func:`remesh_part`."""

    mesh: object  # ngsolve.Mesh, material "solid" (or "soft" and "stiff"), boundaries named
    volume: float
    areas: dict  # boundary name -> area
    dropped: int = 0  # tetrahedra of the pieces not joined to the clamp (faces or pins)
    materials: str | None = None  # two materials: how they were assigned ("element-wise")
    ports: dict = field(default_factory=dict)  # named point -> (source position, new vertex)
    maxh: float = 0.0  # the element size Netgen meshed it with (MESH_RETRY)
    surface: str = "remeshed"  # remeshed by Netgen, or "kept" / "unsmoothed" (_netgen_mesh)


def _bounding_faces(source, exclude):
    """The source's surface triangles that bound its material region (not the interfaces
    inside it), as a pyvista PolyData with cell data ``name`` (index into the returned list)."""
    import pyvista as pv

    ngm = source.ngmesh
    mats = source.GetMaterials()
    inside = {0: False}
    inside.update({k + 1: m not in set(exclude) for k, m in enumerate(mats)})
    names, keep = [], {}
    for k in range(ngm.GetNFaceDescriptors()):
        fd = ngm.FaceDescriptor(k + 1)
        if inside.get(fd.domin, False) != inside.get(fd.domout, False):
            name = fd.bcname
            if name not in names:
                names.append(name)
            keep[k + 1] = names.index(name)
    els = ngm.Elements2D().NumPy()
    idx = np.asarray(els["index"], dtype=int)
    mask = np.isin(idx, list(keep))
    tri = np.asarray(els["nodes"], dtype=np.int64)[mask][:, :3] - 1
    pts = np.asarray(ngm.Coordinates(), dtype=float)
    poly = pv.PolyData(pts, np.c_[np.full(len(tri), 3), tri].ravel())
    poly.cell_data["name"] = np.array([keep[i] for i in idx[mask]], dtype=int)
    return poly, names


def _sample(field, source, pts):
    """``field`` (a CF on ``source``) at the points ``pts`` (n, 3); zero outside the mesh."""
    mips = source(pts[:, 0].copy(), pts[:, 1].copy(), pts[:, 2].copy())
    out = np.zeros(len(pts))
    inside = mips["nr"] >= 0
    if inside.any():
        out[inside] = np.asarray(field(mips[inside])).ravel()
    return out


#: Netgen's meshers in a child process: on some surfaces they abort the process (SIGABRT
#: after "Intersecting elements" in the volume mesher, seen on a 40-iteration pa-inverter-3d
#: part), which no exception would catch.  ``stl``: the surface remeshed from its STL, then
#: the volume; ``fill``: the surface's own triangles kept and the volume filled
_MESHER = ("import json, sys\n"
           "import numpy as np\n"
           "from netgen.meshing import Element2D, FaceDescriptor, Mesh, MeshPoint, Pnt\n"
           "from netgen.stl import STLGeometry\n"
           "kind, path, h, out = sys.argv[1], sys.argv[2], float(sys.argv[3]), sys.argv[4]\n"
           "if kind == 'stl':\n"
           "    m = STLGeometry(path).GenerateMesh(maxh=h, **json.loads(sys.argv[5]))\n"
           "else:\n"
           "    data = np.load(path)\n"
           "    m = Mesh(dim=3)\n"
           "    ids = [m.Add(MeshPoint(Pnt(*p))) for p in data['points']]\n"
           "    fd = m.Add(FaceDescriptor(bc=1, domin=1, domout=0, surfnr=1))\n"
           "    for t in data['triangles']:\n"
           "        m.Add(Element2D(fd, [ids[i] for i in t]))\n"
           "    m.GenerateVolumeMesh(maxh=h)\n"
           "sys.exit(3) if m.ne == 0 else m.Save(out)\n")


#: the element sizes (fractions of the requested one) and Netgen's meshing options tried in
#: turn when its mesher crashes on a part's surface: the same size with a gentler grading
#: (default 0.3) or more of the surface's ridges taken as edges (``yangle``, default 30°),
#: then finer sizes, which resolve a thin wall it could not close.  Netgen's crashes depend
#: on the options as erratically as on the size: on the part of a `pacto run pneunet-3d
#: --model neohookean` (2026-12-07), the defaults crashed at maxh 2.3, 2.4 and 2.5 mm (meshed
#: at 2.6 mm), grading 0.2 and yangle 10° each meshed at 2.2, 2.3, 2.4, 2.5 and 2.7 mm
#: (14,895 and 16,607 tetrahedra at 2.5 mm), where the finer 1.75 mm gave 27,157
MESH_RETRY = ((1.0, {}), (1.0, {"grading": 0.2}), (1.0, {"yangle": 10.0}), (0.7, {}), (0.5, {}))
#: why a try of the mesher was stopped (its time limit)
TOOK_LONGER = "it took longer than"


def _netgen_mesh(surface, maxh: float, timeout: float, unsmoothed=None):
    """The Netgen tetrahedral mesh of the closed, outward-oriented ``surface``, the element
    size that gave it and how its surface was made: its STL remeshed at ``maxh``, or after a
    crash of the mesher with the next size and options of :data:`MESH_RETRY`
    (``"remeshed"``); when every try fails (thin walls of one or two source elements, seen
    on pneunet-3d parts), the
    surface's own triangles kept and the volume filled at ``maxh`` (``"kept"``), and where
    the smoothing made the surface touch itself, the same with the ``unsmoothed`` surface
    (the clipped cells' boundary: ``"unsmoothed"``).  A try that takes longer than
    ``timeout`` s is stopped; after an STL try stopped so, the surface is filled at once (a
    finer size would take longer still).  ValueError when every try fails."""
    with tempfile.TemporaryDirectory() as tmp:
        stl, vol = Path(tmp) / "part.stl", Path(tmp) / "part.vol"
        surf = surface.copy()
        surf.clear_data()
        surf.save(str(stl), binary=True)
        tried = []
        for h, options in ((f * maxh, options) for f, options in MESH_RETRY):
            why = _mesh_child("stl", stl, h, vol, timeout, options)
            if not isinstance(why, str):
                return why, h, "remeshed"
            tried.append(f"{h:.3g}{''.join(f' {k} {v:g}' for k, v in options.items())}: {why}")
            if why.startswith(TOOK_LONGER):
                break
        for how, surf in (("kept", surface), ("unsmoothed", unsmoothed)):
            if surf is None:
                continue
            triangles = Path(tmp) / "part.npz"
            np.savez(triangles, points=np.asarray(surf.points, dtype=float),
                     triangles=np.asarray(surf.faces).reshape(-1, 4)[:, 1:])
            why = _mesh_child("fill", triangles, maxh, vol, timeout)
            if not isinstance(why, str):
                return why, maxh, how
            tried.append(f"the {how} surface filled, {maxh:.3g}: {why}")
    raise ValueError(f"Netgen could not mesh the part (maxh {'; '.join(tried)}; a thin or "
                     f"self-touching part: try another --maxh or --threshold)")


def _mesh_child(kind: str, source: Path, maxh: float, vol: Path, timeout: float,
                options: dict | None = None):
    """One try of the child-process mesher (``kind`` ``stl`` or ``fill``, :data:`_MESHER`;
    ``options``: Netgen's meshing options of an STL try): the Netgen mesh, or why it failed
    (a string, :data:`TOOK_LONGER` ... after ``timeout`` s)."""
    from netgen.meshing import Mesh as NGMesh

    try:
        proc = subprocess.run([sys.executable, "-c", _MESHER, kind, str(source),
                               repr(float(maxh)), str(vol), json.dumps(options or {})],
                              capture_output=True, timeout=timeout)
    except subprocess.TimeoutExpired:
        return f"{TOOK_LONGER} {timeout:g} s"
    if proc.returncode != 0 or not vol.is_file():
        return ("no tetrahedra" if proc.returncode == 3 else
                f"its mesher stopped with exit code {proc.returncode}")
    gen = NGMesh()
    gen.Load(str(vol))
    vol.unlink()
    return gen


_TET_FACES = np.array([[0, 1, 2], [0, 1, 3], [0, 2, 3], [1, 2, 3]])


def _face_keys(cells, n: int) -> np.ndarray:
    """One integer per triangle (rows of 3 point ids) or per face of every tetrahedron (rows
    of 4, four keys each, in order), independent of the vertex order."""
    cells = np.asarray(cells, dtype=np.int64)
    f = np.sort(cells[:, _TET_FACES] if cells.shape[1] == 4 else cells[:, None, :], axis=2)
    return ((f[..., 0] * n + f[..., 1]) * n + f[..., 2]).ravel()


def _clamped_components(tets, clamp_tris, n: int, pinned=()) -> np.ndarray:
    """Mask of the tetrahedra in a face-connected component that holds one of the boundary
    triangles ``clamp_tris`` or one of the point ids ``pinned`` (``n`` points)."""
    keys = _face_keys(tets, n)
    owner = np.repeat(np.arange(len(tets)), 4)
    order = np.argsort(keys, kind="stable")
    k, o = keys[order], owner[order]
    same = k[1:] == k[:-1]
    g = sparse.coo_matrix((np.ones(same.sum()), (o[:-1][same], o[1:][same])),
                          shape=(len(tets), len(tets)))
    _, comp = connected_components(g, directed=False)
    at = np.searchsorted(k, _face_keys(clamp_tris, n))
    held = comp[o[at[at < len(k)]]]
    pins = np.isin(tets, np.asarray(pinned, dtype=np.int64)).any(axis=1)
    return np.isin(comp, np.concatenate([held, comp[pins]]))


def _pins(pts, source, clamp, reach: float) -> dict:
    """The clamped named points of ``source`` the part reaches: name -> ids of the nearest
    points of ``pts`` within ``reach`` (each once)."""
    out, tree = {}, cKDTree(pts)
    for name, points in point_sets(source).items():
        if name in clamp:
            d, near = tree.query(points)
            ids = np.unique(near[d <= reach])
            if ids.size:
                out[name] = ids
    return out


def _add_points(new, pts, source, clamp, pins) -> dict:
    """Add the source's named points to the Netgen mesh ``new`` (points ``pts``): a clamped
    one where the part reaches it (``pins``, :func:`_pins`), any other (a port) on the
    nearest vertex of the part; ``{name: (source position, vertex position)}``."""
    from netgen.meshing import Element0D

    ports = {}
    for name, points in point_sets(source).items():
        if name in clamp:
            at = pins.get(name, np.zeros(0, int))
        else:
            at = np.array([np.argmin(np.linalg.norm(pts - points[0], axis=1))])
        if at.size:
            index = new.AddRegion(name, dim=0)
            for k in at:
                new.Add(Element0D(int(k) + 1, index=index))
            ports[name] = (tuple(map(float, points[0])), tuple(map(float, pts[at[0]])))
    return ports


def _face_names(pts, tris, tets, source, h_source, *, exclude, wet_boundaries, pressure,
                p_in, wet_fraction, probe):
    """``(label, area)`` of the boundary triangles ``tris`` of the tetrahedra ``tets``: each
    the name of the source face it lies on (within 1e-4 ``h_source``), else ``free``, and
    ``pressure`` where the wetting rule holds (the module docstring); and their areas."""
    # outward normals (a triangle against the fourth vertex of its tetrahedron)
    a, b, c = pts[tris[:, 0]], pts[tris[:, 1]], pts[tris[:, 2]]
    cen = (a + b + c) / 3.0
    nrm = np.cross(b - a, c - a)
    area = 0.5 * np.linalg.norm(nrm, axis=1)
    nrm /= np.maximum(2.0 * area[:, None], 1e-300)
    faces = {tuple(sorted(f)): t for t, tet in enumerate(tets)
             for f in (tet[[0, 1, 2]], tet[[0, 1, 3]], tet[[0, 2, 3]], tet[[1, 2, 3]])}
    # a triangle that bounds no tetrahedron (Netgen may leave one where the surface folds onto
    # itself) keeps its own orientation; remesh_part drops it with the faces of no kept piece
    opp = np.array([np.setdiff1d(tets[faces[key]], t)[0] if (key := tuple(sorted(t))) in faces
                    else t[0] for t in tris])
    nrm *= np.where(np.einsum("ij,ij->i", nrm, cen - pts[opp]) > 0, 1.0, -1.0)[:, None]
    # names by position
    bnd, names = _bounding_faces(source, exclude)
    tol = 1e-4 * h_source
    cell, closest = bnd.find_closest_cell(cen, return_closest_point=True)
    dist = np.linalg.norm(closest - cen, axis=1)
    label = np.array([names[i] for i in np.asarray(bnd.cell_data["name"])[cell]], dtype=object)
    label[dist > tol] = FREE
    wet = np.isin(label, list(wet_boundaries))
    if pressure is not None:
        p_in = p_in if p_in is not None else float(np.max(pressure.vec.FV().NumPy()))
        step = h_source if probe is None else float(probe)
        inner = dist > tol
        wet |= inner & (_sample(pressure, source, cen + step * nrm) >= wet_fraction * p_in)
    label[wet] = PRESSURE
    return label, area


def remesh_part(surface, source, maxh: float, h_source: float, *, clamp=(), exclude=(),
                wet_boundaries=(), pressure=None, p_in: float | None = None,
                wet_fraction: float = 0.5, probe: float | None = None,
                timeout: float = 300.0, stiff_at=None, unsmoothed=None) -> Remeshed3D:
    """Mesh the closed ``surface`` (pyvista PolyData) with Netgen tetrahedra of ``maxh`` and
    name its boundary faces (see the module docstring; ``h_source`` is the source mesh's
    element size: the wetting rule's probe distance by default, and 1e-4 of it the distance
    within which a face lies on a source face).  Only the pieces joined through faces to a
    face on ``clamp`` are kept.  ``stiff_at``: a two-material part's rule, points (n, 3) ->
    whether the stiff material is there (the tetrahedra's centroids are asked; see the
    module docstring).  ``unsmoothed``: the surface before smoothing, Netgen's last resort
    (:func:`_netgen_mesh`).  ValueError when Netgen fails (or takes longer than ``timeout`` s) or
    no face lies on the clamp."""
    import ngsolve
    from netgen.meshing import FaceDescriptor, Mesh as NGMesh

    gen, meshed_at, surface_kind = _netgen_mesh(surface, maxh, timeout, unsmoothed)
    pts = np.asarray(gen.Coordinates(), dtype=float)
    tris = np.asarray(gen.Elements2D().NumPy()["nodes"], dtype=np.int64)[:, :3] - 1
    tets = np.asarray(gen.Elements3D().NumPy()["nodes"], dtype=np.int64)[:, :4] - 1
    label, area = _face_names(pts, tris, tets, source, h_source, exclude=exclude,
                              wet_boundaries=wet_boundaries, pressure=pressure, p_in=p_in,
                              wet_fraction=wet_fraction, probe=probe)
    # pieces joined to the clamp through faces only (a piece hanging on a vertex or an edge
    # of another is a mechanism), or pinned at a clamped point: the tetrahedra's
    # face-connected components
    pins = _pins(pts, source, clamp, PIN_REACH * h_source)
    keep_tet = _clamped_components(tets, tris[np.isin(label, list(clamp))], len(pts),
                                   np.concatenate([np.zeros(0, int), *pins.values()]))
    if not keep_tet.any():
        raise ValueError(f"no face or point of the remeshed part lies on the clamp "
                         f"({', '.join(clamp)})")
    used = np.isin(_face_keys(tris, len(pts)), _face_keys(tets[keep_tet], len(pts)))
    dropped = int(np.count_nonzero(~keep_tet))
    tets, tris, label, area = tets[keep_tet], tris[used], label[used], area[used]
    ids, inverse = np.unique(tets, return_inverse=True)
    pts, tets = pts[ids], inverse.reshape(tets.shape)
    tris = np.searchsorted(ids, tris)
    pins = {name: np.searchsorted(ids, k[np.isin(k, ids)]) for name, k in pins.items()}
    # the materials: one, or each tetrahedron's by stiff_at at its centroid
    region = np.zeros(len(tets), dtype=int)
    mats = ("solid",)
    if stiff_at is not None:
        mats = MATERIALS
        region = np.asarray(stiff_at(pts[tets].mean(axis=1)), dtype=bool).astype(int)
    # the new mesh: the kept points and tetrahedra, a face descriptor per name and material
    new = NGMesh(dim=3)
    new.AddPoints(pts)
    for k, mat in enumerate(mats):
        new.SetMaterial(k + 1, mat)
        if np.any(region == k):
            new.AddElements(dim=3, index=k + 1, data=tets[region == k], base=0)
    # each boundary triangle's material: its tetrahedron's (the one face with its key)
    side = np.zeros(len(tris), dtype=int)
    if stiff_at is not None:
        keys = _face_keys(tets, len(pts))
        order = np.argsort(keys, kind="stable")
        at = np.searchsorted(keys[order], _face_keys(tris, len(pts)))
        side = np.repeat(region, 4)[order][at]
    areas, fd = {}, 0
    for name in sorted(set(label)):
        sel = label == name
        areas[name] = float(area[sel].sum())
        for k in np.unique(side[sel]):
            fd += 1
            new.Add(FaceDescriptor(bc=fd, domin=int(k) + 1, domout=0, surfnr=fd))
            new.SetBCName(fd - 1, name)
            new.AddElements(dim=2, index=fd, data=tris[sel & (side == k)], base=0)
    ports = _add_points(new, pts, source, clamp, pins)
    mesh = ngsolve.Mesh(new)
    return Remeshed3D(mesh, float(ngsolve.Integrate(1.0, mesh)), areas, dropped,
                      None if stiff_at is None else "element-wise", ports, meshed_at,
                      surface_kind)

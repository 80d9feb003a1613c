"""A fresh Netgen mesh of a moved part: its boundary as it stands, meshed anew.

When the refinement's mesh motion would fold elements (:func:`~pacto_ng.shape.riesz.
step_length` finds no admissible step), the part is remeshed and the refinement goes on
from the new mesh; the refined part's output is also checked on an independent remesh of
its final shape.  The geometry of the new mesh is the moved mesh's own boundary: each
boundary segment (its two vertices at their moved positions) becomes a straight segment of
a Netgen ``SplineGeometry`` with the segment's boundary name, and with the materials on its
two sides as the geometry's domains (the solid on the left of a segment is its left domain;
a segment between two materials, e.g. the ``interface`` of a two-material part, has both).
The shape is therefore kept (the moved part is a polygon: the shape space is of order 1),
but for segments that the motion has shrunk below :data:`SHORT` times ``maxh`` on a nearly
straight stretch, which are joined to their neighbour (:func:`_join_short`); so are the
boundary names, the materials and the named points: every named point of the old mesh (an
output port) is a vertex of the geometry, named again in the new mesh.  Netgen meshes the polygon with triangles of size at most ``maxh`` (segments shorter
than ``maxh`` are kept as they are: the mesh is as fine as the boundary's resolution where
that is finer).

In 3D the moved boundary triangles themselves are kept (their names, and the materials on
their two sides as the inner and outer domain of their face descriptors) and Netgen fills
the volume anew (``GenerateVolumeMesh`` at ``maxh``): the interior elements, which the
motion squeezes, are new; a squeezed surface triangle stays as it is (no surface geometry
to remesh it on).
"""
from __future__ import annotations

import math

import numpy as np
import ngsolve
from scipy.spatial import cKDTree
from netgen.geom2d import SplineGeometry
from netgen.libngpy._meshing import NgException
from netgen.meshing import Element0D, Element2D, Element3D, FaceDescriptor, MeshPoint, Pnt
from netgen.meshing import Mesh as NgMesh
from ngsolve import BBBND, BBND, BND, VOL

from .thickness import ray_triangle

#: the name Netgen gives a geometry's points that have none
UNNAMED = "default"
#: a boundary segment of a moved 2D part shorter than this share of ``maxh`` is joined to
#: its neighbour when remeshing (:func:`_join_short`)
SHORT = 0.3
#: ... where the boundary turns by less than this (radians: 20°)
STRAIGHT = math.radians(20.0)


def remesh_moved(mesh, points, maxh: float):
    """A new NGSolve mesh of the part ``mesh`` with its vertices at ``points`` ((nv, dim),
    e.g. :meth:`~pacto_ng.shape.deformation.ShapeSpace.moved_points`), meshed at ``maxh``
    (see the module: 2D anew from the boundary polygon, 3D a new interior for the same
    surface triangles).  ValueError (one line) when Netgen fails."""
    dim = mesh.dim
    points = np.asarray(points, dtype=float)[:, :dim]
    if points.shape != (mesh.nv, dim) or not np.all(np.isfinite(points)):
        raise ValueError(f"remesh: {points.shape} points for a mesh of {mesh.nv} vertices")
    materials = list(dict.fromkeys(mesh.GetMaterials()))
    try:
        ngm = (_polygon if dim == 2 else _surface)(mesh, points, materials, float(maxh))
    except NgException as err:
        raise ValueError(f"remesh: Netgen could not mesh the moved part: {err}") from None
    _name_points(ngm, mesh, points)
    new = ngsolve.Mesh(ngm)
    if new.ne == 0:
        raise ValueError("remesh: Netgen left the moved part without elements")
    return new


def _polygon(mesh, points, materials, maxh: float):
    """The Netgen mesh of a moved 2D part: its boundary polygon as a ``SplineGeometry``, its
    short segments joined (:func:`_join_short`)."""
    sides = _join_short(_sides(mesh, points, materials), points, _named(mesh),
                        SHORT * maxh)
    geo = SplineGeometry()
    index = {}
    for v in sorted({v for (a, b), _ in sides.items() for v in (a, b)}):
        index[v] = geo.AppendPoint(float(points[v, 0]), float(points[v, 1]))
    for (a, b), (left, right, name) in sides.items():
        geo.Append(["line", index[a], index[b]], leftdomain=left, rightdomain=right, bc=name)
    for k, name in enumerate(materials):
        geo.SetMaterial(k + 1, name)
    return geo.GenerateMesh(maxh=maxh)


def _named(mesh) -> set:
    """The vertices of ``mesh``'s named points (not Netgen's unnamed ``default`` ones)."""
    kind = BBND if mesh.dim == 2 else BBBND
    return {el.vertices[0].nr for el in mesh.Elements(kind) if el.mat != UNNAMED}


def _join_short(sides: dict, points, keep: set, short: float) -> dict:
    """``sides`` with each vertex between two segments of the same boundary and materials
    removed (the two segments joined) where one of them is shorter than ``short`` and the
    boundary turns there by less than :data:`STRAIGHT` radians, shortest first; the
    vertices in ``keep`` (named points) stay.  A moved boundary's segments shrink where the
    motion compresses it, and a remesh that kept them would keep elements far smaller than
    ``maxh`` there, whose motion the step control then bounds to a few per cent of ``maxh``
    (measured on mm-gripper: every step after the third remesh stopped for quality on a
    fresh mesh).  Joining moves the boundary by at most the sagitta of the removed vertex."""
    sides = dict(sides)
    while True:
        into, out = {}, {}
        for (a, b) in sides:
            into.setdefault(b, []).append(a)
            out.setdefault(a, []).append(b)
        best = None
        for v, (ins, outs) in ((v, (into.get(v, []), out.get(v, []))) for v in into):
            if v in keep or len(ins) != 1 or len(outs) != 1:
                continue
            u, w = ins[0], outs[0]
            if u == w or sides[(u, v)] != sides[(v, w)] or (u, w) in sides:
                continue
            e1, e2 = points[v] - points[u], points[w] - points[v]
            n1, n2 = float(np.hypot(*e1)), float(np.hypot(*e2))
            turn = abs(math.atan2(e1[0] * e2[1] - e1[1] * e2[0], float(e1 @ e2)))
            if min(n1, n2) < short and turn < STRAIGHT and (best is None
                                                           or min(n1, n2) < best[0]):
                best = (min(n1, n2), u, v, w)
        if best is None:
            return sides
        _, u, v, w = best
        sides[(u, w)] = sides.pop((u, v))
        del sides[(v, w)]


def _surface(mesh, points, materials, maxh: float):
    """The Netgen mesh of a moved 3D part: its boundary triangles kept as they are (their
    names, and the materials on their two sides as the face's inner and outer domain; each
    triangle oriented from its inner to its outer domain), the volume meshed anew
    (``GenerateVolumeMesh``)."""
    faces = _faces(mesh, points, materials)
    ngm = NgMesh(dim=3)
    index = {v: ngm.Add(MeshPoint(Pnt(*points[v])))
             for v in sorted({v for tri, _ in faces for v in tri})}
    descriptors = {}
    for tri, (inner, outer, name) in faces:
        key = (inner, outer, name)
        if key not in descriptors:
            descriptors[key] = ngm.Add(FaceDescriptor(bc=len(descriptors) + 1, domin=inner,
                                                      domout=outer,
                                                      surfnr=len(descriptors) + 1))
            ngm.SetBCName(len(descriptors) - 1, name)
        ngm.Add(Element2D(descriptors[key], [index[v] for v in tri]))
    for k, name in enumerate(materials):
        ngm.SetMaterial(k + 1, name)
    ngm.GenerateVolumeMesh(maxh=maxh)
    return ngm


def _faces(mesh, points, materials) -> list:
    """``[(triangle, (inner domain, outer domain, boundary name))]`` for every boundary
    triangle of a 3D ``mesh``, its vertices ordered so that its normal points from the inner
    domain to the outer one (domains 1-based in ``materials``, 0 for none), judged at the
    moved ``points``."""
    neighbours = {}
    for el in mesh.Elements(VOL):
        vs = [v.nr for v in el.vertices]
        centroid = points[vs].mean(axis=0)
        for face in ((0, 1, 2), (0, 1, 3), (0, 2, 3), (1, 2, 3)):
            key = tuple(sorted(vs[i] for i in face))
            neighbours.setdefault(key, []).append((centroid, materials.index(el.mat) + 1))
    out = []
    for el in mesh.Elements(BND):
        tri = [v.nr for v in el.vertices]
        sides = neighbours.get(tuple(sorted(tri)), ())
        if not sides:
            raise ValueError(f"remesh: boundary triangle {tri} borders no element")
        normal = np.cross(points[tri[1]] - points[tri[0]], points[tri[2]] - points[tri[0]])
        centroid, inner = sides[0]
        if np.dot(normal, centroid - points[tri[0]]) > 0:  # the normal points into it
            tri = [tri[0], tri[2], tri[1]]
        outer = sides[1][1] if len(sides) > 1 else 0
        out.append((tri, (inner, outer, el.mat)))
    return out


def _sides(mesh, points, materials) -> dict:
    """``{(a, b): (left domain, right domain, boundary name)}`` for every boundary segment of
    ``mesh``, oriented by its vertices ``a → b`` (domain numbers 1-based in ``materials``, 0
    for none), the sides judged at the moved ``points``."""
    neighbours = {}
    for el in mesh.Elements(VOL):
        vs = [v.nr for v in el.vertices]
        centroid = points[vs].mean(axis=0)
        for i in range(len(vs)):
            key = tuple(sorted((vs[i], vs[(i + 1) % len(vs)])))
            neighbours.setdefault(key, []).append((centroid, materials.index(el.mat) + 1))
    sides = {}
    for el in mesh.Elements(BND):
        a, b = (v.nr for v in el.vertices)
        tangent = points[b] - points[a]
        left = right = 0
        for centroid, domain in neighbours.get(tuple(sorted((a, b))), ()):
            offset = centroid - points[a]
            if tangent[0] * offset[1] - tangent[1] * offset[0] > 0:
                left = domain
            else:
                right = domain
        if left == 0 and right == 0:
            raise ValueError(f"remesh: boundary segment {a}-{b} borders no element")
        sides[(a, b)] = (left, right, el.mat)
    return sides


def _name_points(ngm, mesh, points) -> None:
    """Every named point of ``mesh`` (its point elements, BBND in 2D and BBBND in 3D, but
    Netgen's unnamed ``default`` ones) as a point element of ``ngm`` at the new vertex
    nearest to the point's moved position (a vertex of the old boundary: the same place)."""
    dim = mesh.dim
    coords = np.array([p.p for p in ngm.Points()], dtype=float)[:, :dim]
    regions = {}
    for el in mesh.Elements(BBND if dim == 2 else BBBND):
        if el.mat == UNNAMED:
            continue
        v = el.vertices[0].nr
        k = int(np.argmin(np.linalg.norm(coords - points[v], axis=1)))
        if el.mat not in regions:
            regions[el.mat] = ngm.AddRegion(el.mat, dim=0)
        ngm.Add(Element0D(k + 1, index=regions[el.mat]))


#: 3D: a segment within this share of the lengths of a triangle's edges, or this close to its
#: plane in angle, touches it rather than passing through it (:func:`_edges_through`)
TOUCH = 1e-6


def crossing_walls(mesh, points) -> int:
    """How many pairs of boundary facets of ``mesh`` (segments in 2D, triangles in 3D) cross
    each other with its vertices at ``points`` (facets sharing a vertex are not counted): 0
    for a valid part.  Moving the mesh keeps each element unfolded, but two walls facing each
    other across a void (a chamber, a slot) have no element between them and can pass through
    each other; such a shape is no part (and Netgen cannot mesh it).  The candidates are the
    pairs whose centres lie within twice the largest distance from a facet's centre to its
    vertices (two crossing facets always do: scipy's ``cKDTree.query_pairs``); in 2D each is
    tested by orientation (each one's ends on opposite sides of the other's line), in 3D by
    whether an edge of one passes through the other (:func:`_edges_through`)."""
    ends = np.array([[v.nr for v in el.vertices] for el in mesh.Elements(BND)])
    if mesh.dim == 3:
        return _crossing_triangles(ends, np.asarray(points, dtype=float)[:, :3])
    p = np.asarray(points, dtype=float)[:, :2]
    a, b = p[ends[:, 0]], p[ends[:, 1]]
    reach = float(np.max(np.linalg.norm(b - a, axis=1)))
    pairs = cKDTree(0.5 * (a + b)).query_pairs(reach, output_type="ndarray")
    if len(pairs) == 0:
        return 0
    i, j = pairs[:, 0], pairs[:, 1]
    share = (ends[i, :, None] == ends[j, None, :]).any(axis=(1, 2))
    cross = ((_side(a[i], b[i], a[j]) * _side(a[i], b[i], b[j]) < 0)
             & (_side(a[j], b[j], a[i]) * _side(a[j], b[j], b[i]) < 0) & ~share)
    return int(np.count_nonzero(cross))


def _crossing_triangles(triangles, p) -> int:
    """:func:`crossing_walls` of the boundary ``triangles`` (vertex numbers) at the points
    ``p``: two triangles that share no vertex cross when an edge of one passes through the
    other."""
    v = p[triangles]
    centre = v.mean(axis=1)
    reach = 2.0 * float(np.max(np.linalg.norm(v - centre[:, None, :], axis=2)))
    pairs = cKDTree(centre).query_pairs(reach, output_type="ndarray")
    if len(pairs) == 0:
        return 0
    share = (triangles[pairs[:, 0], :, None] == triangles[pairs[:, 1], None, :]).any(axis=(1, 2))
    i, j = pairs[~share, 0], pairs[~share, 1]
    cross = np.zeros(len(i), dtype=bool)
    for a, b in ((i, j), (j, i)):
        for k in range(3):
            cross |= _edges_through(v[a, k], v[a, (k + 1) % 3], v[b])
    return int(np.count_nonzero(cross))


def _edges_through(p0, p1, tri) -> np.ndarray:
    """Whether each segment ``p0 → p1`` passes through its triangle ``tri`` (``(n, 3, 3)``):
    :func:`~pacto_ng.shape.thickness.ray_triangle` with the ray's parameter and the
    barycentric coordinates strictly inside, to :data:`TOUCH` (a segment that only touches
    the triangle, at its edge or in its plane, as two faces meeting at an edge of the part
    do, does not pass through it)."""
    d, e1, e2 = p1 - p0, tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]
    t, u, w, det = ray_triangle(p0, d, tri[:, 0], e1, e2)
    scale = (np.linalg.norm(d, axis=1) * np.linalg.norm(e1, axis=1)
             * np.linalg.norm(e2, axis=1))
    with np.errstate(invalid="ignore"):
        return ((np.abs(det) > TOUCH * scale) & (u > TOUCH) & (w > TOUCH)
                & (u + w < 1 - TOUCH) & (t > TOUCH) & (t < 1 - TOUCH))


def _side(a, b, c):
    """The orientation of ``c`` about the line ``a → b`` (positive on its left)."""
    return ((b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1])
            - (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0]))


def moved_field(mesh, points, field):
    """The vertex values of the vector GridFunction ``field`` on ``mesh`` as a piecewise
    linear field on the moved part itself: a GridFunction on a copy of ``mesh`` whose
    vertices are at ``points`` (same elements).  A GridFunction of another mesh can then be
    set from it (NGSolve locates the points), e.g. a remeshed part's displacement from the
    last one, where setting from ``field`` directly would locate the points on ``mesh``'s
    reference, not its moved, positions.  The vertex values are the field's first
    coefficients of each component (H1's vertex dofs: their nodal values)."""
    dim, nv = mesh.dim, mesh.nv
    copy = NgMesh(dim=dim)
    index = [copy.Add(MeshPoint(Pnt(*np.r_[points[v], [0.0] * (3 - dim)])))
             for v in range(nv)]
    copy.Add(FaceDescriptor(bc=1, domin=1, domout=0, surfnr=1))
    kind = Element2D if dim == 2 else Element3D
    for el in mesh.Elements(VOL):
        copy.Add(kind(1, [index[v.nr] for v in el.vertices]))
    copy.SetMaterial(1, "copy")
    moved = ngsolve.Mesh(copy)
    out = ngsolve.GridFunction(ngsolve.VectorH1(moved, order=1))
    values = np.asarray(field.vec.FV().NumPy()).reshape(dim, -1)[:, :nv]
    out.vec.FV().NumPy()[:] = values.ravel()
    return out

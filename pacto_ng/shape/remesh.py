"""A fresh Netgen mesh of a moved 2D part: its boundary as it stands, meshed anew.

When the refinement's mesh motion would fold elements (:func:`~pacto_ng.shape.riesz.
step_length` finds no admissible step), the part is remeshed and the refinement goes on
from the new mesh; the refined part's output is also checked on an independent remesh of
its final shape.  The geometry of the new mesh is the moved mesh's own boundary: each
boundary segment (its two vertices at their moved positions) becomes a straight segment of
a Netgen ``SplineGeometry`` with the segment's boundary name, and with the materials on its
two sides as the geometry's domains (the solid on the left of a segment is its left domain;
a segment between two materials, e.g. the ``interface`` of a two-material part, has both).
The shape is therefore kept exactly (the moved part is a polygon: the shape space is of
order 1), and so are the boundary names, the materials and the named points: every named
point of the old mesh (an output port) is a vertex of the geometry, named again in the new
mesh.  Netgen meshes the polygon with triangles of size at most ``maxh`` (segments shorter
than ``maxh`` are kept as they are: the mesh is as fine as the boundary's resolution where
that is finer).
"""
from __future__ import annotations

import numpy as np
import ngsolve
from netgen.geom2d import SplineGeometry
from netgen.libngpy._meshing import NgException
from netgen.meshing import Element0D
from ngsolve import BBND, BND, VOL

#: the name Netgen gives a geometry's points that have none
UNNAMED = "default"


def remesh_moved(mesh, points, maxh: float):
    """A new NGSolve mesh of the 2D part ``mesh`` with its vertices at ``points`` ((nv, 2),
    e.g. :meth:`~pacto_ng.shape.deformation.ShapeSpace.moved_points`), meshed at ``maxh``
    (see the module).  ValueError (one line) for a 3D mesh or when Netgen fails."""
    if mesh.dim != 2:
        raise ValueError("remesh: only 2D parts are remeshed")
    points = np.asarray(points, dtype=float)[:, :2]
    if points.shape != (mesh.nv, 2) or not np.all(np.isfinite(points)):
        raise ValueError(f"remesh: {points.shape} points for a mesh of {mesh.nv} vertices")
    materials = list(dict.fromkeys(mesh.GetMaterials()))
    sides = _sides(mesh, points, materials)
    geo = SplineGeometry()
    index = {}
    for v in sorted({v for (a, b), _ in sides.items() for v in (a, b)}):
        index[v] = geo.AppendPoint(float(points[v, 0]), float(points[v, 1]))
    for (a, b), (left, right, name) in sides.items():
        geo.Append(["line", index[a], index[b]], leftdomain=left, rightdomain=right, bc=name)
    for k, name in enumerate(materials):
        geo.SetMaterial(k + 1, name)
    try:
        ngm = geo.GenerateMesh(maxh=float(maxh))
    except NgException as err:
        raise ValueError(f"remesh: Netgen could not mesh the moved part: {err}") from None
    _name_points(ngm, mesh, points)
    new = ngsolve.Mesh(ngm)
    if new.ne == 0:
        raise ValueError("remesh: Netgen left the moved part without triangles")
    return new


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
    """Every named point of ``mesh`` (its BBND elements but Netgen's unnamed ``default``
    ones) as a point element of ``ngm`` at the new vertex nearest to the point's moved
    position (a geometry vertex: the same place)."""
    coords = np.array([p.p for p in ngm.Points()], dtype=float)[:, :2]
    regions = {}
    for el in mesh.Elements(BBND):
        if el.mat == UNNAMED:
            continue
        v = el.vertices[0].nr
        k = int(np.argmin(np.hypot(*(coords - points[v]).T)))
        if el.mat not in regions:
            regions[el.mat] = ngm.AddRegion(el.mat, dim=0)
        ngm.Add(Element0D(k + 1, index=regions[el.mat]))

"""The optimisation mesh's outer boundary and named points, as the part takes them over.

:func:`outer_boundary` gives the edges that belong to one element only, with the names of the
boundaries they lie on (:data:`FREE` where the mesh names none); a :class:`BoundaryLocator`
answers which of those named edges a point lies on (how a traced polygon's edges and the new
mesh's boundary segments get their names); :func:`point_sets` and :func:`named_points` give
the named points (the supports' pins, the output ports); :func:`segment_distance` measures a
point's distance from segments.
"""
from __future__ import annotations

import numpy as np

from .grid import included_elements

#: the name of a boundary that lies on no named boundary of the source mesh
FREE = "free"


def outer_boundary(mesh, exclude=()):
    """The outer boundary edges of a 2D NGSolve mesh and their names.

    With ``exclude`` (material names) the elements of those materials are left out: the
    boundary is that of the remaining elements, and an edge between a kept and an excluded
    element carries the name of the mesh's boundary element there (an interface name such
    as ``inlet``) or :data:`FREE`.

    Returns
    -------
    segments : ndarray, shape (m, 2, 2)
        End points of every edge that belongs to exactly one element.
    names : list of str
        The boundary name of each edge (:data:`FREE` when the mesh has no boundary element there).
    """
    from ngsolve import BND

    pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    keep = included_elements(mesh, exclude)
    count: dict[tuple[int, int], int] = {}
    for k, el in enumerate(mesh.ngmesh.Elements2D()):
        if keep is not None and not keep[k]:
            continue
        vs = [v.nr - 1 for v in el.vertices]
        for a, b in zip(vs, vs[1:] + vs[:1]):
            key = (min(a, b), max(a, b))
            count[key] = count.get(key, 0) + 1
    named = {}
    for el in mesh.Elements(BND):
        vs = sorted(v.nr for v in el.vertices)
        named[(vs[0], vs[1])] = el.mat
    edges = [k for k, c in count.items() if c == 1]
    seg = np.array([[pts[a], pts[b]] for a, b in edges]).reshape(-1, 2, 2)
    return seg, [named.get(k, FREE) for k in edges]


def segment_distance(p, a, b):
    """Distance of the points ``p`` from the segments ``a -> b`` (broadcast over the leading
    axes; the last axis holds the coordinates); a segment of zero length is its point ``a``."""
    d = b - a
    dd = np.einsum("...k,...k->...", d, d)
    lam = np.clip(np.einsum("...k,...k->...", p - a, d) / np.where(dd > 0, dd, 1.0), 0.0, 1.0)
    return np.linalg.norm(a + lam[..., None] * d - p, axis=-1)


class BoundaryLocator:
    """Which outer-boundary edge of the source mesh (if any) a point lies on."""

    def __init__(self, segments, names, tol):
        from scipy.spatial import cKDTree

        self.seg, self.names, self.tol = segments, list(names), tol
        self.tree = cKDTree(segments.mean(axis=1)) if len(segments) else None

    def locate(self, pts) -> list:
        """Name of the outer-boundary edge containing each point, or None."""
        pts = np.atleast_2d(np.asarray(pts, dtype=float))
        if self.tree is None:
            return [None] * len(pts)
        k = min(4, len(self.seg))
        _, idx = self.tree.query(pts, k=k)
        idx = idx.reshape(len(pts), k)
        dist = segment_distance(pts[:, None, :], self.seg[idx, 0], self.seg[idx, 1])
        best = np.argmin(dist, axis=1)
        out = []
        for i, j in enumerate(best):
            out.append(self.names[idx[i, j]] if dist[i, j] <= self.tol else None)
        return out


def point_sets(mesh) -> dict:
    """Every named point (vertex regions other than 'default': co-dimension 2 in 2D, 3 in 3D)
    of a mesh, grouped by name: name -> array (k, dim) of the k points of that name (a case
    may name many points alike, e.g. the nodes of a clamped rim)."""
    from ngsolve import BBBND, BBND

    out = {}
    for el in mesh.Elements(BBBND if mesh.dim == 3 else BBND):
        if el.mat != "default":
            out.setdefault(el.mat, []).append(mesh[el.vertices[0]].point)
    return {name: np.array(points, dtype=float) for name, points in out.items()}


def named_points(mesh) -> dict:
    """The first point of each name of :func:`point_sets`: name -> (x, y) or (x, y, z) (an
    output port is one point)."""
    return {name: tuple(points[0]) for name, points in point_sets(mesh).items()}

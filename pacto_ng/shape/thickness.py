"""The thickness of a part's walls, as the refinement keeps it from falling, in 2D and 3D.

For each facet of the part's outer boundary (a segment in 2D, a triangle in 3D; not an
interface between two materials), the ray from its centre along its inward normal runs through
the solid until it leaves it through another boundary facet: the length of that ray is the
wall's thickness there (a wall between a chamber and the outside, a hinge, the web between two
chambers).  The inward side of each facet is taken once, on the reference mesh, from the
element it bounds; a motion that folds no element keeps it (the refinement's step control).
The rays are cast against every facet at once (numpy; in 2D the intersection of two lines,
``m + t n = a + u (b - a)`` with ``0 <= u <= 1``, in 3D Möller and Trumbore's ray-triangle
test, 1997, *J. Graphics Tools* 2(1), in chunks of :data:`CHUNK` rays), ``t > 0``.
"""
from __future__ import annotations

import numpy as np
from ngsolve import BND, EDGE, FACE, NodeId

#: hits closer than this fraction of the facet's own size are its neighbours at a corner, not
#: the other side of the wall
NEAR = 1e-9
#: rays cast at once in 3D (memory: CHUNK x facets x 3 numbers per array)
CHUNK = 64


class WallThickness:
    """``walls(points)``: the thickness at every outer boundary facet of ``mesh`` (2D or 3D)
    with its vertices at ``points`` (see the module)."""

    def __init__(self, mesh):
        self.dim = mesh.dim
        node = EDGE if mesh.dim == 2 else FACE
        # the outer boundary's facets (an interface between two materials bounds two
        # elements: inside the part) and the element each one bounds
        outer = [(e, owners[0]) for e in mesh.Elements(BND)
                 for owners in [mesh[NodeId(node, (e.edges if mesh.dim == 2 else e.faces)[0].nr)]
                                .elements]
                 if len(owners) == 1]
        self.facets = np.array([[v.nr for v in e.vertices] for e, _ in outer])
        pts = np.array([v.point for v in mesh.vertices], dtype=float)
        inside = np.array([np.mean([mesh[v].point for v in mesh[el].vertices], axis=0)
                           for _, el in outer])
        normal, centre, _ = self._geometry(pts)
        self.sign = np.where(np.einsum("ij,ij->i", normal, inside - centre) > 0, 1.0, -1.0)

    def _geometry(self, p):
        """``(normal, centre, size)`` of every facet at the points ``p``: a normal (not unit,
        of the facet's left side in 2D, by the vertex order in 3D), its centre and size."""
        v = [p[self.facets[:, k]] for k in range(self.dim)]
        if self.dim == 2:
            d = v[1] - v[0]
            return np.c_[-d[:, 1], d[:, 0]], 0.5 * (v[0] + v[1]), np.linalg.norm(d, axis=1)
        n = np.cross(v[1] - v[0], v[2] - v[0])
        return n, (v[0] + v[1] + v[2]) / 3.0, np.sqrt(np.linalg.norm(n, axis=1))

    def __call__(self, points) -> np.ndarray:
        p = np.asarray(points, dtype=float)[:, :self.dim]
        normal, centre, size = self._geometry(p)
        n = self.sign[:, None] * normal / np.linalg.norm(normal, axis=1)[:, None]
        if self.dim == 2:
            return self._lines(p, n, centre, size)
        return np.concatenate([self._triangles(p, n[k:k + CHUNK], centre[k:k + CHUNK],
                                               size[k:k + CHUNK])
                               for k in range(0, len(n), CHUNK)])

    def _lines(self, p, n, m, size):
        a, b = p[self.facets[:, 0]], p[self.facets[:, 1]]
        d = b - a
        # m_i + t n_i = a_j + u d_j, for every ray i and segment j
        cross = n[:, None, 0] * d[None, :, 1] - n[:, None, 1] * d[None, :, 0]
        am = a[None, :, :] - m[:, None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (am[..., 0] * d[None, :, 1] - am[..., 1] * d[None, :, 0]) / cross
            u = (am[..., 0] * n[:, None, 1] - am[..., 1] * n[:, None, 0]) / cross
            hit = (u >= 0.0) & (u <= 1.0) & (t > NEAR * size[:, None]) & np.isfinite(t)
        return np.where(hit, t, np.inf).min(axis=1)

    def _triangles(self, p, n, o, size):
        v0 = p[self.facets[:, 0]]
        e1, e2 = p[self.facets[:, 1]] - v0, p[self.facets[:, 2]] - v0
        q = np.cross(n[:, None, :], e2[None, :, :])  # (rays, triangles, 3)
        det = np.einsum("jk,ijk->ij", e1, q)
        s = o[:, None, :] - v0[None, :, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            u = np.einsum("ijk,ijk->ij", s, q) / det
            r = np.cross(s, e1[None, :, :])
            w = np.einsum("ik,ijk->ij", n, r) / det
            t = np.einsum("jk,ijk->ij", e2, r) / det
            hit = ((u >= 0.0) & (w >= 0.0) & (u + w <= 1.0) & (t > NEAR * size[:, None])
                   & np.isfinite(t))
        return np.where(hit, t, np.inf).min(axis=1)

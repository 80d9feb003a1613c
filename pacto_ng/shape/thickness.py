"""The thickness of a part's walls, as the refinement keeps it from falling, in 2D and 3D.

For each facet of the part's outer boundary (a segment in 2D, a triangle in 3D; not an
interface between two materials), the ray from its centre along its inward normal runs through
the solid until it leaves it through another boundary facet: the length of that ray is the
wall's thickness there (a wall between a chamber and the outside, a hinge, the web between
two chambers) if that facet faces the ray (the angle between the ray and its outward normal
at most 45°, :data:`FACING`); a ray that leaves at a glancing angle, across the facet beside
it at a blunt edge or corner, measures no wall.  The inward side of each facet is taken
once, on the reference mesh, from the element it bounds; a motion that folds no element
keeps it (the refinement's step control).  :meth:`WallThickness.shortfall` measures how far
the walls fall below a floor, with its exact derivative in the vertices (the refinement's
wall constraint).
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
#: a ray measures a wall only where it leaves through a facet that faces it: the cosine of
#: the angle between the ray and that facet's outward normal at least this (45°); a ray from
#: near a blunt edge or corner of the surface leaves across the facet beside it at a
#: glancing angle, a short way that is no wall (a wedge sharper than 45° is thin, and counts)
FACING = 0.5 ** 0.5


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
        return self.hits(points)[0]

    def hits(self, points) -> tuple[np.ndarray, np.ndarray]:
        """``(t, facet)``: the thickness at every facet and the facet its ray leaves the
        solid through (``-1`` and ``inf`` where it leaves through none)."""
        p = np.asarray(points, dtype=float)[:, :self.dim]
        normal, centre, size = self._geometry(p)
        n = self.sign[:, None] * normal / np.linalg.norm(normal, axis=1)[:, None]
        if self.dim == 2:
            t = self._lines(p, n, centre, size)
        else:
            t = np.concatenate([self._triangles(p, n[k:k + CHUNK], centre[k:k + CHUNK],
                                                size[k:k + CHUNK])
                                for k in range(0, len(n), CHUNK)])
        facet = np.argmin(t, axis=1)
        t = t[np.arange(len(t)), facet]
        # a wall only where the exit facet faces the ray (its outward normal -n_j)
        t = np.where(np.einsum("ij,ij->i", n, n[facet]) <= -FACING, t, np.inf)
        return t, np.where(np.isfinite(t), facet, -1)

    def shortfall(self, points, floor: float) -> tuple[float, np.ndarray]:
        """``(c, dc)``: the walls' shortfall below ``floor``,

            c = Σ_i |f_i| max(0, 1 - t_i/floor)² / floor^(d-1),

        (``|f_i|`` the facet's length or area, ``d`` the dimension: the squared relative
        deficit integrated over the boundary, in units of the floor's length or square), zero
        when no wall is thinner than ``floor``, and its derivative with respect to every
        point's coordinates (``(points, d)``; see :meth:`_thickness_derivative`)."""
        p = np.asarray(points, dtype=float)[:, :self.dim]
        t, hit = self.hits(p)
        deficit = np.where(hit >= 0, np.maximum(0.0, 1.0 - t / floor), 0.0)
        normal, centre, _ = self._geometry(p)
        length = np.linalg.norm(normal, axis=1)
        half = 1.0 if self.dim == 2 else 0.5  # |f| = |N| in 2D, |N|/2 in 3D
        scale = floor ** (self.dim - 1)
        grad = np.zeros_like(p)
        for i in np.flatnonzero(deficit > 0):
            # d(|f_i| δ_i²) = δ_i² d|f_i| - 2 |f_i| δ_i dt_i / floor, d|f_i| = half N̂_i·dN_i
            self._add_normal(grad, i, p, deficit[i] ** 2 * half * normal[i] / length[i])
            self._thickness_derivative(grad, p, (normal, centre), (i, hit[i], t[i]),
                                       -2.0 * half * length[i] * deficit[i] / floor)
        return float(np.sum(half * length * deficit ** 2)) / scale, grad / scale

    def _thickness_derivative(self, grad, p, geometry, ray, weight: float) -> None:
        """Add ``weight`` times the derivative of the thickness ``t`` of the ray ``(i, j, t)``
        (from facet ``i``, leaving through facet ``j``) to ``grad``; ``geometry`` the facets'
        normals and centres at the points ``p``.  With ``m`` the centre
        and ``n = s N_i/|N_i|`` the unit inward normal of facet ``i``, ``ν = N_j`` a normal
        of facet ``j``, ``a`` its first vertex and ``h = m + t n`` the hit: ``(h - a)·ν = 0``
        gives ``t = (a - m)·ν / (n·ν)`` and

            dt = (ν·da - ν·dm - t (Pν)·dN_i s/|N_i| + (a - h)·dN_j) / (n·ν),

        ``P = I - n nᵀ`` (``dn = s P dN_i / |N_i|``)."""
        (i, j, t), (normal, centre) = ray, geometry
        length = np.linalg.norm(normal[i])
        n = self.sign[i] * normal[i] / length
        nu = normal[j]
        w = weight / float(n @ nu)
        grad[self.facets[j, 0]] += w * nu
        for v in self.facets[i]:
            grad[v] -= w * nu / self.dim
        self._add_normal(grad, i, p, -w * t * self.sign[i] / length * (nu - (n @ nu) * n))
        self._add_normal(grad, j, p, w * (p[self.facets[j, 0]] - centre[i] - t * n))

    def _add_normal(self, grad, facet: int, p, g) -> None:
        """Add the derivative of ``g·N`` (``N`` the facet's normal of :meth:`_geometry`, ``g``
        fixed) with respect to its vertices to ``grad``: in 2D ``N = J(b - a)``, ``J(x, y) =
        (-y, x)``; in 3D ``N = e1 × e2``, ``e_k = v_k - v_0``."""
        v = self.facets[facet]
        if self.dim == 2:
            jg = np.array([g[1], -g[0]])  # Jᵀg
            grad[v[1]] += jg
            grad[v[0]] -= jg
            return
        e1, e2 = p[v[1]] - p[v[0]], p[v[2]] - p[v[0]]
        d1, d2 = np.cross(e2, g), np.cross(g, e1)  # g·(de1 × e2 + e1 × de2)
        grad[v[1]] += d1
        grad[v[2]] += d2
        grad[v[0]] -= d1 + d2

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
        return np.where(hit, t, np.inf)

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
        return np.where(hit, t, np.inf)

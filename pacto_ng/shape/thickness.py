"""The thickness of a part's walls, as the refinement keeps it from falling, in 2D and 3D.

For each facet of the part's outer boundary (a segment in 2D, a triangle in 3D; not an
interface between two materials), the ray from its centre along its inward normal runs through
the solid until it leaves it through another boundary facet: the length of that ray is the
wall's thickness there (a wall between a chamber and the outside, a hinge, the web between
two chambers).  A ray that leaves across a facet beside its own (sharing a vertex with it) at
a glancing angle (more than 45° between the ray and that facet's outward normal,
:data:`FACING`) measures no wall: that is an edge of the surface, not a wall.  The inward
side of each facet is taken once, on the reference mesh, from the element it bounds; a motion
that folds no element keeps it (the refinement's step control).  Along normals, a hinge whose
narrowest chord is oblique to both its walls reads thicker than it is: in 2D
:meth:`WallThickness.neck` measures that chord.  :meth:`WallThickness.shortfall` measures
how far the walls (along normals) fall below a floor, with its exact derivative in the
vertices (the refinement's wall constraint).
The rays are cast against every facet at once (numpy; in 2D the intersection of two lines,
``m + t n = a + u (b - a)`` with ``0 <= u <= 1``, in 3D Möller and Trumbore's ray-triangle
test, 1997, *J. Graphics Tools* 2(1), in chunks of :data:`CHUNK` rays), ``t > 0``.
"""
from __future__ import annotations

import math

import numpy as np
from ngsolve import BND, EDGE, FACE, NodeId
from scipy.spatial import cKDTree

#: hits closer than this fraction of the facet's own size are its neighbours at a corner, not
#: the other side of the wall
NEAR = 1e-9
#: rays cast at once in 3D (memory: CHUNK x facets x 3 numbers per array)
CHUNK = 64
#: a ray that leaves across a facet beside its own (one sharing a vertex with it) measures a
#: wall only where that facet faces it: the cosine of the angle between the ray and the
#: facet's outward normal at least this (45°); a ray from near an edge of a triangulated
#: surface crosses the large triangle beside it at a glancing angle, a short way that is no
#: wall.  A facet further away counts at any angle: a wall whose surface is ragged is as thin
#: as it is
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
        self._last = None  # the last points measured, and their hits
        self._loop_order = None  # 2D: the boundary's loops (neck)
        self.sign = np.where(np.einsum("ij,ij->i", normal, inside - centre) > 0, 1.0, -1.0)

    def neck(self, points, reach: float) -> float:
        """The narrowest neck of a 2D part below ``reach`` (``inf`` if none): the shortest
        distance between two vertices of the outer boundary that face each other across the
        solid (the chord from each one goes inward of its boundary, :meth:`_loops`' inward
        normals) and lie at least twice that distance apart along the boundary (so that a
        corner blunter than 60° is no neck).  A measure by distance, not along normals: a
        hinge narrowest across a chord oblique to its walls' normals, which their rays cross
        longer, is as thin as it is.  3D: ``inf`` (not measured)."""
        if self.dim != 2:
            return math.inf
        order, loop = self._loops()
        p = np.asarray(points, dtype=float)[order, :2]
        runs = np.split(np.arange(len(order)), np.flatnonzero(np.diff(loop)) + 1)
        nxt = np.roll(np.arange(len(order)), -1)
        for run in runs:  # each loop closes on itself
            nxt[run[-1]] = run[0]
        prv = np.empty_like(nxt)
        prv[nxt] = np.arange(len(nxt))
        step = np.linalg.norm(p[nxt] - p, axis=1)
        arc = np.cumsum(step) - step
        for run in runs:  # the arc length from its loop's start
            arc[run] -= arc[run[0]]
        total = np.bincount(loop, weights=step)
        tangent = p[nxt] - p[prv]
        inward = np.c_[-tangent[:, 1], tangent[:, 0]]  # left of the loop: the solid
        pairs = cKDTree(p).query_pairs(reach, output_type="ndarray")
        if len(pairs) == 0:
            return math.inf
        a, b = pairs[:, 0], pairs[:, 1]
        chord = p[b] - p[a]
        d = np.linalg.norm(chord, axis=1)
        along = np.abs(arc[a] - arc[b])
        path = np.where(loop[a] == loop[b], np.minimum(along, total[loop[a]] - along), np.inf)
        facing = ((np.einsum("ij,ij->i", chord, inward[a]) > 0)
                  & (np.einsum("ij,ij->i", -chord, inward[b]) > 0))
        valid = facing & (path >= 2.0 * d)
        return float(d[valid].min()) if np.any(valid) else math.inf

    def _loops(self):
        """``(order, loop)``: the outer boundary's vertices in the order of its loops, each
        run with the solid on its left, and the loop of each (computed once)."""
        if self._loop_order is None:
            ends = np.where(self.sign[:, None] > 0, self.facets, self.facets[:, ::-1])
            following = dict(zip(ends[:, 0].tolist(), ends[:, 1].tolist()))
            order, loop, seen = [], [], set()
            for start in following:
                if start in seen:
                    continue
                k, v = (loop[-1] + 1) if loop else 0, start
                while v not in seen:
                    seen.add(v)
                    order.append(v)
                    loop.append(k)
                    v = following[v]
            self._loop_order = (np.array(order), np.array(loop))
        return self._loop_order

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
        return self.hits(points)[0].copy()

    def hits(self, points) -> tuple[np.ndarray, np.ndarray]:
        """``(t, facet)``: the thickness at every facet and the facet its ray leaves the
        solid through (``-1`` and ``inf`` where it leaves through none).  The last points'
        are kept: a refinement measures each shape more than once."""
        p = np.asarray(points, dtype=float)[:, :self.dim]
        if self._last is not None and np.array_equal(p, self._last[0]):
            return self._last[1]
        self._last = (p.copy(), self._cast(p))
        return self._last[1]

    def _cast(self, p) -> tuple[np.ndarray, np.ndarray]:
        """:meth:`hits` at the points ``p``, cast."""
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
        # no wall where the ray leaves across a facet beside its own (a shared vertex) that
        # does not face it (its outward normal -n_j): an edge or corner of the surface
        beside = (self.facets[:, :, None] == self.facets[facet][:, None, :]).any(axis=(1, 2))
        glancing = np.einsum("ij,ij->i", n, n[facet]) > -FACING
        t = np.where(beside & glancing, np.inf, t)
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
        t, u, w, _ = ray_triangle(o[:, None, :], n[:, None, :], v0[None], e1[None], e2[None])
        hit = ((u >= 0.0) & (w >= 0.0) & (u + w <= 1.0) & (t > NEAR * size[:, None])
               & np.isfinite(t))
        return np.where(hit, t, np.inf)


def ray_triangle(o, d, v0, e1, e2):
    """``(t, u, w, det)`` of the rays ``o + t d`` against the triangles ``v0 + u e1 + w e2``
    (arrays of 3-vectors that broadcast against each other), by Möller and Trumbore's test
    (1997, *J. Graphics Tools* 2(1)): the ray meets the triangle's plane at ``t`` in the
    point of barycentric coordinates ``(u, w)``; ``det`` 0 (and the others not finite) for a
    ray parallel to the plane."""
    q = np.cross(d, e2)
    det = np.einsum("...k,...k->...", e1, q)
    s = o - v0
    r = np.cross(s, e1)
    with np.errstate(divide="ignore", invalid="ignore"):
        return (np.einsum("...k,...k->...", e2, r) / det, np.einsum("...k,...k->...", s, q) / det,
                np.einsum("...k,...k->...", d, r) / det, det)

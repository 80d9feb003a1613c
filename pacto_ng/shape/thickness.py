"""The thickness of a 2D part's walls, as the refinement keeps it from falling.

For each segment of the part's outer boundary (not an interface between two materials), the ray
from its midpoint along its inward normal runs through the solid until it leaves it through
another boundary segment: the length of that ray is the wall's thickness there (a wall between
a chamber and the outside, a hinge, the web between two chambers). The inward side of each
segment is taken once, on the reference mesh, from the element it bounds; a motion that folds
no element keeps it (the refinement's step control). The rays are cast against every segment at
once (numpy: the intersection of two lines, ``m + t n = a + u (b - a)`` with ``0 <= u <= 1``
and ``t > 0``).
"""
from __future__ import annotations

import numpy as np
from ngsolve import BND, EDGE, NodeId

#: hits closer than this fraction of the segment's own length are the segment's neighbours
#: at a corner, not the other side of the wall
NEAR = 1e-9


class WallThickness:
    """``walls(points)``: the thickness at every boundary segment of the 2D ``mesh`` with its
    vertices at ``points`` (see the module)."""

    def __init__(self, mesh):
        if mesh.dim != 2:
            raise ValueError("wall thickness: 2D meshes only")
        # the outer boundary's segments (an interface between two materials bounds two
        # elements: inside the part) and the element each one bounds
        outer = [(e, owners[0]) for e in mesh.Elements(BND)
                 for owners in [mesh[NodeId(EDGE, e.edges[0].nr)].elements]
                 if len(owners) == 1]
        self.ends = np.array([[v.nr for v in e.vertices] for e, _ in outer])
        pts = np.array([v.point for v in mesh.vertices], dtype=float)
        a, b = pts[self.ends[:, 0]], pts[self.ends[:, 1]]
        # the inward side: towards the centroid of the element each segment bounds
        inside = np.array([np.mean([mesh[v].point for v in mesh[el].vertices], axis=0)
                           for _, el in outer])
        left = np.c_[-(b - a)[:, 1], (b - a)[:, 0]]
        self.sign = np.where(np.einsum("ij,ij->i", left, inside - 0.5 * (a + b)) > 0,
                             1.0, -1.0)

    def __call__(self, points) -> np.ndarray:
        p = np.asarray(points, dtype=float)[:, :2]
        a, b = p[self.ends[:, 0]], p[self.ends[:, 1]]
        d = b - a
        length = np.linalg.norm(d, axis=1)
        n = self.sign[:, None] * np.c_[-d[:, 1], d[:, 0]] / length[:, None]
        m = 0.5 * (a + b)
        # m_i + t n_i = a_j + u d_j, for every ray i and segment j
        cross = n[:, None, 0] * d[None, :, 1] - n[:, None, 1] * d[None, :, 0]
        am = a[None, :, :] - m[:, None, :]
        with np.errstate(divide="ignore", invalid="ignore"):
            t = (am[..., 0] * d[None, :, 1] - am[..., 1] * d[None, :, 0]) / cross
            u = (am[..., 0] * n[:, None, 1] - am[..., 1] * n[:, None, 0]) / cross
        hit = (u >= 0.0) & (u <= 1.0) & (t > NEAR * length[:, None]) & np.isfinite(t)
        return np.where(hit, t, np.inf).min(axis=1)

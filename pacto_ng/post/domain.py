"""The domain geometry of a case for the post-analysis: its material face, its boundary curves,
and its symmetry line.

* :func:`material_domain` — the faces of a case's netgen.occ shape that can hold material (every
  face but the passive void ones, e.g. a chamber), fused into one region without the interfaces
  between them; the edge names of the shape (``fixed``, ``inlet``, ``symmetry``, ...) are kept
  (netgen.occ carries names through booleans and ``UnifySameDomain``).
* :class:`BoundaryCurves` — the boundary edges of that region sampled densely: the nearest point
  of the exact boundary (:meth:`~BoundaryCurves.project`) and how far a mesh's boundary
  polyline strays from it (:meth:`~BoundaryCurves.gap`).
* :func:`symmetry_line` / :func:`mirror` — the straight line of a mesh's ``symmetry`` boundary
  and the reflection about it (the pictures of a case solved on a symmetric half show the whole
  mechanism).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from .boundary import segment_distance

SYMMETRY = "symmetry"


# ---------------------------------------------------------------------------------------
def material_domain(shape, void=()):
    """The region of ``shape`` that can be solid: its faces not named in ``void``, fused.

    Returns a netgen.occ shape (one face per connected piece) whose edges carry the names of
    ``shape``'s edges; the interfaces between the fused faces are gone.

    Raises
    ------
    ValueError
        If ``shape`` has no face, or every face is void.
    """
    from netgen import occ

    void = set((void,) if isinstance(void, str) else void)
    faces = list(shape.faces)
    if not faces:
        raise ValueError("the domain shape has no face")
    keep = [f for f in faces if f.name not in void]
    if not keep:
        raise ValueError(f"every face of the domain shape is void ({', '.join(sorted(void))})")
    if len(keep) == 1 and len(faces) == 1:
        return shape
    out = occ.Fuse(keep) if len(keep) > 1 else keep[0]
    # faces only: merging edges would join collinear edges of different names
    return out.UnifySameDomain(unifyEdges=False, unifyFaces=True)


# ---------------------------------------------------------------------------------------
class BoundaryCurves:
    """The boundary edges of a 2D netgen.occ region, sampled at spacing about ``spacing``.

    Parameters
    ----------
    shape : netgen.occ shape
        The region (e.g. :func:`material_domain`).
    spacing : float
        Sampling distance; the projection refines within one sample interval by golden section,
        so its accuracy does not depend on it (about 1e-12 relative).
    """

    def __init__(self, shape, spacing: float):
        from scipy.spatial import cKDTree

        self.edges = list(shape.edges)
        pts, owner, par = [], [], []
        for k, e in enumerate(self.edges):
            t0, t1 = e.parameter_interval
            n = int(np.clip(np.ceil(float(e.mass) / spacing), 8, 20000)) + 1
            ts = np.linspace(t0, t1, n)
            pts.append(np.array([[e.Value(t).x, e.Value(t).y] for t in ts]))
            owner.append(np.full(n, k))
            par.append(ts)
        self.points = np.vstack(pts)
        self.owner = np.concatenate(owner)
        self.par = np.concatenate(par)
        self.names = [e.name for e in self.edges]
        self._tree = cKDTree(self.points)
        self._bounds = [e.parameter_interval for e in self.edges]
        self._dt = [(b[1] - b[0]) / max(len(p) - 1, 1) for b, p in zip(self._bounds, pts)]

    def _refine(self, q, k, t):
        """Golden-section search of the nearest parameter of edge ``k`` around ``t``."""
        e = self.edges[k]
        lo = max(self._bounds[k][0], t - self._dt[k])
        hi = min(self._bounds[k][1], t + self._dt[k])

        def dist(s):
            p = e.Value(s)
            return (p.x - q[0]) ** 2 + (p.y - q[1]) ** 2

        g = 0.5 * (np.sqrt(5.0) - 1.0)
        a, b = lo + (1 - g) * (hi - lo), lo + g * (hi - lo)
        fa, fb = dist(a), dist(b)
        for _ in range(60):
            if fa < fb:
                hi, b, fb = b, a, fa
                a = lo + (1 - g) * (hi - lo)
                fa = dist(a)
            else:
                lo, a, fa = a, b, fb
                b = lo + g * (hi - lo)
                fb = dist(b)
        s = 0.5 * (lo + hi)
        p = e.Value(s)
        return np.array([p.x, p.y])

    def project(self, pts) -> np.ndarray:
        """The nearest point of the boundary to each of ``pts`` (n, 2)."""
        pts = np.atleast_2d(np.asarray(pts, dtype=float))
        k = min(6, len(self.points))
        _, idx = self._tree.query(pts, k=k)
        idx = np.atleast_2d(idx)
        out = np.empty_like(pts)
        for i, q in enumerate(pts):
            best, bd = None, np.inf
            for j in idx[i]:
                c = self._refine(q, self.owner[j], self.par[j])
                d = np.hypot(*(c - q))
                if d < bd:
                    best, bd = c, d
            out[i] = best
        return out

    def distance(self, pts) -> np.ndarray:
        """Distance of each of ``pts`` from the boundary."""
        pts = np.atleast_2d(np.asarray(pts, dtype=float))
        return np.linalg.norm(self.project(pts) - pts, axis=1)

    def gap(self, segments) -> float:
        """How far the boundary strays from a polyline approximation of it: the largest distance
        of a boundary sample from the nearest of ``segments`` (m, 2, 2), e.g. the sagitta of a
        mesh's chords along a curved edge (0 for a polygon meshed exactly)."""
        from scipy.spatial import cKDTree

        seg = np.asarray(segments, dtype=float).reshape(-1, 2, 2)
        if not len(seg):
            return 0.0
        k = min(8, len(seg))
        _, idx = cKDTree(seg.mean(axis=1)).query(self.points, k=k)
        idx = idx.reshape(len(self.points), k)
        d = segment_distance(self.points[:, None, :], seg[idx, 0], seg[idx, 1]).min(axis=1)
        return float(d.max())


# ---------------------------------------------------------------------------------------
@dataclass(frozen=True)
class Line:
    """A straight line through ``point`` along the unit vector ``direction``."""

    point: tuple
    direction: tuple

    def reflect(self, pts) -> np.ndarray:
        """The mirror images of ``pts`` (..., 2) about the line."""
        pts = np.asarray(pts, dtype=float)
        p0 = np.asarray(self.point, dtype=float)
        d = np.asarray(self.direction, dtype=float)
        rel = pts - p0
        along = rel @ d
        return p0 + 2.0 * along[..., None] * d - rel


def symmetry_line(mesh, name: str = SYMMETRY, rtol: float = 1e-6):
    """The straight line of the boundary ``name`` of a 2D NGSolve mesh, or None.

    The line runs through the two vertices of the boundary farthest apart; None when the mesh
    has no such boundary, or when a vertex of it lies farther than ``rtol`` times the mesh's
    diameter from that line (a curved or broken symmetry boundary is not mirrored).
    """
    from ngsolve import BND

    if name not in set(mesh.GetBoundaries()):
        return None
    ids = sorted({v.nr for el in mesh.Elements(BND) if el.mat == name for v in el.vertices})
    if len(ids) < 2:
        return None
    allpts = np.array([v.point for v in mesh.vertices], dtype=float)[:, :2]
    pts = allpts[ids]
    diam = float(np.ptp(allpts, axis=0).max()) or 1.0
    a = pts[np.argmin(pts @ np.array([1.0, 0.0]) + 1e-3 * pts[:, 1])]
    a = pts[np.argmax(np.linalg.norm(pts - a, axis=1))]  # an extreme vertex
    b = pts[np.argmax(np.linalg.norm(pts - a, axis=1))]  # the one farthest from it
    d = b - a
    length = float(np.linalg.norm(d))
    if length <= rtol * diam:
        return None
    d = d / length
    off = np.abs((pts - a) @ np.array([-d[1], d[0]]))
    if off.max() > rtol * diam:
        return None
    # a canonical direction (+x, else +y) so that the line does not depend on vertex order
    if d[0] < -1e-12 or (abs(d[0]) <= 1e-12 and d[1] < 0):
        d = -d
    return Line(tuple(map(float, a)), tuple(map(float, d)))


def mirror(polygons, line):
    """``polygons`` (a list of (k, 2) arrays) followed by their mirror images about ``line``
    (each image reversed, so that it keeps its orientation)."""
    if line is None:
        return list(polygons)
    return list(polygons) + [line.reflect(p)[::-1] for p in polygons]

"""The part's geometry traced from the thresholded polygons, as Netgen OCC faces.

Every loop of :mod:`.threshold` is cut at its *break points* — where the name of the source
boundary it runs along changes, and at the corners of that boundary.  A run along the source
mesh's outer boundary becomes one straight ``occ.Segment`` (so a clamp stays exactly on the
clamp line); a run inside the domain is smoothed (:func:`_smooth`), thinned to points at least
``min_spacing`` apart and becomes one ``occ.SplineApproximation`` (a loop with no break point is
split into four runs).  Faces are built from the wires, holes are cut out
(:func:`build_geometry`); the edges are named by the source boundary they lie on, else
:data:`~.boundary.FREE`.  :mod:`.domain_part` builds the part on the domain's own geometry from
the same pieces.
"""
from __future__ import annotations

import numpy as np

from .boundary import FREE
from .threshold import Loop


def clean(points, labels, tol):
    """Merge consecutive points closer than ``tol`` (the merged edge keeps the longer label)."""
    p, lab = [np.asarray(q) for q in points], list(labels)
    i = 0
    while len(p) > 3 and i < len(p):
        j = (i + 1) % len(p)
        if np.linalg.norm(p[j] - p[i]) < tol:
            # drop point j: the tiny edge i -> j and the edge j -> j+1 become one edge
            lab[i] = lab[j]
            del p[j], lab[j]
            if j < i:
                i -= 1
            continue
        i += 1
    return np.array(p), lab


def _breaks(p, lab):
    """Indices where a run starts: the label changes, or a boundary run turns a corner."""
    n = len(p)
    out = []
    for i in range(n):
        a, b = lab[i - 1], lab[i]
        if a != b:
            out.append(i)
        elif a is not None:
            d0 = p[i] - p[i - 1]
            d1 = p[(i + 1) % n] - p[i]
            cross = d0[0] * d1[1] - d0[1] * d1[0]
            if abs(cross) > 1e-8 * np.linalg.norm(d0) * np.linalg.norm(d1):
                out.append(i)
    if not out:  # a loop entirely inside the domain: four runs of equal arc length
        s = np.r_[0.0, np.cumsum(np.linalg.norm(np.diff(np.vstack([p, p[:1]]), axis=0), axis=1))]
        out = sorted({int(np.searchsorted(s, k * s[-1] / 4.0)) % n for k in range(4)})
    return out


def _smooth(run, iterations: int = 2, lam: float = 0.5, mu: float = -0.53,
            corner: float = 40.0):
    """Taubin's λ|μ smoothing of an open polyline (its ends fixed): removes the zig-zag of an
    iso-line traced through the elements without shrinking it.  Measured on the jaw-gripper
    and soft-finger designs: thinning the raw zig-zag to every ``0.6 h`` picks a biased subset
    of its points (the part -2.2 % and +0.5 % of the thresholded area); smoothed first,
    -0.4 % and +0.3 %."""
    p = np.array(run, dtype=float)
    if len(p) < 3:
        return p
    # corners stay: a vertex that turns by ``corner`` degrees or more the same way as a
    # neighbour is pinned (a traced rectangle's corner, cut by one diagonal: two turns of 45
    # degrees); the zig-zag of an iso-line turns back and forth and is smoothed
    d = np.diff(p, axis=0)
    turn = np.arctan2(d[:-1, 0] * d[1:, 1] - d[:-1, 1] * d[1:, 0],
                      np.einsum("ij,ij->i", d[:-1], d[1:]))
    sharp = np.abs(turn) >= np.radians(corner)
    t = np.where(sharp, np.sign(turn), 0.0)
    same = (np.r_[0.0, t[:-1]] * t > 0) | (np.r_[t[1:], 0.0] * t > 0)
    free = np.r_[False, ~same, False]
    for _ in range(iterations):
        for f in (lam, mu):
            q = p.copy()
            q[1:-1] += f * (0.5 * (p[:-2] + p[2:]) - p[1:-1])
            p = np.where(free[:, None], q, p)
    return p


def _thin(run, spacing):
    """Keep the ends of a run and interior points at least ``spacing`` apart."""
    kept = [run[0]]
    for q in run[1:-1]:
        if np.linalg.norm(q - kept[-1]) >= spacing:
            kept.append(q)
    if len(kept) > 1 and np.linalg.norm(run[-1] - kept[-1]) < 0.5 * spacing:
        kept.pop()
    kept.append(run[-1])
    return np.array(kept)


def spline(run, spacing, tol):
    """One OCC edge through a run inside the domain: smoothed, thinned to ``spacing``, a
    spline within ``tol`` of the thinned points (a straight segment when two points are
    left)."""
    from netgen import occ

    thin = _thin(_smooth(run), spacing)
    P = [occ.Pnt(float(x), float(y), 0.0) for x, y in thin]
    if len(P) == 2:
        return occ.Segment(P[0], P[1])
    return occ.SplineApproximation(P, deg_min=1, deg_max=3, tol=tol)


def loop_edges(loop: Loop, spacing, tol, h):
    """OCC edges of one loop (straight runs on the boundary, splines inside)."""
    from netgen import occ

    p, lab = clean(loop.points, loop.labels, 1e-3 * h)
    n = len(p)
    br = _breaks(p, lab)
    edges = []
    for k, i0 in enumerate(br):
        i1 = br[(k + 1) % len(br)]
        idx = list(range(i0, i1 + 1)) if i1 > i0 else list(range(i0, n)) + list(range(0, i1 + 1))
        run = p[idx]
        if lab[i0] is not None or len(run) == 2:
            edges.append(occ.Segment(occ.Pnt(float(run[0][0]), float(run[0][1]), 0.0),
                                     occ.Pnt(float(run[-1][0]), float(run[-1][1]), 0.0)))
        else:
            edges.append(spline(run, spacing, tol))
    return edges


def build_geometry(components, h, *, min_spacing=None, spline_tol=None, locator=None):
    """The netgen.occ shape (material ``solid``, edges named by location) of solid pieces.

    Parameters
    ----------
    components : sequence of Component
    h : float
        Element size of the source mesh (sets the defaults below).
    min_spacing : float, optional
        Minimum distance between spline points, default ``0.6 h``.
    spline_tol : float, optional
        Tolerance of the spline approximation, default ``0.1 h``.
    locator : BoundaryLocator, optional
        Names of the source's outer boundary; edges not on it are ``free``.
    """
    from netgen import occ

    spacing = 0.6 * h if min_spacing is None else float(min_spacing)
    tol = 0.1 * h if spline_tol is None else float(spline_tol)
    faces = []
    for comp in components:
        face = occ.Face(occ.Wire(loop_edges(comp.outer, spacing, tol, h)))
        for hole in comp.holes:
            face = face - occ.Face(occ.Wire(loop_edges(hole, spacing, tol, h)))
        faces.append(face)
    shape = occ.Glue(faces) if len(faces) > 1 else faces[0]
    shape.faces.name = "solid"
    for e in shape.edges:
        c = e.center
        name = locator.locate([(c.x, c.y)])[0] if locator is not None else None
        e.name = name or FREE
    return shape


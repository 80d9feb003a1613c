"""The part on the domain's own geometry: where the solid reaches the domain's boundary, the
part's boundary is the domain's edge itself, with its name.

Given the netgen.occ shape the source mesh was made from (:func:`domain_shape`,
:func:`build_domain_geometry`): the loops' runs along the source's boundary are moved a margin
off the domain (outward from the solid), the cuts inside stay splines (:func:`.traced.spline`)
but end 0.25 h inside the domain and are joined to the moved runs by straight segments (a
spline ending on the domain's boundary, at a grazing angle or at a vertex of the domain, made
OCC's Common empty on the soft-finger example), and the face is intersected with the domain
(``*``, OCC's Common) without its void faces.  Every spline's points are smoothed first.
Wherever the solid reaches the domain's boundary — a curved outline, a hole, a void chamber's
wall — the part's boundary is then that edge itself with its name, not the source mesh's
polyline; a hole of the domain inside the solid stays a hole with its own edge.  Measured: a
half ring along the arc of a half disc (maxh 0.05 R) has its arc on the circle to round-off and
its area +0.03 % of the thresholded area (tests/post/test_domain_remesh.py).  The margin is
0.25 h, or three times the largest distance between the source mesh's boundary chords and the
domain's edges if that is more.
"""
from __future__ import annotations

import numpy as np

from .boundary import FREE, outer_boundary
from .domain import BoundaryCurves, material_domain
from .threshold import Loop, Thresholded
from .traced import clean, loop_edges, spline


def _segments_cross(P, closed=True) -> bool:
    """Whether the polygon ``P`` (n, 2) crosses itself (proper crossings of non-adjacent
    edges)."""
    Q = np.roll(P, -1, axis=0) if closed else P[1:]
    A = P if closed else P[:-1]
    m = len(A)
    if m < 4:
        return False
    d = Q - A

    def orient(a, b, c):
        return (b[..., 0] - a[..., 0]) * (c[..., 1] - a[..., 1]) - \
            (b[..., 1] - a[..., 1]) * (c[..., 0] - a[..., 0])

    i, j = np.triu_indices(m, k=2)
    if closed:
        keep = ~((i == 0) & (j == m - 1))
        i, j = i[keep], j[keep]
    o1 = orient(A[i], Q[i], A[j])
    o2 = orient(A[i], Q[i], Q[j])
    o3 = orient(A[j], Q[j], A[i])
    o4 = orient(A[j], Q[j], Q[i])
    scale = np.linalg.norm(d, axis=1).max() ** 2
    eps = 1e-14 * scale
    return bool(np.any((o1 * o2 < -eps) & (o3 * o4 < -eps)))


def _runs(on):
    """Maximal runs of equal ``on`` along a closed loop of edges: ``(start, stop, on)`` with the
    run's vertices ``start..stop`` (indices mod n); the first run starts where ``on`` changes."""
    n = len(on)
    start = next(i for i in range(n) if on[i] != on[i - 1])
    out, i = [], start
    while i < start + n:
        j = i
        while j < start + n and on[j % n] == on[i % n]:
            j += 1
        out.append((i, j, bool(on[i % n])))
        i = j
    return out


def _vertex_normals(P, sign):
    """Unit normals at the vertices of the open polyline ``P`` (k, 2): ``sign`` times the
    right-hand normal of the adjacent edges, averaged at interior vertices."""
    d = np.diff(P, axis=0)
    d = d / np.linalg.norm(d, axis=1)[:, None]
    ne = sign * np.c_[d[:, 1], -d[:, 0]]
    nv = np.vstack([ne[:1], ne[:-1] + ne[1:], ne[-1:]])
    norm = np.linalg.norm(nv, axis=1)
    bad = norm < 1e-6  # a hairpin: the edge normal before it
    nv[bad] = np.vstack([ne[:1], ne])[bad]
    return nv / np.linalg.norm(nv, axis=1)[:, None]


def _extended_loop(loop: Loop, h, curves, margin, inset=None):
    """The point sequence of a loop whose runs along the domain boundary are moved a distance
    ``margin`` off the domain (outward from the solid), with the cuts inside the domain ending
    ``inset`` (default ``0.25 h``) inside it.

    A run along the boundary becomes the path of its vertices offset by ``margin`` along the
    outward normal (its ends projected onto the exact boundary first).  A cut (a run inside the
    domain) keeps only its points at least ``inset`` from the domain's exact boundary; the wire
    joins its first and last such point to the neighbouring offset paths by straight segments
    (:func:`_wire_of`), so that every crossing of the domain's boundary is a straight segment
    from a point well inside to a point ``margin`` outside.  (A spline ending *on* the
    boundary, as before, left or re-entered the domain at a grazing angle near its end on the
    soft-finger design -- the iso-line turns along the skin as it meets it -- and OCC's Common
    of that face with the domain came out empty.)  A cut with no point that far inside (a
    notch shallower than ``inset``) is dropped: the offset paths around it are joined.

    Returns ``(pieces, polygon)``: pieces ``("cut", points)`` (inside the domain) and
    ``("out", points)`` (a path outside the domain), and the whole closed polygon (the pieces'
    points in order) for the crossing check; ``None`` for a hole that runs entirely along the
    domain boundary (the domain's own hole: the intersection with the domain restores it).
    """
    inset = 0.25 * h if inset is None else float(inset)
    p, lab = clean(loop.points, loop.labels, 1e-3 * h)
    on = np.array([lb is not None for lb in lab])
    # the loops are counter-clockwise: outward from the solid is the right-hand normal of an
    # outer loop (solid on the left) and the left-hand normal of a hole
    sign = -1.0 if loop.is_hole else 1.0
    n = len(p)
    if on.all():
        if loop.is_hole:
            return None
        closed = np.vstack([p, p[:1]])
        nv = _vertex_normals(np.vstack([p[-1:], closed]), sign)[1:-1]
        out = p + margin * nv
        return [("out", np.vstack([out, out[:1]]))], out
    if not on.any():
        return [("inside", None)], p
    pieces = []
    for i0, i1, is_on in _runs(on):
        idx = [k % n for k in range(i0, i1 + 1)]
        run = p[idx]
        if not is_on:
            deep = np.flatnonzero(curves.distance(run) >= inset)
            if len(deep):
                pieces.append(("cut", run[deep[0]:deep[-1] + 1]))
            continue
        nv = _vertex_normals(run, sign)
        a, b = curves.project(run[0])[0], curves.project(run[-1])[0]
        pieces.append(("out", np.vstack([a + margin * nv[0], run[1:-1] + margin * nv[1:-1],
                                         b + margin * nv[-1]])))
    poly = np.vstack([pts for _, pts in pieces])
    keep = np.r_[True, np.linalg.norm(np.diff(poly, axis=0), axis=1) > 0.0]
    return pieces, poly[keep]


def _wire_of(pieces, spacing, tol):
    """The closed wire of :func:`_extended_loop`'s pieces: a cut of more than one point as a
    spline, an offset path as straight segments, consecutive pieces joined by straight
    segments."""
    from netgen import occ

    def seg(a, b):
        return occ.Segment(occ.Pnt(float(a[0]), float(a[1]), 0.0),
                           occ.Pnt(float(b[0]), float(b[1]), 0.0))

    edges, last = [], None
    for kind, pts in pieces:
        if last is not None and np.linalg.norm(pts[0] - last) > 0.0:
            edges.append(seg(last, pts[0]))
        if kind == "cut" and len(pts) > 1:
            edges.append(spline(pts, spacing, tol))
        elif kind != "cut":
            edges.extend(seg(a, b) for a, b in zip(pts[:-1], pts[1:])
                         if np.linalg.norm(b - a) > 0.0)
        last = pts[-1]
    first = pieces[0][1][0]
    if np.linalg.norm(first - last) > 0.0:
        edges.append(seg(last, first))
    return occ.Wire(edges)


def build_domain_geometry(components, h, domain, *, curves=None, margin=None,
                          min_spacing=None, spline_tol=None):
    """The part on the domain's own geometry: the traced solid, extended off the domain where
    it lies along the domain's boundary, intersected with the domain.

    Where the solid reaches the domain's boundary (outer, curved, a hole or a void chamber's
    wall) the part's boundary is therefore the domain's edge itself, with its name; the cuts
    inside the domain are splines as in :func:`~.traced.build_geometry` and are named ``free``.

    Parameters
    ----------
    components : sequence of Component
        Thresholded on the mesh of ``domain`` (with the void faces excluded).
    h : float
        Element size of the source mesh.
    domain : netgen.occ shape
        The material domain (:func:`~pacto_ng.post.domain.material_domain`).
    curves : BoundaryCurves, optional
        The sampled boundary of ``domain`` (built here if missing).
    margin : float, optional
        How far the boundary runs are moved off the domain, default ``0.25 h`` (at least
        three times the largest sagitta of the source mesh's boundary chords).  Halved (down
        to ``0.01 h``) where a moved loop would cross itself.
    min_spacing, spline_tol : float, optional
        As :func:`~.traced.build_geometry`.

    Returns
    -------
    netgen.occ shape, material ``solid``; faces of less than ``1e-6 h²`` (slivers where a
    spline grazes the boundary) are dropped.
    """
    from netgen import occ

    spacing = 0.6 * h if min_spacing is None else float(min_spacing)
    tol = 0.1 * h if spline_tol is None else float(spline_tol)
    curves = BoundaryCurves(domain, 0.1 * h) if curves is None else curves
    margin = 0.25 * h if margin is None else float(margin)
    parts = []
    for comp in components:
        face = None
        for k, loop in enumerate(comp.loops):
            m = margin
            while True:
                ext = _extended_loop(loop, h, curves, m)
                if ext is None or not _segments_cross(ext[1]) or m < 0.01 * h:
                    break
                m *= 0.5
            if ext is None:
                continue
            if ext[0][0][0] == "inside":  # a loop inside the domain: as the traced geometry
                f = occ.Face(occ.Wire(loop_edges(loop, spacing, tol, h)))
            else:
                f = occ.Face(_wire_of(ext[0], spacing, tol))
            if k == 0:
                face = f
            else:
                face = face - f
        face.edges.name = FREE
        parts.append(face * domain)
    shape = occ.Glue(parts) if len(parts) > 1 else parts[0]
    faces = [f for f in shape.faces if f.mass > 1e-6 * h * h]
    if not faces:
        raise ValueError("the part and the domain do not overlap")
    if len(faces) < len(shape.faces):
        shape = occ.Glue(faces) if len(faces) > 1 else faces[0]
    shape.faces.name = "solid"
    for e in shape.edges:
        if e.name is None:
            e.name = FREE
    return shape


def domain_shape(th: Thresholded, kept, domain, min_spacing, spline_tol):
    """:func:`build_domain_geometry` of the kept pieces on ``domain`` without the excluded
    faces; the margin is ``0.25 h``, or three times the largest distance between the source
    mesh's boundary polyline and the domain's edges if that is more (at most ``2 h``)."""
    faces = {f.name for f in domain.faces}
    missing = sorted(set(th.excluded) - faces)
    if missing:
        raise ValueError(f"the excluded materials {', '.join(missing)} are not faces of the "
                         f"domain")
    dom = material_domain(domain, th.excluded)
    curves = BoundaryCurves(dom, 0.05 * th.h)
    seg, _ = outer_boundary(th.source, th.excluded)
    margin = float(np.clip(3.0 * curves.gap(seg), 0.25 * th.h, 2.0 * th.h))
    return build_domain_geometry(kept, th.h, dom, curves=curves, margin=margin,
                                 min_spacing=min_spacing, spline_tol=spline_tol)

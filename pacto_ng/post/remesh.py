"""A body-fitted Netgen mesh of a thresholded design, with its boundaries named by location.

Geometry (the recipe of ``shared/NGSOLVE_NOTES.md``): every loop of :mod:`.threshold` is cut at
its *break points* — where the name of the source boundary it runs along changes, and at the
corners of that boundary.  A run along the source mesh's outer boundary becomes one straight
``occ.Segment`` (so a clamp stays exactly on the clamp line); a run inside the domain is thinned
to points at least ``min_spacing`` apart and becomes one ``occ.SplineApproximation`` (a loop
with no break point is split into four runs).  Faces are built from the wires, holes are cut
out, and Netgen meshes the result with triangles of size ``maxh``; the material is ``solid``.

**On the domain's own geometry** (``domain``: the netgen.occ shape the source mesh was made
from; :func:`build_domain_geometry`): the loops' runs along the source's boundary are moved a
margin off the domain (outward from the solid), the cuts inside stay splines but end 0.25 h
inside the domain and are joined to the moved runs by straight segments (a spline ending on the
domain's boundary, at a grazing angle or at a vertex of the domain, made OCC's Common empty on
the soft-finger example), and the face is intersected with the domain (``*``, OCC's Common)
without its void faces.  Every spline's points are smoothed first (:func:`_smooth`).  Wherever the solid reaches the domain's
boundary — a curved outline, a hole, a void chamber's wall — the part's boundary is then that
edge itself with its name, not the source mesh's polyline; a hole of the domain inside the
solid stays a hole with its own edge.  Measured: a half ring along the arc of a half disc (maxh
0.05 R) has its arc on the circle to round-off and its area +0.03 % of the thresholded area
(tests/post/test_domain_remesh.py).  The margin is 0.25 h, or three times the largest distance
between the source mesh's boundary chords and the domain's edges if that is more.

Names carried over from the source mesh:

* boundary segments on the source's outer boundary keep that boundary's name (``fixed``,
  ``symmetry``, ``inlet``, ...); the other boundary segments are ``free``;
* **the wetting rule** — a boundary segment of the new mesh is renamed ``pressure`` when

  - it lies on a source boundary whose name is in ``wet_boundaries`` (the fluid is on the
    other side of the domain boundary, e.g. the inlet), or
  - it lies inside the source domain and the pressure field at its midpoint moved a distance
    ``probe`` (default: the source element size) along the outward normal of the solid — its
    cavity side — is at least ``wet_fraction`` (default 0.5) times the inlet pressure
    ``p_in`` (default: the largest nodal pressure).  A probe point outside the source mesh
    sees zero pressure.

* every named point (co-dimension 2 region) of the source becomes the nearest vertex of the
  new mesh.

Solid pieces that touch none of the ``clamp`` boundaries would float (a singular stiffness):
they are dropped and reported; if no piece touches the clamp, :func:`remesh` raises.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from .threshold import Loop, Thresholded, _BoundaryLocator, outer_boundary

PRESSURE = "pressure"
FREE = "free"


@dataclass
class Remeshed:
    """The result of :func:`remesh`.

    Attributes
    ----------
    mesh : ngsolve.Mesh
        Triangle mesh of the solid (material ``solid``) with the named boundaries and points.
    area : float
        Area of the new mesh.
    thresholded_area : float
        Area of the clipped solid it was built from (:attr:`Thresholded.area`).
    dropped_area : float
        Area of the floating pieces that were dropped.
    ports : dict
        Point name -> ``(source position, new vertex position)``.
    wetted_length : float
        Length of the ``pressure`` boundary.
    p_in : float or None
        The inlet pressure the wetting rule used.
    geometry : str
        ``"traced"`` (the part's whole boundary traced from the thresholded polygons) or
        ``"domain"`` (on the domain's own edges where the solid reaches them); ``"traced
        (...)"`` says why a given domain was not used.
    """

    mesh: object
    area: float
    thresholded_area: float
    dropped_area: float = 0.0
    ports: dict = field(default_factory=dict)
    wetted_length: float = 0.0
    p_in: float | None = None
    geometry: str = "traced"


def _unmeshed_edges(ngm) -> int:
    """The boundary segments of a Netgen mesh that border no triangle (an empty face)."""
    edges = set()
    for el in ngm.Elements2D():
        vs = [v.nr for v in el.vertices]
        edges.update((min(a, b), max(a, b)) for a, b in zip(vs, vs[1:] + vs[:1]))
    ends = ([v.nr for v in s.vertices][:2] for s in ngm.Elements1D())
    return sum((min(a, b), max(a, b)) not in edges for a, b in ends)


def _generate(shape, maxh: float, threshold: float):
    """The Netgen mesh of ``shape`` at ``maxh``; ValueError (one line) when Netgen fails: an
    OCC triangulation error, or a face left without triangles ("NOT ALL FACES HAVE BEEN
    MESHED").  (Retrying at 0.7 and 0.5 maxh was tried on two such PneuNet parts and did not
    help, so there is no retry.)"""
    from netgen import occ

    try:
        ngm = occ.OCCGeometry(shape, dim=2).GenerateMesh(maxh=maxh)
    except Exception as err:  # netgen's NgException, e.g. "OCC-Triangulation could not be built"
        what = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
    else:
        bad = _unmeshed_edges(ngm)
        if not bad:
            return ngm
        what = f"{bad} boundary edges have no triangle (a face of the traced geometry was left empty)"
    raise ValueError(f"Netgen could not mesh the part: {what}; threshold {threshold:g}, maxh "
                     f"{maxh:g}: try another threshold or maxh")


# ---------------------------------------------------------------------------------------
def _clean(points, labels, tol):
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


def _loop_edges(loop: Loop, spacing, tol, h):
    """OCC edges of one loop (straight runs on the boundary, splines inside)."""
    from netgen import occ

    p, lab = _clean(loop.points, loop.labels, 1e-3 * h)
    n = len(p)
    br = _breaks(p, lab)
    edges = []
    for k, i0 in enumerate(br):
        i1 = br[(k + 1) % len(br)]
        idx = list(range(i0, i1 + 1)) if i1 > i0 else list(range(i0, n)) + list(range(0, i1 + 1))
        run = p[idx]
        P = [occ.Pnt(float(x), float(y), 0.0) for x, y in run]
        if lab[i0] is not None or len(run) == 2:
            edges.append(occ.Segment(P[0], P[-1]))
            continue
        thin = _thin(_smooth(run), spacing)
        if len(thin) == 2:
            edges.append(occ.Segment(P[0], P[-1]))
            continue
        Q = [occ.Pnt(float(x), float(y), 0.0) for x, y in thin]
        edges.append(occ.SplineApproximation(Q, deg_min=1, deg_max=3, tol=tol))
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
    locator : _BoundaryLocator, optional
        Names of the source's outer boundary; edges not on it are ``free``.
    """
    from netgen import occ

    spacing = 0.6 * h if min_spacing is None else float(min_spacing)
    tol = 0.1 * h if spline_tol is None else float(spline_tol)
    faces = []
    for comp in components:
        face = occ.Face(occ.Wire(_loop_edges(comp.outer, spacing, tol, h)))
        for hole in comp.holes:
            face = face - occ.Face(occ.Wire(_loop_edges(hole, spacing, tol, h)))
        faces.append(face)
    shape = occ.Glue(faces) if len(faces) > 1 else faces[0]
    shape.faces.name = "solid"
    for e in shape.edges:
        c = e.center
        name = locator.locate([(c.x, c.y)])[0] if locator is not None else None
        e.name = name or FREE
    return shape


# ---------------------------------------------------------------------------------------
# the part on the domain's own geometry
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
    p, lab = _clean(loop.points, loop.labels, 1e-3 * h)
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
            edges.append(_spline(pts, spacing, tol))
        elif kind != "cut":
            edges.extend(seg(a, b) for a, b in zip(pts[:-1], pts[1:])
                         if np.linalg.norm(b - a) > 0.0)
        last = pts[-1]
    first = pieces[0][1][0]
    if np.linalg.norm(first - last) > 0.0:
        edges.append(seg(last, first))
    return occ.Wire(edges)


def _spline(run, spacing, tol):
    from netgen import occ

    thin = _thin(_smooth(run), spacing)
    P = [occ.Pnt(float(x), float(y), 0.0) for x, y in thin]
    if len(P) == 2:
        return occ.Segment(P[0], P[1])
    return occ.SplineApproximation(P, deg_min=1, deg_max=3, tol=tol)


def build_domain_geometry(components, h, domain, *, curves=None, margin=None,
                          min_spacing=None, spline_tol=None):
    """The part on the domain's own geometry: the traced solid, extended off the domain where
    it lies along the domain's boundary, intersected with the domain.

    Where the solid reaches the domain's boundary (outer, curved, a hole or a void chamber's
    wall) the part's boundary is therefore the domain's edge itself, with its name; the cuts
    inside the domain are splines as in :func:`build_geometry` and are named ``free``.

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
        As :func:`build_geometry`.

    Returns
    -------
    netgen.occ shape, material ``solid``; faces of less than ``1e-6 h²`` (slivers where a
    spline grazes the boundary) are dropped.
    """
    from netgen import occ

    from .domain import BoundaryCurves

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
                f = occ.Face(occ.Wire(_loop_edges(loop, spacing, tol, h)))
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


# ---------------------------------------------------------------------------------------
def pressure_sampler(pressure, source):
    """A function ``(xy) -> p`` for points ``xy`` (n, 2); zero outside the source mesh.

    ``pressure`` may be an NGSolve CoefficientFunction or GridFunction on ``source``, a numpy
    array of nodal values (one per source vertex, the vertex order of ``source``), or a
    Python callable ``f(x, y)`` on arrays.
    """
    import ngsolve

    if isinstance(pressure, np.ndarray):
        vals = np.asarray(pressure, dtype=float).ravel()
        if vals.shape[0] != source.nv:
            raise ValueError(f"nodal pressure has {vals.shape[0]} values but the mesh has "
                             f"{source.nv} vertices")
        gf = ngsolve.GridFunction(ngsolve.H1(source, order=1))
        gf.vec.FV().NumPy()[:source.nv] = vals
        pressure = gf
    if isinstance(pressure, ngsolve.CoefficientFunction):
        cf = pressure

        def sample(xy):
            xy = np.atleast_2d(np.asarray(xy, dtype=float))
            mips = source(xy[:, 0].copy(), xy[:, 1].copy())
            out = np.zeros(len(xy))
            inside = mips["nr"] >= 0
            if inside.any():
                out[inside] = np.asarray(cf(mips[inside])).ravel()
            return out

        return sample
    if callable(pressure):
        return lambda xy: np.asarray(pressure(np.atleast_2d(xy)[:, 0], np.atleast_2d(xy)[:, 1]),
                                     dtype=float) * np.ones(len(np.atleast_2d(xy)))
    raise TypeError("pressure must be a CoefficientFunction, GridFunction, nodal array or callable")


def _source_points(mesh):
    """Named points (co-dimension 2 regions other than 'default') of a mesh: name -> (x, y)."""
    from ngsolve import BBND

    out = {}
    for el in mesh.Elements(BBND):
        if el.mat != "default" and el.mat not in out:
            out[el.mat] = tuple(mesh[el.vertices[0]].point)
    return out


def remesh(th: Thresholded, maxh: float, *, clamp=("fixed",), pressure=None,
           p_in: float | None = None, wet_fraction: float = 0.5, wet_boundaries=("inlet",),
           probe: float | None = None, min_spacing: float | None = None,
           spline_tol: float | None = None, domain=None) -> Remeshed:
    """Mesh the thresholded solid with Netgen triangles and carry the names over.

    Parameters
    ----------
    th : Thresholded
        Output of :func:`~pacto_ng.post.threshold.threshold`.
    maxh : float
        Element size of the new mesh.
    clamp : sequence of str
        Boundary names of the source that support the structure.  Pieces touching none of them
        are dropped; empty: keep every piece.
    pressure : CoefficientFunction, GridFunction, ndarray or callable, optional
        The pressure field on the source mesh (see :func:`pressure_sampler`); None: only the
        ``wet_boundaries`` are wetted.
    p_in : float, optional
        Inlet pressure of the wetting rule; default the largest nodal pressure.
    wet_fraction : float
        A segment inside the domain is wetted where ``p(probe point) >= wet_fraction * p_in``.
    wet_boundaries : sequence of str
        Source boundaries whose solid parts are wetted (the fluid lies beyond them).
    probe : float, optional
        Distance of the probe point from the segment midpoint, default the source element size.
    min_spacing, spline_tol : float, optional
        Geometry parameters of :func:`build_geometry`.
    domain : netgen.occ shape, optional
        The geometry the source mesh was made from (a face, or a glued compound of named
        faces).  Given, the part is built by :func:`build_domain_geometry`: wherever the solid
        reaches the domain's boundary (a curved outline, a hole, the wall of a void face) the
        part's boundary is that edge of the domain, with its name; the faces named in
        ``th.excluded`` (the ``exclude`` of :func:`~.threshold.threshold`: passive void faces)
        are not part of the domain.  Should that geometry fail (an OCC error, or Netgen cannot
        mesh it) the traced geometry is used and :attr:`Remeshed.geometry` says why.

    Returns
    -------
    Remeshed

    Raises
    ------
    ValueError
        If no solid touches the clamp boundary, or ``maxh`` is not positive.
    """
    import ngsolve
    from netgen.meshing import Element0D

    if maxh <= 0:
        raise ValueError("maxh must be positive")
    if not 0.0 < wet_fraction <= 1.0:
        raise ValueError(f"wet_fraction must lie in (0, 1], got {wet_fraction!r}")
    clamp = (clamp,) if isinstance(clamp, str) else tuple(clamp)
    comps = list(th.components)
    if not comps:
        raise ValueError("the thresholded design has no solid")
    if clamp:
        kept = [c for c in comps if c.names & set(clamp)]
        if not kept:
            raise ValueError(f"no solid touches the clamp boundary {'|'.join(clamp)} "
                             f"(threshold {th.threshold:g})")
    else:
        kept = comps
    dropped = sum(c.area for c in comps if c not in kept)

    src = th.source
    seg, names = outer_boundary(src)
    diam = float(np.ptp(seg.reshape(-1, 2), axis=0).max())
    locator = _BoundaryLocator(seg, names, 1e-8 * max(diam, th.h))
    ngm, geometry = None, "traced"
    if domain is not None:
        try:
            ngm = _generate(_domain_shape(th, kept, domain, min_spacing, spline_tol), maxh,
                            th.threshold)
            geometry = "domain"
        except Exception as err:  # OCC's and Netgen's errors: the traced part instead
            what = str(err).strip().splitlines()[0] if str(err).strip() else type(err).__name__
            geometry = f"traced (the part on the domain's geometry failed: {what})"
    if ngm is None:
        shape = build_geometry(kept, th.h, min_spacing=min_spacing, spline_tol=spline_tol,
                               locator=locator)
        ngm = _generate(shape, maxh, th.threshold)

    # -- the wetting rule, segment by segment ----------------------------------------------
    coords = np.asarray(ngm.Coordinates(), dtype=float)
    sample = pressure_sampler(pressure, src) if pressure is not None else None
    if sample is not None and p_in is None:
        p_in = float(np.max(sample(np.asarray(src.ngmesh.Coordinates(), dtype=float))))
    probe = th.h if probe is None else float(probe)
    centroid = {}
    for el in ngm.Elements2D():
        vs = [v.nr - 1 for v in el.vertices]
        c = coords[vs].mean(axis=0)
        for a, b in zip(vs, vs[1:] + vs[:1]):
            centroid[(min(a, b), max(a, b))] = c
    segs = list(ngm.Elements1D())
    ends = np.array([[v.nr - 1 for v in s.vertices][:2] for s in segs])
    mid = 0.5 * (coords[ends[:, 0]] + coords[ends[:, 1]])
    tang = coords[ends[:, 1]] - coords[ends[:, 0]]
    length = np.linalg.norm(tang, axis=1)
    normal = np.c_[tang[:, 1], -tang[:, 0]] / length[:, None]
    inner = np.array([centroid[(min(a, b), max(a, b))] for a, b in ends])
    flip = np.einsum("ij,ij->i", normal, inner - mid) > 0
    normal[flip] *= -1.0  # outward from the solid
    current = [ngm.GetBCName(s.index - 1) for s in segs]
    if geometry == "domain":
        # names are the domain's: wetted by name wherever the part runs along a wetted edge
        # (an outer inlet, or a chamber's wall); everywhere else by the pressure beyond it (a
        # probe point outside the source mesh sees none)
        wet = np.array([c in wet_boundaries for c in current])
        if sample is not None and p_in is not None and p_in > 0:
            q = mid + probe * normal
            inside = np.asarray(src(q[:, 0].copy(), q[:, 1].copy())["nr"]) >= 0
            pv = np.where(inside, sample(q), 0.0)
            wet |= pv >= wet_fraction * p_in
    else:
        on_outer = np.array([n is not None for n in locator.locate(mid)])
        wet = np.array([c in wet_boundaries for c in current]) & on_outer
        if sample is not None and p_in is not None and p_in > 0:
            pv = sample(mid + probe * normal)
            wet |= (~on_outer) & (pv >= wet_fraction * p_in)
    if wet.any():
        idx = ngm.AddRegion(PRESSURE, dim=1)
        for s, w in zip(segs, wet):
            if w:
                s.index = idx
    # -- named points --------------------------------------------------------------------
    ports = {}
    for name, (px, py) in _source_points(src).items():
        k = int(np.argmin(np.hypot(coords[:, 0] - px, coords[:, 1] - py)))
        idx = ngm.AddRegion(name, dim=0)
        ngm.Add(Element0D(k + 1, index=idx))
        ports[name] = ((px, py), tuple(coords[k]))
    mesh = ngsolve.Mesh(ngm)
    area = ngsolve.Integrate(ngsolve.CF(1.0), mesh)
    return Remeshed(mesh, float(area), th.area, float(dropped), ports,
                    float(length[wet].sum()), p_in, geometry)


def _domain_shape(th: Thresholded, kept, domain, min_spacing, spline_tol):
    """:func:`build_domain_geometry` of the kept pieces on ``domain`` without the excluded
    faces; the margin is ``0.25 h``, or three times the largest distance between the source
    mesh's boundary polyline and the domain's edges if that is more (at most ``2 h``)."""
    from .domain import BoundaryCurves, material_domain

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

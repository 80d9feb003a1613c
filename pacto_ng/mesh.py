"""Rectangular layouts with named boundaries, passive regions and ports, meshed two ways.

A :class:`Layout` is the geometry of every case of this toolkit: a rectangle ``[0, W] x [0, H]``
whose outer boundary is cut into named segments, passive rectangles inside it (``solid``,
``void`` or a pressurised ``cavity``) and named points (ports).  It is meshed either with
Netgen triangles (OCC geometry, :func:`netgen_mesh`) or as a structured grid of
``nelx x nely`` quadrilaterals (:func:`structured_mesh`), with the *same* region and boundary
names in both:

* materials: ``design`` and the names of the passive rectangles;
* boundaries: the segment names, ``free`` for the rest of the outer boundary, and for a
  rectangle with ``boundary=NAME`` (a cavity) its edges inside the domain get that name;
* points (co-dimension 2): the port names.

Every geometry, a Layout or another (:func:`pacto_ng.meshing.mesh_geometry`), is meshed into a
:class:`Meshed` domain: the mesh, its element size and the shape it was made from.
"""
from __future__ import annotations

import sys
from dataclasses import dataclass

import numpy as np

_TOL = 1e-9


@dataclass
class Meshed:
    """A meshed domain: the ``ngsolve.Mesh``, its element size ``h``, and the netgen.occ
    ``shape`` it was meshed from (``None`` for a mesh file or a structured grid)."""

    mesh: object
    h: float
    shape: object = None

    @property
    def dim(self) -> int:
        return self.mesh.dim


@dataclass(frozen=True)
class Segment:
    """A named straight part of the outer boundary from ``start`` to ``end``."""

    name: str
    start: tuple[float, float]
    end: tuple[float, float]


@dataclass(frozen=True)
class Region:
    """A passive rectangle ``[x0, x1] x [y0, y1]``.  ``kind`` is ``solid`` or ``void``;
    ``boundary`` names its edges that lie inside the domain (e.g. ``inlet`` for a cavity)."""

    name: str
    kind: str
    x0: float
    y0: float
    x1: float
    y1: float
    boundary: str | None = None

    def __post_init__(self):
        if self.kind not in ("solid", "void"):
            raise ValueError(f"region '{self.name}': kind must be 'solid' or 'void', not '{self.kind}'")
        if not (self.x1 > self.x0 and self.y1 > self.y0):
            raise ValueError(f"region '{self.name}' is empty")

    def contains(self, px, py, tol=_TOL) -> np.ndarray:
        return (px > self.x0 - tol) & (px < self.x1 + tol) & (py > self.y0 - tol) & (py < self.y1 + tol)


@dataclass(frozen=True)
class Layout:
    """A rectangle with named boundary segments, passive regions and ports."""

    width: float
    height: float
    segments: tuple[Segment, ...] = ()
    regions: tuple[Region, ...] = ()
    points: tuple[tuple[str, tuple[float, float]], ...] = ()

    def __post_init__(self):
        if self.width <= 0 or self.height <= 0:
            raise ValueError("layout width and height must be positive")
        for s in self.segments:
            for px, py in (s.start, s.end):
                if not self._on_outer(px, py):
                    raise ValueError(f"segment '{s.name}' does not lie on the outer boundary")

    # -- helpers ------------------------------------------------------------------------
    def _on_outer(self, px, py, tol=1e-9):
        W, H = self.width, self.height
        t = tol * max(W, H)
        return abs(px) < t or abs(px - W) < t or abs(py) < t or abs(py - H) < t

    def outer_name(self, px: float, py: float) -> str:
        """Name of the outer-boundary point (px, py) (a midpoint of an edge)."""
        t = 1e-9 * max(self.width, self.height)
        for s in self.segments:
            (ax, ay), (bx, by) = s.start, s.end
            ex, ey = bx - ax, by - ay
            ln2 = ex * ex + ey * ey
            lam = ((px - ax) * ex + (py - ay) * ey) / ln2
            qx, qy = ax + lam * ex, ay + lam * ey
            if -1e-9 <= lam <= 1 + 1e-9 and abs(qx - px) < t and abs(qy - py) < t:
                return s.name
        return "free"

    def material(self, px, py) -> str:
        for r in self.regions:
            if r.contains(px, py, tol=0.0):
                return r.name
        return "design"

    def perimeter_points(self) -> list[tuple[float, float]]:
        """Counter-clockwise corner and break points of the outer boundary."""
        W, H = self.width, self.height
        pts = {(0.0, 0.0), (W, 0.0), (W, H), (0.0, H)}
        cand = [s.start for s in self.segments] + [s.end for s in self.segments]
        for r in self.regions:
            cand += [(r.x0, r.y0), (r.x1, r.y0), (r.x1, r.y1), (r.x0, r.y1)]
        cand += [p for _, p in self.points]
        for px, py in cand:
            if self._on_outer(px, py):
                pts.add((float(px), float(py)))

        def arclength(p):
            px, py = p
            t = 1e-9 * max(W, H)
            if abs(py) < t:
                return px
            if abs(px - W) < t:
                return W + py
            if abs(py - H) < t:
                return W + H + (W - px)
            return 2 * W + H + (H - py)

        return sorted(pts, key=arclength)


# ---------------------------------------------------------------------------------------
def layout_shape(layout: Layout):
    """The netgen.occ shape of ``layout``: faces named ``design`` and by the passive rectangles,
    edges by the segments (``free`` elsewhere on the outer boundary) and the rectangles'
    ``boundary``, vertices by the points."""
    from netgen import occ

    pts = layout.perimeter_points()
    wp = occ.WorkPlane().MoveTo(*pts[0])
    for p in pts[1:]:
        wp.LineTo(*p)
    wp.Close()
    outer = wp.Face()
    faces = []
    cut = outer
    for r in layout.regions:
        rf = occ.WorkPlane().MoveTo(r.x0, r.y0).Rectangle(r.x1 - r.x0, r.y1 - r.y0).Face()
        cut = cut - rf
        rf.faces.name = r.name
        faces.append(rf)
    cut.faces.name = "design"
    shape = occ.Glue([cut] + faces) if faces else cut
    # name the edges by where they lie
    for e in shape.edges:
        c = e.center
        if layout._on_outer(c.x, c.y):
            e.name = layout.outer_name(c.x, c.y)
        else:
            e.name = None
            for r in layout.regions:
                if r.boundary and _on_rect_boundary(r, c.x, c.y):
                    e.name = r.boundary
    for name, (px, py) in layout.points:
        v = shape.vertices.Nearest((px, py, 0))
        if _at_vertex(v, px, py, layout):
            v.name = name
    return shape


def _at_vertex(vertex, px, py, layout) -> bool:
    p = vertex.p
    return abs(p.x - px) + abs(p.y - py) <= 1e-9 * max(layout.width, layout.height)


def netgen_mesh(layout: Layout, maxh: float, *, quad_dominated: bool = False):
    """Netgen triangle mesh of ``layout`` with element size ``maxh`` (returns ngsolve.Mesh).

    A point that is a vertex of the layout (a corner, a segment's end, a region's corner) is
    that vertex of the mesh; any other point is the mesh node nearest to it."""
    from netgen import occ
    from netgen.meshing import Element0D
    import ngsolve

    shape = layout_shape(layout)
    geo = occ.OCCGeometry(shape, dim=2)
    ngm = geo.GenerateMesh(maxh=maxh, quad_dominated=quad_dominated)
    inner = [(name, xy) for name, xy in layout.points
             if not _at_vertex(shape.vertices.Nearest((*xy, 0)), *xy, layout)]
    if inner:
        coords = np.array([[p[0], p[1]] for p in ngm.Points()])
        for name, (px, py) in inner:
            k = int(np.argmin((coords[:, 0] - px) ** 2 + (coords[:, 1] - py) ** 2))
            ngm.Add(Element0D(k + 1, index=ngm.AddRegion(name, dim=0)))
    return ngsolve.Mesh(ngm)


def _on_rect_boundary(r: Region, px, py, tol=1e-9):
    s = tol * max(r.x1 - r.x0, r.y1 - r.y0)
    inx = r.x0 - s <= px <= r.x1 + s
    iny = r.y0 - s <= py <= r.y1 + s
    return (inx and iny) and (abs(px - r.x0) < s or abs(px - r.x1) < s or abs(py - r.y0) < s
                              or abs(py - r.y1) < s)


def structured_mesh(layout: Layout, nelx: int, nely: int):
    """Structured ``nelx x nely`` quadrilateral mesh of ``layout`` (returns ngsolve.Mesh).

    Element ``(i, j)`` (column i from the left, row j from the bottom) is the NGSolve element
    ``j * nelx + i``.  Region membership is decided by the element centroid, boundary names by
    the edge midpoint, ports by the nearest node.
    """
    from netgen.meshing import Element0D, Element1D, Element2D, FaceDescriptor, MeshPoint, Pnt
    from netgen.meshing import Mesh as NGMesh
    import ngsolve

    if nelx < 1 or nely < 1:
        raise ValueError("nelx and nely must be positive")
    W, H = layout.width, layout.height
    xs = np.linspace(0.0, W, nelx + 1)
    ys = np.linspace(0.0, H, nely + 1)
    m = NGMesh(dim=2)
    pid = np.empty((nelx + 1, nely + 1), dtype=object)
    for j in range(nely + 1):
        for i in range(nelx + 1):
            pid[i, j] = m.Add(MeshPoint(Pnt(xs[i], ys[j], 0.0)))
    names = ["design"] + [r.name for r in layout.regions]
    for k, nm in enumerate(names):
        m.Add(FaceDescriptor(surfnr=1, domin=k + 1, bc=1))
        m.SetMaterial(k + 1, nm)
    cx = 0.5 * (xs[:-1] + xs[1:])
    cy = 0.5 * (ys[:-1] + ys[1:])
    mat = np.zeros((nelx, nely), dtype=int)
    for k, r in enumerate(layout.regions):
        inside = r.contains(cx[:, None], cy[None, :], tol=0.0)
        if not inside.any():
            # a region smaller than an element: the element holding its centre represents it
            i = min(int(0.5 * (r.x0 + r.x1) / W * nelx), nelx - 1)
            j = min(int(0.5 * (r.y0 + r.y1) / H * nely), nely - 1)
            inside[i, j] = True
        mat[inside & (mat == 0)] = k + 1
    for j in range(nely):
        for i in range(nelx):
            m.Add(Element2D(mat[i, j] + 1, [pid[i, j], pid[i + 1, j], pid[i + 1, j + 1], pid[i, j + 1]]))
    bc_index: dict[str, int] = {}

    def add_edge(name, a, b):
        if name not in bc_index:
            bc_index[name] = m.AddRegion(name, dim=1)
        m.Add(Element1D([a, b], index=bc_index[name]))

    # outer boundary, counter-clockwise
    for i in range(nelx):
        add_edge(layout.outer_name(cx[i], 0.0), pid[i, 0], pid[i + 1, 0])
    for j in range(nely):
        add_edge(layout.outer_name(W, cy[j]), pid[nelx, j], pid[nelx, j + 1])
    for i in reversed(range(nelx)):
        add_edge(layout.outer_name(cx[i], H), pid[i + 1, nely], pid[i, nely])
    for j in reversed(range(nely)):
        add_edge(layout.outer_name(0.0, cy[j]), pid[0, j + 1], pid[0, j])
    # interior interfaces of named regions
    for k, r in enumerate(layout.regions):
        if not r.boundary:
            continue
        inside = mat == k + 1
        for i in range(nelx):
            for j in range(nely):
                if i + 1 < nelx and inside[i, j] != inside[i + 1, j]:
                    add_edge(r.boundary, pid[i + 1, j], pid[i + 1, j + 1])
                if j + 1 < nely and inside[i, j] != inside[i, j + 1]:
                    add_edge(r.boundary, pid[i, j + 1], pid[i + 1, j + 1])
    for name, (px, py) in layout.points:
        i = int(np.argmin(np.abs(xs - px)))
        j = int(np.argmin(np.abs(ys - py)))
        idx = m.AddRegion(name, dim=0)
        m.Add(Element0D(pid[i, j], index=idx))
    _say_snapped_segments(layout, xs, ys)
    return ngsolve.Mesh(m)


def _say_snapped_segments(layout: Layout, xs: np.ndarray, ys: np.ndarray) -> None:
    """One line on stderr naming the segments whose ends fall between the grid's nodes: each
    takes the whole element edges whose midpoints it covers, so its length is not the one
    given (e.g. the cantilever's load_width of 0.036 m and 0.04 m give the same patch)."""
    tol = 1e-9 * max(layout.width, layout.height)
    moved = []
    for seg in layout.segments:
        along_x = abs(seg.start[1] - seg.end[1]) <= tol  # a horizontal segment
        nodes = xs if along_x else ys
        ends = (seg.start[0], seg.end[0]) if along_x else (seg.start[1], seg.end[1])
        if any(np.min(np.abs(nodes - e)) > tol for e in ends):
            lo, hi = sorted(ends)
            mids = 0.5 * (nodes[:-1] + nodes[1:])
            covered = np.flatnonzero((mids >= lo - tol) & (mids <= hi + tol))
            got = (nodes[covered[-1] + 1] - nodes[covered[0]]) if covered.size else 0.0
            moved.append(f"'{seg.name}' {hi - lo:.4g} -> {got:.4g}")
    if moved:
        print("mesh: boundaries ending between grid nodes cover whole element edges (length "
              "given -> covered): " + ", ".join(moved), file=sys.stderr)

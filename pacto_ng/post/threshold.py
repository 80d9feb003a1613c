"""From element densities to closed polygons of the solid (thesis §6, "the filtered design").

The element densities ρ̄ are smoothed to the mesh vertices (area-weighted mean of the elements
around a vertex), the mesh is clipped at the threshold with pyvista's ``clip_scalar`` (which
interpolates linearly along the element edges, so the cut is the ρ̄ = threshold iso-line of the
nodal field), and the boundary edges of the clipped solid are joined into closed loops by
pyvista's ``strip``.  Nesting decides a loop's role: a loop inside an even number of other loops
bounds the solid from outside, inside an odd number it bounds a hole.  Loops enclosing less than
``min_area`` (specks: tiny islands, pinholes) are removed.  Every loop is returned
counter-clockwise; every edge of a loop carries the name of the source mesh's outer boundary it
lies on (``None`` inside the domain), which :mod:`pacto_ng.post.remesh` turns into straight,
named segments.

``exclude`` (the names of passive void faces of a domain geometry, used with
:func:`pacto_ng.post.remesh.remesh`'s ``domain``) leaves those elements out: the nodal density
is averaged over the other elements only and the solid is sought among them, so the walls of
the excluded faces are boundary of the clipped mesh like the outer boundary (a solid wall along
a void chamber runs exactly along the chamber's wall instead of the iso-line half an element
off it).

Ties: a vertex whose nodal density equals the threshold (within 1e-9, e.g. the corner shared by
two solid and two void squares of a structured mesh) is counted as solid by raising it by 1e-9;
a value exactly at the threshold would make VTK emit zero-length edges and broken loops.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

_TIE = 1e-9  # nodal values this close to the threshold count as solid


@dataclass(frozen=True, eq=False)
class Loop:
    """A closed polygon, counter-clockwise, the first point not repeated at the end.

    Attributes
    ----------
    points : ndarray, shape (n, 2)
    labels : tuple of (str or None), length n
        ``labels[i]`` names the edge ``points[i] -> points[i+1]``: the source mesh's outer
        boundary it lies on, or ``None`` for an edge inside the domain.
    depth : int
        Number of other loops that enclose this one (even: outer boundary, odd: hole).
    """

    points: np.ndarray
    labels: tuple
    depth: int

    @property
    def area(self) -> float:
        """Enclosed area (positive)."""
        return abs(_signed_area(self.points))

    @property
    def is_hole(self) -> bool:
        return self.depth % 2 == 1

    @property
    def names(self) -> set:
        """The outer-boundary names this loop runs along."""
        return {lab for lab in self.labels if lab is not None}


@dataclass(frozen=True, eq=False)
class Component:
    """One connected piece of solid: an outer loop and the holes directly inside it."""

    outer: Loop
    holes: tuple[Loop, ...]

    @property
    def area(self) -> float:
        return self.outer.area - sum(h.area for h in self.holes)

    @property
    def names(self) -> set:
        """Every outer-boundary name the piece touches."""
        out = set(self.outer.names)
        for h in self.holes:
            out |= h.names
        return out

    @property
    def loops(self) -> tuple[Loop, ...]:
        return (self.outer,) + self.holes


@dataclass(frozen=True, eq=False)
class Thresholded:
    """The result of :func:`threshold`.

    Attributes
    ----------
    components : tuple of Component
        The solid pieces, specks removed.
    area : float
        Area of the clipped solid as pyvista measures it (specks included).
    threshold : float
    nodal : ndarray
        The smoothed nodal density (one value per source-mesh vertex, tie-broken).
    solid : pyvista.UnstructuredGrid
        The clipped solid.
    h : float
        Typical element size of the source mesh (median over elements).
    source : ngsolve.Mesh
        The mesh the densities live on.
    removed_area : float
        Net area of the removed specks (islands count positive, filled pinholes negative).
    excluded : frozenset of str
        Materials of the source mesh left out (the ``exclude`` of :func:`threshold`).
    """

    components: tuple[Component, ...]
    area: float
    threshold: float
    nodal: np.ndarray
    solid: object
    h: float
    source: object
    removed_area: float = 0.0
    excluded: frozenset = frozenset()

    @property
    def polygon_area(self) -> float:
        """Area enclosed by the returned polygons (= ``area - removed_area``)."""
        return float(sum(c.area for c in self.components))

    @property
    def loops(self) -> tuple[Loop, ...]:
        return tuple(lp for c in self.components for lp in c.loops)


# ---------------------------------------------------------------------------------------
def mesh_to_pyvista(mesh):
    """The 2D volume elements of an NGSolve mesh as a pyvista UnstructuredGrid (z = 0).

    Cells follow NGSolve's element order; triangles and quadrilaterals (also mixed) are
    supported.  Curved (high-order) geometry is ignored: only the vertices are used.
    """
    import pyvista as pv

    pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    if pts.shape[1] != 2:
        raise ValueError("only 2D meshes are supported")
    cells = [[v.nr - 1 for v in el.vertices] for el in mesh.ngmesh.Elements2D()]
    sizes = np.array([len(c) for c in cells])
    if not np.all((sizes == 3) | (sizes == 4)):
        raise ValueError("only triangles and quadrilaterals are supported")
    flat = np.concatenate([np.r_[len(c), c] for c in cells]).astype(np.int64)
    types = np.where(sizes == 3, pv.CellType.TRIANGLE, pv.CellType.QUAD).astype(np.uint8)
    return pv.UnstructuredGrid(flat, types, np.c_[pts, np.zeros(len(pts))])


def _grid_and_densities(mesh, rho):
    """The mesh as a pyvista grid and ``rho`` as a flat float array, one value per element."""
    grid = mesh_to_pyvista(mesh)
    rho = np.asarray(rho, dtype=float).ravel()
    if rho.shape[0] != grid.n_cells:
        raise ValueError(f"rho has {rho.shape[0]} values but the mesh has {grid.n_cells} elements")
    return grid, rho


def _cell_areas(grid) -> np.ndarray:
    return np.asarray(grid.compute_cell_sizes(length=False, area=True, volume=False)
                      .cell_data["Area"], dtype=float)


def nodal_density(mesh, rho) -> np.ndarray:
    """Area-weighted mean of the element densities around every vertex.

    Parameters
    ----------
    mesh : ngsolve.Mesh
    rho : array_like, shape (mesh.ne,)
        Element densities in NGSolve element order.

    Returns
    -------
    ndarray, shape (mesh.nv,)
        ``ρ_i = Σ_e A_e ρ_e / Σ_e A_e`` over the elements ``e`` sharing vertex ``i``.
    """
    grid, rho = _grid_and_densities(mesh, rho)
    return _nodal(grid, rho, _cell_areas(grid))


def _nodal(grid, rho, area):
    conn = grid.cell_connectivity
    offs = grid.cell_offsets
    counts = np.diff(offs)
    owner = np.repeat(np.arange(grid.n_cells), counts)
    num = np.bincount(conn, weights=(area * rho)[owner], minlength=grid.n_points)
    den = np.bincount(conn, weights=area[owner], minlength=grid.n_points)
    return num / den


def _element_size(grid, area) -> float:
    counts = np.diff(grid.cell_offsets)
    # side of the equilateral triangle / square of the same area
    side = np.where(counts == 3, np.sqrt(4.0 * area / np.sqrt(3.0)), np.sqrt(area))
    return float(np.median(side))


def element_materials(mesh) -> np.ndarray:
    """The material name of every 2D element (NGSolve element order)."""
    ngm = mesh.ngmesh
    return np.array([ngm.GetMaterial(el.index) for el in ngm.Elements2D()], dtype=object)


def _included(mesh, exclude) -> np.ndarray | None:
    """Boolean mask of the elements whose material is not in ``exclude`` (None: all)."""
    exclude = set((exclude,) if isinstance(exclude, str) else (exclude or ()))
    if not exclude:
        return None
    keep = ~np.isin(element_materials(mesh), list(exclude))
    if not keep.any():
        raise ValueError(f"every element of the mesh is in an excluded material "
                         f"({', '.join(sorted(exclude))})")
    return keep


def outer_boundary(mesh, exclude=()):
    """The outer boundary edges of a 2D NGSolve mesh and their names.

    With ``exclude`` (material names) the elements of those materials are left out: the
    boundary is that of the remaining elements, and an edge between a kept and an excluded
    element carries the name of the mesh's boundary element there (an interface name such
    as ``inlet``) or ``"free"``.

    Returns
    -------
    segments : ndarray, shape (m, 2, 2)
        End points of every edge that belongs to exactly one element.
    names : list of str
        The boundary name of each edge (``"free"`` when the mesh has no boundary element there).
    """
    from ngsolve import BND

    pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    keep = _included(mesh, exclude)
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
    return seg, [named.get(k, "free") for k in edges]


def _segment_distance(p, a, b):
    """Distance of the points ``p`` from the segments ``a -> b`` (broadcast over the leading
    axes; the last axis holds the coordinates)."""
    d = b - a
    lam = np.clip(np.einsum("...k,...k->...", p - a, d) / np.einsum("...k,...k->...", d, d),
                  0.0, 1.0)
    return np.linalg.norm(a + lam[..., None] * d - p, axis=-1)


class _BoundaryLocator:
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
        dist = _segment_distance(pts[:, None, :], self.seg[idx, 0], self.seg[idx, 1])
        best = np.argmin(dist, axis=1)
        out = []
        for i, j in enumerate(best):
            out.append(self.names[idx[i, j]] if dist[i, j] <= self.tol else None)
        return out


def _signed_area(p) -> float:
    x, y = p[:, 0], p[:, 1]
    return 0.5 * float(np.dot(x, np.roll(y, -1)) - np.dot(np.roll(x, -1), y))


def _polylines(poly):
    """Point-id lists of the polylines of a pyvista PolyData (``lines`` array)."""
    lines = poly.lines
    out, i = [], 0
    while i < len(lines):
        n = lines[i]
        out.append(list(lines[i + 1:i + 1 + n]))
        i += n + 1
    return out


def _close_loops(chains):
    """Join point-id chains that share end points into closed loops (first id not repeated)."""
    loops, open_ = [], []
    for c in chains:
        if len(c) > 2 and c[0] == c[-1]:
            loops.append(c[:-1])
        else:
            open_.append(list(c))
    while open_:
        cur = open_.pop()
        grown = True
        while grown and cur[0] != cur[-1]:
            grown = False
            for k, c in enumerate(open_):
                if c[0] == cur[-1]:
                    cur += c[1:]
                elif c[-1] == cur[-1]:
                    cur += c[::-1][1:]
                elif c[-1] == cur[0]:
                    cur = c[:-1] + cur
                elif c[0] == cur[0]:
                    cur = c[::-1][:-1] + cur
                else:
                    continue
                open_.pop(k)
                grown = True
                break
        if cur[0] != cur[-1] or len(cur) < 4:
            raise RuntimeError("the boundary of the thresholded solid does not form closed loops")
        loops.append(cur[:-1])
    return loops


def threshold(mesh, rho, threshold: float = 0.5, *, min_area: float | None = None,
              exclude=()) -> Thresholded:
    """Threshold element densities into closed polygons of the solid.

    Parameters
    ----------
    mesh : ngsolve.Mesh
        2D mesh of triangles and/or quadrilaterals.
    rho : array_like, shape (mesh.ne,)
        Element densities ρ̄ in NGSolve element order.
    threshold : float
        Iso-value in (0, 1): the solid is where the smoothed nodal density is >= threshold.
    min_area : float, optional
        Loops enclosing less area are removed (islands dropped, pinholes filled).
        Default ``4 h²`` with ``h`` the median element size.
    exclude : iterable of str
        Materials left out (passive void faces, see the module docstring).

    Returns
    -------
    Thresholded

    Raises
    ------
    ValueError
        If ``threshold`` is not in (0, 1), ``rho`` has the wrong length, or nothing is solid.
    """
    if not (0.0 < float(threshold) < 1.0):
        raise ValueError(f"threshold must lie in (0, 1), got {threshold!r}")
    threshold = float(threshold)
    grid, rho = _grid_and_densities(mesh, rho)
    area = _cell_areas(grid)
    h = _element_size(grid, area)
    keep = _included(mesh, exclude)
    nodal = _nodal(grid, rho, area)
    if keep is not None:
        # the average over the kept elements only (vertices of excluded elements alone keep
        # the full average)
        with np.errstate(invalid="ignore", divide="ignore"):
            inner = _nodal(grid, rho, np.where(keep, area, 0.0))
        nodal = np.where(np.isfinite(inner), inner, nodal)
    nodal = np.where(np.abs(nodal - threshold) <= _TIE, threshold + _TIE, nodal)
    grid.point_data["rho"] = nodal
    base = grid if keep is None else grid.extract_cells(np.flatnonzero(keep))
    solid = base.clip_scalar(scalars="rho", value=threshold, invert=False)
    if solid.n_cells == 0:
        raise ValueError(f"no element reaches the threshold {threshold} (max nodal density "
                         f"{nodal.max():.3g})")
    solid_area = float(_cell_areas(solid).sum())
    edges = solid.extract_feature_edges(boundary_edges=True, non_manifold_edges=False,
                                        feature_edges=False, manifold_edges=False)
    chains = _polylines(edges.strip(join=True))
    ids = _close_loops(chains)
    pts2 = np.asarray(edges.points)[:, :2]

    seg, names = outer_boundary(mesh, exclude if keep is not None else ())
    diam = float(np.ptp(pts2, axis=0).max()) if len(pts2) else 1.0
    locator = _BoundaryLocator(seg, names, 1e-8 * max(diam, h))

    raw = []
    for loop in ids:
        p = pts2[loop]
        if _signed_area(p) < 0:
            p = p[::-1]
        mid = 0.5 * (p + np.roll(p, -1, axis=0))
        raw.append((p, tuple(locator.locate(mid))))

    # nesting depth by point-in-polygon tests (loops do not cross)
    from matplotlib.path import Path

    paths = [Path(p) for p, _ in raw]
    depth = []
    for i, (p, _) in enumerate(raw):
        probe = 0.5 * (p[0] + p[1])  # an edge midpoint: never a vertex of another loop
        depth.append(sum(1 for j, pa in enumerate(paths) if j != i and pa.contains_point(probe)))
    loops = [Loop(p, lab, d) for (p, lab), d in zip(raw, depth)]

    if min_area is None:
        min_area = 4.0 * h * h
    # a loop is kept if it and every loop enclosing it are large enough
    keep = [lp.area >= min_area for lp in loops]
    for i, lp in enumerate(loops):
        probe = 0.5 * (lp.points[0] + lp.points[1])
        for j, pa in enumerate(paths):
            if j != i and not keep[j] and loops[j].depth < lp.depth and pa.contains_point(probe):
                keep[i] = False
    removed = sum((-1) ** lp.depth * lp.area for lp, k in zip(loops, keep) if not k)
    kept = [lp for lp, k in zip(loops, keep) if k]
    # nesting among the kept loops only (a filled pinhole no longer counts)
    kpaths = [Path(lp.points) for lp in kept]
    kdepth = []
    for i, lp in enumerate(kept):
        probe = 0.5 * (lp.points[0] + lp.points[1])
        kdepth.append(sum(1 for j, pa in enumerate(kpaths) if j != i and pa.contains_point(probe)))
    kept = [Loop(lp.points, lp.labels, d) for lp, d in zip(kept, kdepth)]
    comps = []
    for i, lp in enumerate(kept):
        if lp.is_hole:
            continue
        holes = []
        for j, hl in enumerate(kept):
            probe = 0.5 * (hl.points[0] + hl.points[1])
            if hl.depth == lp.depth + 1 and kpaths[i].contains_point(probe):
                holes.append(hl)
        comps.append(Component(lp, tuple(holes)))
    comps.sort(key=lambda c: -c.area)
    excluded = frozenset() if keep is None else frozenset(
        (exclude,) if isinstance(exclude, str) else exclude)
    return Thresholded(tuple(comps), solid_area, threshold, nodal, solid, h, mesh, float(removed),
                       excluded)


# ---------------------------------------------------------------------------------------
# choosing the threshold
def design_volume(mesh, rho) -> float:
    """``Σ_e A_e ρ̄_e``: the material volume (area) of the density design."""
    grid, rho = _grid_and_densities(mesh, rho)
    return float(np.dot(_cell_areas(grid), rho))


def volume_threshold(mesh, rho, *, tol: float = 1e-4) -> float:
    """The threshold whose solid has the design's material volume (a volume-preserving threshold).

    The area of the solid ``{ρ_nodal >= t}`` (clipped as in :func:`threshold`, specks included)
    falls as ``t`` rises, so ``t`` is found by bisection to within ``tol`` such that that area
    equals :func:`design_volume`.  A crisp design gives a value near 0.5; grey material (ρ̄
    between 0 and 1, counted at its density by the volume) moves it.

    Raises
    ------
    ValueError
        If the design has no material.
    """
    grid, rho = _grid_and_densities(mesh, rho)
    area = _cell_areas(grid)
    target = float(np.dot(area, rho))
    if not target > 0.0:
        raise ValueError("the design has no material: no volume-preserving threshold")
    grid.point_data["rho"] = _nodal(grid, rho, area)

    def solid_area(t):
        part = grid.clip_scalar(scalars="rho", value=t, invert=False)
        return float(_cell_areas(part).sum()) if part.n_cells else 0.0

    lo, hi = 1e-3, 1.0 - 1e-3  # solid_area(lo) >= target >= solid_area(hi) (or the ends)
    if solid_area(hi) >= target:
        return hi
    if solid_area(lo) <= target:
        return lo
    while hi - lo > tol:
        mid = 0.5 * (lo + hi)
        if solid_area(mid) >= target:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def _near(loop: Loop, point, tol: float) -> bool:
    """Whether ``point`` is within ``tol`` of an edge of ``loop``."""
    a = loop.points
    return bool(np.min(_segment_distance(point, a, np.roll(a, -1, axis=0))) <= tol)


def _inside(loop: Loop, point) -> bool:
    from matplotlib.path import Path

    return bool(Path(loop.points).contains_point(point))


def part_contains(th: Thresholded, point, clamp=("fixed",)) -> bool:
    """Whether ``point`` lies in (or on the boundary of) a piece of ``th`` touching ``clamp``.

    That piece is what :func:`~pacto_ng.post.remesh.remesh` keeps; with an empty ``clamp``
    every piece counts.  A point on a hole's boundary counts as in the piece.
    """
    point = np.asarray(point, dtype=float).ravel()[:2]
    tol = 1e-6 * th.h
    clamp = set((clamp,) if isinstance(clamp, str) else clamp)
    for comp in th.components:
        if clamp and not comp.names & clamp:
            continue
        if not (_near(comp.outer, point, tol) or _inside(comp.outer, point)):
            continue
        if not any(_inside(h, point) and not _near(h, point, tol) for h in comp.holes):
            return True
    return False


def connecting_threshold(mesh, rho, start: float, point, clamp=("fixed",), *,
                         floor: float = 0.1, resolution: float = 0.005, exclude=()):
    """The largest threshold ``t <= start`` at which the part kept on ``clamp`` contains ``point``.

    A lower threshold only adds solid, so whether the point is in the kept part is monotone in
    ``t`` and bisection between ``floor`` and ``start`` finds ``t`` to within ``resolution``
    (the value returned is the lower end of the last bracket: one that contains the point).
    ``exclude`` is passed to :func:`threshold`.

    Returns
    -------
    (t, Thresholded) or (None, Thresholded at ``start``)
        ``None`` if the point is not in the kept part even at ``floor``.
    """
    th = threshold(mesh, rho, start, exclude=exclude)
    if part_contains(th, point, clamp):
        return start, th
    low = threshold(mesh, rho, floor, exclude=exclude) if floor < start else th
    if not part_contains(low, point, clamp):
        return None, th
    lo, hi = floor, start
    while hi - lo > resolution:
        mid = 0.5 * (lo + hi)
        cand = threshold(mesh, rho, mid, exclude=exclude)
        if part_contains(cand, point, clamp):
            lo, low = mid, cand
        else:
            hi = mid
    return lo, low

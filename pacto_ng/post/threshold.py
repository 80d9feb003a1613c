"""From element densities to closed polygons of the solid (thesis §6, "the filtered design").

The element densities ρ̄ are smoothed to the mesh vertices (area-weighted mean of the elements
around a vertex), the mesh is clipped at the threshold with pyvista's ``clip_scalar`` (which
interpolates linearly along the element edges, so the cut is the ρ̄ = threshold iso-line of the
nodal field), and the boundary edges of the clipped solid are joined into closed loops by
pyvista's ``strip``.  Nesting decides a loop's role: a loop inside an even number of other loops
bounds the solid from outside, inside an odd number it bounds a hole.  Loops enclosing less than
``min_area`` (specks: tiny islands, pinholes) are removed.  Every loop is returned
counter-clockwise; every edge of a loop carries the name of the source mesh's outer boundary it
lies on (``None`` inside the domain), which :mod:`pacto_ng.post.traced` turns into straight,
named segments.  The smoothed densities come from :mod:`pacto_ng.post.grid`, the boundary names
from :mod:`pacto_ng.post.boundary`; which threshold to take is :mod:`pacto_ng.post.threshold_choice`.

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
from matplotlib.path import Path

from .boundary import BoundaryLocator, outer_boundary, segment_distance
from .grid import (area_weighted_nodal, cell_areas, element_size, grid_and_densities,
                   included_elements)

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

    def holds(self, point, tol: float) -> bool:
        """Whether ``point`` (x, y) lies in the piece: inside its outer loop and outside its
        holes, or within ``tol`` of one of its loops (a support point on its boundary)."""
        q = np.asarray(point, dtype=float)[:2]
        if any(segment_distance(q, lp.points, np.roll(lp.points, -1, axis=0)).min() <= tol
               for lp in self.loops):
            return True
        return Path(self.outer.points).contains_point(q) and not any(
            Path(h.points).contains_point(q) for h in self.holes)


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
    grid, rho = grid_and_densities(mesh, rho)
    area = cell_areas(grid)
    h = element_size(grid, area)
    keep = included_elements(mesh, exclude)
    nodal = _nodal_density(grid, rho, area, keep, threshold)
    grid.point_data["rho"] = nodal
    base = grid if keep is None else grid.extract_cells(np.flatnonzero(keep))
    solid = base.clip_scalar(scalars="rho", value=threshold, invert=False)
    if solid.n_cells == 0:
        raise ValueError(f"no element reaches the threshold {threshold} (max nodal density "
                         f"{nodal.max():.3g})")
    solid_area = float(cell_areas(solid).sum())
    raw = _labelled_loops(solid, mesh, exclude if keep is not None else (), h)
    paths, depth = _nesting([p for p, _ in raw])
    loops = [Loop(p, lab, d) for (p, lab), d in zip(raw, depth)]
    kept, removed = _without_specks(loops, paths, 4.0 * h * h if min_area is None else min_area)
    comps = _components(kept)
    excluded = frozenset() if keep is None else frozenset(
        (exclude,) if isinstance(exclude, str) else exclude)
    return Thresholded(tuple(comps), solid_area, threshold, nodal, solid, h, mesh, float(removed),
                       excluded)


def _nodal_density(grid, rho, area, keep, threshold: float) -> np.ndarray:
    """The element densities smoothed to the vertices (area-weighted; over the kept elements
    only where ``keep`` is given), values at the threshold tie-broken to solid."""
    nodal = area_weighted_nodal(grid, rho, area)
    if keep is not None:
        # the average over the kept elements only (vertices of excluded elements alone keep
        # the full average)
        with np.errstate(invalid="ignore", divide="ignore"):
            inner = area_weighted_nodal(grid, rho, np.where(keep, area, 0.0))
        nodal = np.where(np.isfinite(inner), inner, nodal)
    return np.where(np.abs(nodal - threshold) <= _TIE, threshold + _TIE, nodal)


def _labelled_loops(solid, mesh, exclude, h: float) -> list:
    """The boundary of the clipped solid as closed loops ``(points, labels)``, each
    counter-clockwise, every edge labelled with the source's outer boundary it lies on (the
    walls of the ``exclude`` faces count as outer boundary)."""
    edges = solid.extract_feature_edges(boundary_edges=True, non_manifold_edges=False,
                                        feature_edges=False, manifold_edges=False)
    chains = _polylines(edges.strip(join=True))
    ids = _close_loops(chains)
    pts2 = np.asarray(edges.points)[:, :2]

    seg, names = outer_boundary(mesh, exclude)
    diam = float(np.ptp(pts2, axis=0).max()) if len(pts2) else 1.0
    locator = BoundaryLocator(seg, names, 1e-8 * max(diam, h))

    raw = []
    for loop in ids:
        p = pts2[loop]
        if _signed_area(p) < 0:
            p = p[::-1]
        mid = 0.5 * (p + np.roll(p, -1, axis=0))
        raw.append((p, tuple(locator.locate(mid))))
    return raw


def _nesting(polygons) -> tuple[list, list]:
    """``(paths, depth)``: a matplotlib Path per polygon and the number of the others that
    enclose it, by point-in-polygon tests (the polygons do not cross)."""
    paths = [Path(p) for p in polygons]
    depth = []
    for i, p in enumerate(polygons):
        probe = 0.5 * (p[0] + p[1])  # an edge midpoint: never a vertex of another loop
        depth.append(sum(1 for j, pa in enumerate(paths) if j != i and pa.contains_point(probe)))
    return paths, depth


def _without_specks(loops: list, paths: list, min_area: float) -> tuple[list, float]:
    """``(kept, removed)``: the loops that enclose at least ``min_area`` and lie inside no
    loop that encloses less, their depths counted among themselves (a filled pinhole no
    longer counts), and the net area removed (islands positive, pinholes negative)."""
    # a loop is kept if it and every loop enclosing it are large enough
    large = [lp.area >= min_area for lp in loops]
    for i, lp in enumerate(loops):
        probe = 0.5 * (lp.points[0] + lp.points[1])
        for j, pa in enumerate(paths):
            if j != i and not large[j] and loops[j].depth < lp.depth and pa.contains_point(probe):
                large[i] = False
    removed = sum((-1) ** lp.depth * lp.area for lp, k in zip(loops, large) if not k)
    kept = [lp for lp, k in zip(loops, large) if k]
    # nesting among the kept loops only (a filled pinhole no longer counts)
    _, kdepth = _nesting([lp.points for lp in kept])
    return [Loop(lp.points, lp.labels, d) for lp, d in zip(kept, kdepth)], removed


def _components(kept: list) -> list:
    """The solid pieces: every outer loop with the holes directly inside it, largest first."""
    from matplotlib.path import Path

    kpaths = [Path(lp.points) for lp in kept]
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
    return comps

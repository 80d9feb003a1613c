"""Which threshold ``pacto analyse`` cuts the density design at, and why.

:func:`volume_threshold` is the threshold whose solid has the design's material volume
(:func:`design_volume`); :func:`part_contains` says whether points (the output ports) lie in the
part kept on the clamp; :func:`connecting_threshold` lowers a threshold until they all do (a
grey joint to an output is kept); :func:`choose_threshold` puts these together into the choice
``pacto analyse`` makes and records.
"""
from __future__ import annotations

import numpy as np

from .boundary import named_points, segment_distance
from .grid import area_weighted_nodal, cell_areas, grid_and_densities
from .threshold import Loop, Thresholded, threshold


def design_volume(mesh, rho) -> float:
    """``Σ_e A_e ρ̄_e``: the material volume (area) of the density design."""
    grid, rho = grid_and_densities(mesh, rho)
    return float(np.dot(cell_areas(grid), rho))


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
    grid, rho = grid_and_densities(mesh, rho)
    area = cell_areas(grid)
    target = float(np.dot(area, rho))
    if not target > 0.0:
        raise ValueError("the design has no material: no volume-preserving threshold")
    grid.point_data["rho"] = area_weighted_nodal(grid, rho, area)

    def solid_area(t):
        part = grid.clip_scalar(scalars="rho", value=t, invert=False)
        return float(cell_areas(part).sum()) if part.n_cells else 0.0

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
    return bool(np.min(segment_distance(point, a, np.roll(a, -1, axis=0))) <= tol)


def _inside(loop: Loop, point) -> bool:
    from matplotlib.path import Path

    return bool(Path(loop.points).contains_point(point))


def _point_in_part(th: Thresholded, point, clamp: set, tol: float) -> bool:
    for comp in th.components:
        if clamp and not comp.names & clamp:
            continue
        if not (_near(comp.outer, point, tol) or _inside(comp.outer, point)):
            continue
        if not any(_inside(h, point) and not _near(h, point, tol) for h in comp.holes):
            return True
    return False


def part_contains(th: Thresholded, points, clamp=("fixed",)) -> bool:
    """Whether every one of ``points`` (one point (x, y), or several (n, 2)) lies in (or on the
    boundary of) a piece of ``th`` touching ``clamp``.

    Those pieces are what :func:`~pacto_ng.post.remesh.remesh` keeps; with an empty ``clamp``
    every piece counts.  A point on a hole's boundary counts as in the piece.
    """
    pts = np.atleast_2d(np.asarray(points, dtype=float))[:, :2]
    tol = 1e-6 * th.h
    clamp = set((clamp,) if isinstance(clamp, str) else clamp)
    return all(_point_in_part(th, p, clamp, tol) for p in pts)


def connecting_threshold(mesh, rho, start: float, points, clamp=("fixed",), *,
                         floor: float = 0.1, resolution: float = 0.005, exclude=()):
    """The largest threshold ``t <= start`` at which the part kept on ``clamp`` contains every
    one of ``points`` (see :func:`part_contains`).

    A lower threshold only adds solid, so whether the points are in the kept part is monotone in
    ``t`` and bisection between ``floor`` and ``start`` finds ``t`` to within ``resolution``
    (the value returned is the lower end of the last bracket: one that contains the points).
    ``exclude`` is passed to :func:`threshold`.

    Returns
    -------
    (t, Thresholded) or (None, Thresholded at ``start``)
        ``None`` if the points are not all in the kept part even at ``floor``.
    """
    th = threshold(mesh, rho, start, exclude=exclude)
    if part_contains(th, points, clamp):
        return start, th
    low = threshold(mesh, rho, floor, exclude=exclude) if floor < start else th
    if not part_contains(low, points, clamp):
        return None, th
    lo, hi = floor, start
    while hi - lo > resolution:
        mid = 0.5 * (lo + hi)
        cand = threshold(mesh, rho, mid, exclude=exclude)
        if part_contains(cand, points, clamp):
            lo, low = mid, cand
        else:
            hi = mid
    return lo, low


def _named(names, total) -> str:
    """``the output point`` of a one-port case; else which of the points ``names`` are."""
    if total == 1:
        return "the output point"
    return (f"the output point {names[0]}" if len(names) == 1 else
            f"the output points {', '.join(names)}")


def choose_threshold(mesh, rho, requested, ports, clamp, *, connect: bool = True, exclude=()):
    """The threshold ``pacto analyse`` uses, and why: ``(record, Thresholded at it)``.

    ``requested`` is a number in (0, 1) or ``"volume"`` (the volume-preserving threshold).
    ``ports`` are the names of the output points (one, or several: a gripper's jaws).  With
    ``connect``, when the part kept on the clamp at that threshold does not contain every output
    point, the threshold is lowered to the largest value (down to 0.1, to within 0.005) at which
    it does: a joint to an output that is still grey is kept, at the price of the grey material
    around it.  The record says what was asked, what was used, the design's material volume,
    the area of the part at the threshold used and, per output point, whether the part holds it
    there (``ports``); its note names the points the part at the requested threshold misses.  A
    port that is no named point of ``mesh`` is not checked.  ``exclude``: materials left out of
    the thresholding (:func:`~pacto_ng.post.threshold.threshold`).
    """
    start = volume_threshold(mesh, rho) if requested == "volume" else float(requested)
    known = named_points(mesh)
    points = {name: known[name] for name in ports if name in known}
    rec = {"requested": requested, "start": start, "used": start, "lowered": False,
           "missed": False, "connect": bool(connect), "design_volume": design_volume(mesh, rho)}
    what = (f"threshold {start:.4g} (volume-preserving)" if requested == "volume"
            else f"threshold {start:g}")
    th = threshold(mesh, rho, start, exclude=exclude)
    missing = [name for name, p in points.items() if not part_contains(th, p, clamp)]
    them = _named(missing or list(points), len(points))
    if not points:
        rec["reaches_output"] = None
        rec["note"] = what
    elif not missing:
        rec["reaches_output"] = True
        rec["note"] = f"{what}: the part on the clamp contains {them}"
    elif not connect:
        rec["reaches_output"] = False
        rec["note"] = (f"{what}: the part on the clamp does not contain {them} (not lowered: "
                       f"--keep-threshold)")
    else:
        used, low = connecting_threshold(mesh, rho, start, list(points.values()), clamp,
                                         exclude=exclude)
        if used is None:
            rec.update(missed=True, reaches_output=False)
            rec["note"] = (f"{what}: the part on the clamp does not contain {them}, nor at "
                           f"threshold 0.1; analysed at {start:.4g}")
        else:
            th = low
            rec.update(used=used, lowered=True, reaches_output=True)
            rec["note"] = (f"{what} lowered to {used:.4g}: above it the part on the clamp does "
                           f"not contain {them} (a grey joint)")
    rec["ports"] = {name: part_contains(th, p, clamp) for name, p in points.items()}
    rec["part_area"] = th.area
    return rec, th

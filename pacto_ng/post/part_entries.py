"""The part's entries of ``analysis.json`` (:mod:`.report`): its measures (thresholded, kept,
remeshed), its materials, its named points and their shifts, its boundaries, and the
warnings a user must know beyond the figures.
"""
from __future__ import annotations

import numpy as np

from .materials import interface_length, material_areas
from .part3d import closed_checks
from .post3d import material_volumes
from .report import jsonable


def part_measures(part) -> dict:
    """The measures of a run's part (m² in 2D, m³ in 3D): thresholded, kept on the clamp,
    remeshed, and what was dropped on the way."""
    a, b = part.pieces
    if part.dim == 2:
        kept = a.polygon_area - b.dropped_area
        out = dict(thresholded=a.area, polygons=a.polygon_area, removed_specks=a.removed_area,
                   dropped_floating=b.dropped_area, kept=kept, remeshed=b.area)
    else:
        kept = a.volume_kept
        out = dict(thresholded=a.volume_thresholded, kept=kept, surface=a.volume,
                   remeshed=b.volume, pieces=a.pieces, dropped_pieces=a.dropped,
                   dropped_tetrahedra=b.dropped, **closed_checks(a.surface))
    out["remeshed_vs_kept"] = out["remeshed"] / kept - 1.0 if kept else None
    return out


def materials_entry(part, E, threshold2) -> dict | None:
    """analysis.json's ``materials`` for a part with a ``stiff`` region (else None): how the
    regions were made, threshold2, each region's modulus and measure (3D two-material runs:
    also in the clipped solid, ``part``; 2D: the interface's length)."""
    if not isinstance(E, dict):
        return None
    measures = {k: v for k, v in material_areas(part.mesh).items() if k in E}
    out = {"mode": part.materials or "as built", "threshold2": threshold2, "E": E,
           "remeshed": measures, "part": None, "interface_length": None}
    if part.dim == 3 and part.pieces[0] is not None and "material" in getattr(
            part.pieces[0].solid, "cell_data", {}):
        out["part"] = material_volumes(part.pieces[0].solid)
    if part.dim == 2:
        out["interface_length"] = interface_length(part.mesh)
    return out


def part_warnings(part, ports, sweeps, shown, h: float, unit: str) -> list[str]:
    """What a user must know of the part beyond its figures: an output point the part does
    not reach (its vertex more than two design elements ``h`` away), a sweep that stopped, a
    port that moves more across its direction than along it (in the ``shown`` kind's last
    converged state)."""
    out = []
    regions = {p.region for p in ports}
    for region, (src, new) in part.ports.items():
        shift = float(np.linalg.norm(np.subtract(new, src)))
        if region in regions and shift > 2.0 * h:
            out.append(f"the part does not reach the output point '{region}': its nearest "
                       f"vertex is {shift:.3g} m away (the output ends in void)")
    for kind, sw in sweeps.items():
        bad = [p for p in sw.points if not p.converged]
        if bad:
            above = "" if len(bad) == 1 else " nor above"
            out.append(f"the {kind} analysis did not converge at {bad[0].pressure:.4g} "
                       f"{unit} (equilibrium up to {100 * bad[0].load_reached:.3g} % of "
                       f"it){above}")
    if shown is not None:
        pt = sweeps[shown].points[int(np.flatnonzero(sweeps[shown].converged)[-1])]
        for port, vec in zip(ports, pt.vectors):
            d = np.asarray(port.direction, dtype=float) / np.linalg.norm(port.direction)
            v = np.asarray(vec, dtype=float)
            along = float(v @ d)
            across = float(np.linalg.norm(v - along * d))
            if across > abs(along):
                out.append(f"the output '{port.region}' moves more across its direction "
                           f"({across:.3g} m) than along it ({along:.3g} m) in the {shown} "
                           f"analysis at {pt.pressure:.4g} {unit}: the "
                           f"objective leaves that motion free")
    return out


def boundary_measures(mesh) -> dict:
    """The length (2D) or area (3D) of every named boundary of ``mesh``."""
    import ngsolve

    return {name: float(ngsolve.Integrate(1.0, mesh, ngsolve.BND,
                                          definedon=mesh.Boundaries(name)))
            for name in sorted(set(mesh.GetBoundaries()))}


def part_entry(part, ports, measures: dict) -> dict:
    """analysis.json's ``part``: :meth:`~.part.Part.summary`, its ``measures`` and its named
    points (source position, the part's vertex, the shift between them)."""
    entry = dict(part.summary(), measures=dict(measures), boundaries=boundary_measures(part.mesh))
    regions = {p.region for p in ports}
    entry["points"] = {k: {"source": list(map(float, a)), "new": list(map(float, b)),
                           "shift": float(np.linalg.norm(np.subtract(b, a)))}
                       for k, (a, b) in part.ports.items()}
    shifts = {k: v["shift"] for k, v in entry["points"].items() if k in regions}
    entry["port_shifts"] = shifts
    entry["output_port_shift"] = max(shifts.values()) if shifts else None
    return jsonable(entry)

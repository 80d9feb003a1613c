"""One call for the whole post-analysis of a density field (SPEC §7), writing its files.

:func:`post_analyse` chains :func:`~.threshold.threshold`, :func:`~.remesh.remesh`, the
sweeps of :mod:`.reanalysis` and the writers of :mod:`.export`, and writes into ``out_dir``:

=================  ====================================================================
``design.stl``     the thresholded, remeshed solid extruded by the thickness (watertight)
``remeshed.vtu``   the remeshed solid with ``u``, ``J``, ``stress``, ``von_mises``
``deformed.vtu``   the same in the deformed configuration
``deformed.png``   deformed solid over the undeformed outline, true scale (the whole part:
                   mirrored about a straight ``symmetry`` boundary of the source mesh)
``analysis.png``   Δ against pressure: expected, and every analysis kind
``analysis.csv``   one row per (kind, pressure): Δ, max |u|, min J, iterations, converged
``post.json``      threshold, areas, wetted length, ports, parameters and the sweeps
=================  ====================================================================

The deformed state is the last converged pressure of the ``follower`` sweep (else of the first
kind that converged somewhere).
"""
from __future__ import annotations

import csv
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ..physics.mechanics import Supports
from ..physics.newton import NewtonSettings
from .export import plot_deformed, plot_sweeps, write_stl, write_vtu
from .plots import mirror_line
from .reanalysis import Output, Reanalysis, pressure_body_force
from .remesh import remesh
from .threshold import threshold


@dataclass
class PostResult:
    """What :func:`post_analyse` computed and wrote."""

    thresholded: object
    remeshed: object
    sweeps: dict
    files: dict = field(default_factory=dict)
    summary: dict = field(default_factory=dict)


def post_analyse(mesh, rho, out_dir, *, pressures, E: float, nu: float, thickness: float,
                 output: Output, clamp=("fixed",), supports: Supports | None = None,
                 threshold_value: float = 0.5, thresholded=None,
                 maxh: float | None = None, pressure=None,
                 p_in: float | None = None, wet_fraction: float = 0.5,
                 wet_boundaries=("inlet",), kinds=("fixed", "follower"), darcy_pressure=None,
                 darcy_p_in: float | None = None, expected=None, order: int = 2,
                 newton: NewtonSettings = NewtonSettings(), domain=None, exclude=(),
                 mirror=True) -> PostResult:
    """Threshold, remesh, re-analyse and export a design.

    Parameters
    ----------
    mesh : ngsolve.Mesh
        The optimisation mesh.
    rho : array_like
        Element densities ρ̄ (NGSolve element order).
    out_dir : str or Path
        Created if missing.
    pressures : sequence of float
        The sweep, increasing (Pa).
    E, nu, thickness : float
        Neo-Hookean solid and out-of-plane thickness.
    output : Output
        Output point, direction and spring.
    clamp : sequence of str
        Clamp boundaries (pieces not touching them are dropped).
    supports : Supports, optional
        Default ``Supports(clamp=clamp)``; add e.g. ``fix_y=("symmetry",)``.
    threshold_value : float
        Density threshold in (0, 1).
    thresholded : Thresholded, optional
        :func:`~.threshold.threshold` of ``mesh, rho`` at ``threshold_value``, if the caller has
        it already (else computed here).
    maxh : float, optional
        Element size of the new mesh, default the optimisation mesh's.
    pressure, p_in, wet_fraction, wet_boundaries
        The wetting rule of :func:`~.remesh.remesh`.
    kinds : sequence of {"fixed", "follower", "darcy"}
    darcy_pressure : GridFunction or CF on ``mesh``, optional
        The Darcy pressure for the ``darcy`` kind, at inlet pressure ``darcy_p_in``.
    expected : tuple ``(pressures, deltas)``, optional
        What the optimisation predicted, for the plot and the summary.
    order : int
        Displacement order of the re-analysis.
    newton : NewtonSettings
    domain : netgen.occ shape, optional
        The geometry ``mesh`` was made from: the part keeps its edges (see
        :func:`~.remesh.remesh`).
    exclude : iterable of str
        Passive void materials left out of the thresholding (see
        :func:`~.threshold.threshold`; with ``domain``, the case's void faces).
    mirror : bool
        ``deformed.png`` shows the whole part of a case solved on a symmetric half (mirrored
        about ``mesh``'s straight ``symmetry`` boundary).  The files are of the half.
    """
    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    th = thresholded
    if th is None or th.threshold != threshold_value:
        th = threshold(mesh, rho, threshold_value, exclude=exclude)
    rm = remesh(th, th.h if maxh is None else maxh, clamp=clamp, pressure=pressure, p_in=p_in,
                wet_fraction=wet_fraction, wet_boundaries=wet_boundaries, domain=domain)
    supports = Supports(clamp=tuple(clamp)) if supports is None else supports
    supports = _present(supports, rm.mesh)
    kw = dict(E=E, nu=nu, thickness=thickness, supports=supports, output=output, order=order,
              newton=newton)
    sweeps = {}
    for kind in kinds:
        extra = {}
        if kind == "darcy":
            if darcy_pressure is None or darcy_p_in is None:
                raise ValueError("the darcy kind needs darcy_pressure and darcy_p_in")
            extra = dict(body=pressure_body_force(darcy_pressure), body_pressure=darcy_p_in)
        sweeps[kind] = Reanalysis(rm.mesh, kind, **kw, **extra).sweep(pressures)

    files = {"stl": out / "design.stl", "remeshed": out / "remeshed.vtu",
             "deformed": out / "deformed.vtu", "deformed_png": out / "deformed.png",
             "analysis_png": out / "analysis.png", "csv": out / "analysis.csv",
             "json": out / "post.json"}
    write_stl(files["stl"], rm.mesh, thickness)
    order_ = [k for k in ("follower",) + tuple(kinds) if k in sweeps]
    shown = next((k for k in order_ if sweeps[k].converged.any()), None)
    if shown is not None:
        u = sweeps[shown].displacement()
        i = int(np.flatnonzero(sweeps[shown].converged)[-1])
        write_vtu(files["remeshed"], rm.mesh, u, E=E, nu=nu)
        write_vtu(files["deformed"], rm.mesh, u, E=E, nu=nu, deformed=True)
        plot_deformed(files["deformed_png"], rm.mesh, u,
                      title=f"{shown} pressure {sweeps[shown].pressures[i]:.3g} Pa (true scale)",
                      mirror=mirror_line(mesh, mirror) or False)
    else:
        write_vtu(files["remeshed"], rm.mesh)
        for k in ("deformed", "deformed_png"):
            files.pop(k)
    plot_sweeps(files["analysis_png"], sweeps, expected=expected)
    rows = [row for sw in sweeps.values() for row in sw.table()]
    with open(files["csv"], "w", newline="") as fh:
        writer = csv.DictWriter(fh, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    summary = {
        "threshold": th.threshold, "thresholded_area": th.area,
        "polygon_area": th.polygon_area, "removed_speck_area": th.removed_area,
        "remeshed_area": rm.area, "dropped_floating_area": rm.dropped_area,
        "wetted_length": rm.wetted_length, "p_in": rm.p_in,
        "ports": {k: {"source": list(map(float, a)), "new": list(map(float, b))}
                  for k, (a, b) in rm.ports.items()},
        "elements": rm.mesh.ne, "geometry": rm.geometry, "order": order, "E": E, "nu": nu, "thickness": thickness,
        "supports": {"clamp": list(supports.clamp), "fix_x": list(supports.fix_x),
                     "fix_y": list(supports.fix_y)},
        "wet_boundaries": list(wet_boundaries),
        "output": {"region": output.region, "direction": list(output.direction),
                   "stiffness": output.stiffness},
        "deformed_state": shown,
        "expected": None if expected is None else [list(map(float, a)) for a in expected],
        "sweeps": {k: [_jsonable(r) for r in sw.table()] for k, sw in sweeps.items()},
    }
    files["json"].write_text(json.dumps(summary, indent=2))
    return PostResult(th, rm, sweeps, files, summary)


def _present(supports: Supports, mesh) -> Supports:
    """The supports restricted to the boundaries and points the remeshed solid has: a thresholded
    design need not touch every support of its domain (e.g. a symmetry line); the clamp is
    guaranteed by :func:`~.remesh.remesh`."""
    names = set(mesh.GetBoundaries()) | set(mesh.GetBBoundaries())
    keep = lambda group: tuple(n for n in group if n in names)
    return Supports(clamp=keep(supports.clamp), fix_x=keep(supports.fix_x),
                    fix_y=keep(supports.fix_y))


def _jsonable(row: dict) -> dict:
    out = {}
    for k, v in row.items():
        if isinstance(v, (np.floating, float)):
            v = float(v)
            out[k] = v if np.isfinite(v) else None
        elif isinstance(v, (np.integer, np.bool_)):
            out[k] = v.item()
        else:
            out[k] = v
    return out

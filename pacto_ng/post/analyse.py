"""``pacto analyse``: a part analysed over a sweep of pressures, one flow for 2D and 3D.

``pacto analyse DIR`` (a finished run, :func:`analyse_run`):

1. the run is loaded and rebuilt (its final design analysed at its load, as summary.json
   reports it); the **expected** Δ at every pressure P of the sweep is the density design
   with the run's own model at load factor P/load (:func:`expected_sweep`), on the run's
   mesh at the part's displacement order (:func:`~.runs.at_order`: the run's order-1
   elements are stiffer, and the gap is to measure making the part, not the order);
2. its **part** is made (:func:`~.part.make_part`: threshold chosen so that the part reaches
   every output, body-fitted remesh, the wetted walls named ``pressure`` by the run's final
   Darcy field at P_in = the run's load, the chambers' seal checked); only this step differs
   by dimension;
3. the part is analysed (:class:`~.part_analysis.PartAnalysis`) with the run's own material
   law (``--model`` names another) for each kind: ``darcy`` (the thresholded design's Darcy
   pressure as the body force −∇p, scaled with P/P_in), ``fixed`` and ``follower`` (the
   pressure on the wetted walls), one progress line per pressure;
4. what would take too long or not fit this machine is refused before anything is meshed,
   with one line giving the estimate of time and memory (:func:`check_resources`);
5. everything is written into ``DIR/analysis/`` (:func:`finish`).

``pacto analyse CASE --as-built`` (:mod:`.as_built`) takes the case's own geometry as the part
and runs steps 3-5 on it.  Files written (2D and 3D alike):

=================  ===========================================================================
``analysis.json``  one layout (:mod:`.report`): run, settings, part, seal, per pressure the
                   expected Δ and each kind's Δ, ports, max |u|, min J, iterations; gaps,
                   warnings, wall time
``analysis.csv``   one row per (kind, pressure)
``analysis.png``   Δ against P: expected and every kind (:func:`~.export.plot_sweeps`)
``deformed.png``   the deformed part at the largest converged P (follower if asked)
``materials.png``  2D, a part with a ``stiff`` region: the regions
``report.md``      the part, the seal, the analyses, the gap, the warnings, the pictures
``part.stl``       the part, closed, whole (mirrored about the symmetry lines or planes), in mm
``remeshed.vtu``   the part with u (and, for a run, the thresholded design's Darcy p), J,
                   stress and von Mises of the analysis's own energy
``deformed.vtu``   the same, points moved by u
=================  ===========================================================================
"""
from __future__ import annotations

import dataclasses
import json
import math
import sys
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from ..errors import InputError
from ..files import atomic_write_text
from ..params import Parameters
from ..physics.equilibrium import NewtonFailure
from ..threads import compute
from .cli_commands import check_threshold
from .domain import symmetry_line
from .export import material_names, plot_deformed, plot_materials, plot_sweeps, write_vtu
from .materials import STIFF
from .part import Part, make_part, part_ports, present_supports
from .part_analysis import PartAnalysis, pressure_body_force
from .part_resources import TIME_LIMIT, check_resources, part_estimate
from .part_stage import PART_MAXH, PART_ORDER, write_part_stl
from .plots3d import deformed_picture
from .post3d import solid_elements
from .report import (analysis_csv, analysis_json, jsonable, materials_entry, part_entry,
                     part_measures, part_warnings, ports_json, report_md, short_table)
from .runs import at_order, copy_gridfunction, design_delta, load_run, rebuild, thresholded_elements

#: the kinds of a run's part (``darcy`` needs the run's Darcy field), in this order
KINDS = ("darcy", "fixed", "follower")
#: a case's part as built: its displacement order when ``--order`` is not given, by dimension
#: (a run's part: the order and element size of the run's own part, :mod:`.part_stage`)
DEFAULT_ORDER = {2: 2, 3: 1}


@dataclass
class Subject:
    """What ``pacto analyse`` analyses: a run's part or a case as built (:mod:`.as_built`).

    ``mesh`` is the design's (the case's) mesh, whose symmetry lines or planes make the whole
    part; ``params`` the analysis's parameters (model, order, material); ``run`` the ``run``
    entry of analysis.json; ``expected`` the rows of :func:`expected_sweep` (None as built);
    ``darcy`` ``(p, P_in)``: the thresholded design's Darcy field on ``mesh`` (None as
    built); ``h`` the design's element size."""

    case: object
    params: Parameters
    setup: object
    mesh: object
    part: Part
    out: Path
    run: dict
    h: float
    expected: list | None = None
    darcy: tuple | None = None
    measures: dict = dataclasses.field(default_factory=dict)
    warnings: list = dataclasses.field(default_factory=list)


def _say(quiet, msg):
    if not quiet:
        print(msg, flush=True)


# -- the options ----------------------------------------------------------------------------
def parse_pressures(text: str) -> list[float]:
    """``"1e5,1e6"`` -> ``[1e5, 1e6]`` (sorted, duplicates removed); InputError otherwise."""
    out = []
    for item in str(text).split(","):
        item = item.strip()
        try:
            val = float(item)
        except ValueError:
            raise InputError(f"--pressures: cannot read '{item}' as a pressure (expected "
                             f"comma-separated numbers, e.g. 1e5,1e6)") from None
        if not math.isfinite(val) or val <= 0:
            raise InputError(f"--pressures: pressures must be positive and finite (got {item})")
        out.append(val)
    return sorted(set(out))


def default_pressures(load: float, n: int = 5, span: float = 100.0) -> list[float]:
    """``n`` log-spaced pressures from ``load / span`` to ``load``."""
    return [float(v) for v in np.geomspace(load / span, load, n)]


def check_kinds(kinds, allowed) -> tuple:
    """``--kinds``: a non-empty selection of ``allowed`` (in its order)."""
    kinds = tuple(kinds)
    bad = [k for k in kinds if k not in allowed]
    if bad or not kinds:
        raise InputError(f"--kinds: choose from {', '.join(allowed)} (got "
                         f"{','.join(kinds) or 'none'})")
    return tuple(k for k in allowed if k in kinds)


def analysis_params(params: Parameters, model: str | None, order: int) -> Parameters:
    """The part analysis's parameters: ``params`` with ``model`` (if given) and ``order``."""
    if order not in (1, 2, 3):
        raise InputError(f"--order: must be 1, 2 or 3, got {order}")
    if model == "auto" or (model is None and params.model == "auto"):
        raise InputError("--model: auto is chosen by a run from its first analysis; name the "
                         "model of the part's analysis")
    return params.replace(order=order, **({"model": model} if model else {}))


# -- the expected Δ ------------------------------------------------------------------------------
def expected_sweep(problem, pressures, load, **design) -> list[dict]:
    """Δ of the density design (``x=`` design variables, or ``rho_bar=`` physical densities)
    with the optimisation's own model at every pressure (load factor P/load; Newton with load
    stepping, warm-started along the sweep; after a failure the larger pressures are not
    attempted).  A linear model's Δ is linear in P (the Darcy pressure is linear in P_in):
    one analysis at the run's load, scaled.  Leaves the problem at the last pressure."""
    mech = problem.mech
    warm = mech.state
    mech.set_state(replace(warm, u=np.zeros_like(warm.u), converged=False))
    if mech.linear:
        with compute():
            mech.target = 1.0
            delta = float(problem.chain.forward(**design)["delta"])
        return [dict(pressure=P, delta=delta * P / load, newton_iterations=1, converged=True)
                for P in pressures]
    rows, failed = [], False
    with compute():
        for P in pressures:
            if failed:
                rows.append(dict(pressure=P, delta=None, newton_iterations=0, converged=False))
                continue
            mech.target = P / load
            try:
                vals = problem.chain.forward(**design)
                rows.append(dict(pressure=P, delta=float(vals["delta"]),
                                 newton_iterations=int(mech.result.iterations), converged=True))
            except NewtonFailure as err:
                failed = True
                rows.append(dict(pressure=P, delta=None,
                                 newton_iterations=int(err.result.iterations), converged=False,
                                 load_reached=float(err.result.load_reached) * load))
    return rows


def load_path_note(rebuilt, summary, rtol: float = 1e-4):
    """A note when the final design's Δ loaded from rest (``rebuilt``) differs from the
    optimisation's (``summary``, its equilibrium reached by warm starts along the design
    history) by more than ``rtol``: the design has more than one equilibrium at that load,
    so Δ depends on the load path; None when they agree (or one is missing)."""
    if rebuilt is None or summary is None:
        return None
    scale = max(abs(float(summary)), abs(float(rebuilt)), 1e-300)
    if abs(float(rebuilt) - float(summary)) <= rtol * scale:
        return None
    return (f"the final design's output displacement depends on the load path: {rebuilt:.4g} m "
            f"loaded from rest, {float(summary):.4g} m in summary.json (the optimisation's "
            f"equilibrium, reached by warm starts along the design history): the design has "
            f"more than one equilibrium at this load, and Δ below is read on the path from rest")


# -- a run's part ----------------------------------------------------------------------------
def analyse_run(folder, *, pressures=None, threshold_value=0.5, maxh=None, order=None,
                kinds=KINDS, quiet: bool = False, connect: bool = True, threshold2=0.5,
                model: str | None = None, time_limit: float = TIME_LIMIT) -> int:
    """``pacto analyse DIR``: the part of a finished run analysed (the module docstring).
    ``order`` and ``maxh`` default those of the run's own part (:mod:`.part_stage`: order 2,
    half the design's element size in 2D, the design's in 3D); ``model`` the part's
    analysis model (default the run's); ``connect`` lower the threshold until the part
    reaches every output (``--keep-threshold``: False).  Returns the exit code (0)."""
    t0 = time.perf_counter()
    threshold_value = check_threshold(threshold_value, allow_volume=True)
    threshold2 = check_threshold(threshold2, name="--threshold2")
    kinds = check_kinds(kinds, KINDS)
    if maxh is not None and not maxh > 0:
        raise InputError(f"--maxh: must be positive, got {maxh:g}")
    run = load_run(folder, "analyse")
    setup = run.case.make_setup(run.params)
    if setup.pressure is None:
        raise InputError(f"analyse: case '{run.case.name}' has no pressure load; the analysis "
                         f"applies to pressure cases only ('pacto export {folder}' writes its "
                         f"part)")
    if not setup.ports:
        raise InputError(f"analyse: case '{run.case.name}' has no output port")
    pressures = default_pressures(run.load) if pressures is None else list(pressures)
    _say(quiet, f"analyse {run.path}: {run.case.name}, model {run.params.model}, load "
                f"{run.load:g} {run.case.load_unit}, design '{run.design}' after {run.k} "
                f"iterations")
    with compute():
        problem = rebuild(run)
    dim = problem.mesh.dim
    params = analysis_params(run.params, model, order or PART_ORDER[dim])
    maxh = PART_MAXH[dim] * problem.h if maxh is None else float(maxh)
    est = part_estimate(problem, maxh, params.order, kinds)
    seconds = check_resources(est, f"--maxh = {maxh:g}", dim=dim, kinds=kinds,
                              n_pressures=len(pressures), model=params.model,
                              mesh_time_limit=run.params.mesh_time_limit, time_limit=time_limit)
    _say(quiet, f"  the part at maxh {maxh:g}, order {params.order}: about {est.elements:.3g} "
                f"{est.kind}, {est.dofs:.3g} dofs; the analysis about {seconds:.3g} s, "
                f"{est.memory / 1e9:.2g} GB")
    entry, p_final = _rebuilt_entry(run, problem, quiet)
    design = _at_part_order(problem, params.order, entry, quiet)
    expected = expected_sweep(design, pressures, run.load, x=run.x)
    _say(quiet, "  expected Δ: " + ", ".join(
        f"{r['pressure']:.3g} -> {r['delta']:.4g}" if r["converged"] else
        f"{r['pressure']:.3g} -> failed" for r in expected))
    part = make_part(problem, setup, threshold=threshold_value, maxh=maxh,
                     threshold2=threshold2, connect=connect, pressure=p_final, p_in=run.load,
                     mesh_time_limit=run.params.mesh_time_limit)
    _say(quiet, f"  {part.choice['note']}; the part: {part.mesh.ne} elements, "
                f"{part.measure:.4g} {'m²' if dim == 2 else 'm³'}"
                + ("" if part.seal is None else
                   f", {'sealed' if part.sealed else 'NOT SEALED'}"))
    darcy = _thresholded_darcy(problem, part)
    rounded = rounded_sweep(design, part, pressures, run.load)
    if rounded is not None:
        expected = [dict(e, rounded=r["delta"]) for e, r in zip(expected, rounded)]
    subject = Subject(run.case, params, setup, problem.mesh, part, run.path / "analysis",
                      entry, float(problem.h), expected, (darcy, run.load),
                      part_measures(part))
    subject.warnings += [w for w in (entry["load_path_note"], entry.get("failure")) if w]
    if part.sealed is False:
        subject.warnings.append("the part is not sealed: " + part.seal.message())
    settings = dict(threshold=part.threshold, threshold_choice=jsonable(part.choice),
                    threshold2=threshold2 if setup.materials == 2 else None, maxh=maxh)
    return finish(subject, kinds, pressures, settings, quiet=quiet, t0=t0)


def _rebuilt_entry(run, problem, quiet):
    """``(the 'run' entry of analysis.json, the run's final Darcy field)``."""
    delta = None if problem.failure else float(problem.values["delta"])
    summary = run.summary.get("output_displacement")
    # a run reported at its full load only (else summary.json's Δ is at another load)
    note = (load_path_note(delta, summary)
            if run.summary.get("load_factor_reached", 1.0) == 1.0 else None)
    _say(quiet, f"  rebuilt: Δ = {'—' if delta is None else format(delta, '.6g')} m at "
                f"{run.load:g} {run.case.load_unit} (summary.json: {summary})")
    entry = {"as_built": False, "dir": str(run.path), "case": run.case.name,
             "case_file": run.case.file or None, "model": run.params.model, "load": run.load,
             "load_unit": run.case.load_unit, "iterations": run.k, "design": run.design,
             "stopped": run.summary.get("stopped"), "output_displacement_summary": summary,
             "output_displacement_rebuilt": delta, "mesh_h": float(problem.h),
             "dim": problem.mesh.dim, "load_path_note": note}
    if problem.failure:
        entry["failure"] = (f"the run's own model fails on its final design at the full load "
                            f"({problem.failure}); the expected Δ is recorded where it "
                            f"converges")
    return entry, copy_gridfunction(problem.pressure_block.gfp)


def _at_part_order(problem, order, entry, quiet):
    """The run's problem at the part's ``order`` (:func:`~.runs.at_order`), its Δ at the
    run's load into the 'run' ``entry``; the run's problem where that has no equilibrium."""
    entry["expected_order"] = int(order)
    if problem.failure or int(problem.params.order) == int(order):
        entry["expected_order"] = int(problem.params.order)
        entry["output_displacement_at_order"] = entry["output_displacement_rebuilt"]
        return problem
    try:
        with compute():
            design = at_order(problem, order)
    except NewtonFailure as err:
        entry["expected_order"] = int(problem.params.order)
        entry["output_displacement_at_order"] = entry["output_displacement_rebuilt"]
        entry["order_note"] = (f"the design has no equilibrium at order {order} ({err}); the "
                               f"expected Δ is at the run's order")
        return problem
    entry["output_displacement_at_order"] = design_delta(design)
    _say(quiet, f"  the design at order {order}: Δ = "
                f"{entry['output_displacement_at_order']:.6g} m")
    return design


def rounded_density(problem, part: Part) -> np.ndarray:
    """The part's solid as element densities of the design mesh: 1 where at least half of an
    element lies in the clipped solid the part was made from, else 0 (2D
    :func:`~.runs.thresholded_elements`, 3D :func:`~.post3d.solid_elements`)."""
    source = part.pieces[0]
    return (thresholded_elements(source) if part.dim == 2 else
            solid_elements(source.solid, problem.field.areas))


def rounded_sweep(problem, part: Part, pressures, load) -> list[dict] | None:
    """:func:`expected_sweep` of the part's solid rounded onto the design mesh
    (:func:`rounded_density`): the first step from the density design to the part, which
    the gap's decomposition (:mod:`.report`, ``gap_parts``) takes apart from remeshing and
    from the load on the walls.  None for two materials (one rounded field is not their
    design)."""
    if problem.n_design_fields != 1:
        return None
    rho = rounded_density(problem, part)
    rho[problem.field.solid] = 1.0
    rho[problem.field.void] = 0.0
    return expected_sweep(problem, pressures, load, rho_bar=rho)


def _thresholded_darcy(problem, part: Part):
    """The Darcy field of the thresholded design (:func:`rounded_density`) at P_in = the
    run's load."""
    rho = rounded_density(problem, part)
    block = problem.pressure_block
    with compute():
        block.forward(rho)
    return copy_gridfunction(block.gfp)


# -- steps 3 and 5, for every part --------------------------------------------------------
def finish(subject: Subject, kinds, pressures, settings: dict, *, quiet: bool, t0: float) -> int:
    """Analyse the part of ``subject`` for every kind over ``pressures`` and write the files
    of the module docstring into ``subject.out``; ``settings`` holds what the flow chose (the
    threshold and its choice, threshold2, maxh).  Returns 0."""
    part, params = subject.part, subject.params
    ports = part_ports(subject.setup)
    supports = present_supports(subject.setup.supports, part.mesh)
    sweeps = {kind: _sweep(subject, kind, pressures, ports, supports, quiet) for kind in kinds}
    shown = next((k for k in ("follower",) + tuple(kinds) if k in sweeps
                  and sweeps[k].converged.any()), None)
    E = region_moduli(part.mesh, params)
    ana = next(iter(sweeps.values())).analysis
    settings = dict(settings, model=params.model, material=params.material, E=E, nu=params.nu,
                    thickness=params.thickness if part.dim == 2 else None,
                    plane=params.plane if part.dim == 2 else None, order=ana.order,
                    formulation=ana.formulation, pressures=[float(P) for P in pressures],
                    supports=dataclasses.asdict(supports), output_ports=ports_json(ports))
    deformed = {"kind": shown, "pressure": None if shown is None else float(
        sweeps[shown].pressures[np.flatnonzero(sweeps[shown].converged)[-1]])}
    warnings = subject.warnings + part_warnings(part, ports, sweeps, shown, subject.h,
                                                subject.run["load_unit"])
    data = analysis_json(
        run=subject.run, settings=jsonable(settings),
        part=part_entry(part, ports, subject.measures),
        seal=None if part.seal is None else part.seal.to_json(),
        materials=materials_entry(part, E, settings.get("threshold2")), sweeps=sweeps,
        ports=ports, expected=subject.expected, deformed=deformed, warnings=warnings,
        wall=time.perf_counter() - t0)
    mats = data["materials"]
    if mats:
        unit = "m²" if part.dim == 2 else "m³"
        cut = mats["part"] or {}
        _say(quiet, f"  materials (remeshed, {mats['mode']}"
                    + ("; the part cut at the iso-surface" if cut else "") + "): " + ", ".join(
                        f"{k} {v:.4g} {unit}" + (f" ({cut[k]:.4g})" if k in cut else "")
                        for k, v in mats["remeshed"].items()))
    out = subject.out
    out.mkdir(parents=True, exist_ok=True)
    _write_files(subject, data, sweeps, shown, t0)
    for w in warnings:
        print(f"pacto: warning: {w}", file=sys.stderr, flush=True)
    _say(quiet, short_table(data))
    _say(quiet, f"  written to {out} ({time.perf_counter() - t0:.1f} s)")
    return 0


def _sweep(subject: Subject, kind, pressures, ports, supports, quiet):
    """One kind's :class:`~.part_analysis.Sweep`, a progress line per pressure."""
    extra = {}
    if kind == "darcy":
        p, p_in = subject.darcy
        extra = dict(body=pressure_body_force(p), body_pressure=p_in)
    try:
        ana = PartAnalysis(subject.part.mesh, kind, params=subject.params, supports=supports,
                           ports=ports, **extra)
    except ValueError as err:
        raise InputError(f"analyse: the part cannot be analysed: {err}") from None
    return ana.sweep(pressures, say=None if quiet else (lambda line: print(line, flush=True)))


def region_moduli(mesh, params):
    """Young's modulus of the part: E1, or per region ``{name: E2 on stiff, else E1}``."""
    names = material_names(mesh)
    if STIFF not in names:
        return float(params.E1)
    return {n: float(params.E2 if n == STIFF else params.E1) for n in names}



def _write_files(subject: Subject, data: dict, sweeps: dict, shown, t0: float) -> None:
    """The files: the table, the pictures, the STL, the VTUs, the report and, last (with the
    wall time since ``t0``), analysis.json."""
    out, part, run = subject.out, subject.part, subject.run
    unit = run["load_unit"]
    exp = [r for r in (subject.expected or []) if r["converged"]]
    plot_sweeps(out / "analysis.png", sweeps, log=True,
                expected=([r["pressure"] for r in exp], [r["delta"] for r in exp]) if exp
                else None,
                title=f"{run['case']} — " + ("as built" if run["as_built"] else
                                             f"{run['model']} design, {part.dim}D part")
                + f", {subject.params.model} analysis")
    atomic_write_text(out / "analysis.csv", analysis_csv(data))
    write_part_stl(out / "part.stl", part, subject)
    line = symmetry_line(subject.mesh) if part.dim == 2 else None
    if part.dim == 2 and isinstance(data["settings"]["E"], dict):
        plot_materials(out / "materials.png", part.mesh, mirror=line or False,
                       title="the part's regions: E2 on 'stiff', E1 elsewhere")
    u, extra = None, {}
    if shown is not None:
        sw = sweeps[shown]
        u = sw.displacement()
        P = data["deformed_state"]["pressure"]
        title = (f"{run['case']} part, {shown} {P:.3g} {unit}, {subject.params.model} "
                 f"(true scale)")
        if part.dim == 2:
            plot_deformed(out / "deformed.png", part.mesh, u, title=title, mirror=line or False)
        else:
            deformed_picture(out / "deformed.png", part.mesh, u, title=title)
        if subject.darcy is not None:
            p, p_in = subject.darcy
            extra["p"] = _vertex_values(p, subject.mesh, part.mesh) * (P / p_in)
    phi = sweeps[shown].analysis.energy_density if shown is not None else None
    kw = dict(phi=phi, plane=subject.params.plane, E=data["settings"]["E"], point_data=extra)
    write_vtu(out / "remeshed.vtu", part.mesh, u, **kw)
    if u is not None:
        write_vtu(out / "deformed.vtu", part.mesh, u, deformed=True, **kw)
    data["wall_time_s"] = time.perf_counter() - t0
    atomic_write_text(out / "report.md", report_md(data))
    atomic_write_text(out / "analysis.json", json.dumps(data, indent=1))


def _vertex_values(field, source, mesh) -> np.ndarray:
    """``field`` (a CF on ``source``) at the vertices of ``mesh``; 0 outside ``source``."""
    pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    mips = source(*(pts[:, i].copy() for i in range(mesh.dim)))
    vals = np.zeros(len(pts))
    inside = np.asarray(mips["nr"]) >= 0
    if inside.any():
        vals[inside] = np.asarray(field(mips[inside])).ravel()
    return vals

"""``pacto analyse``: a part analysed over a sweep of pressures, one flow for 2D and 3D.

``pacto analyse DIR`` (a finished run, :func:`analyse_run`):

1. the run is loaded and rebuilt (its final design analysed at its load, as summary.json
   reports it); the **expected** Δ at every pressure P of the sweep is the density design
   with the run's own model at load factor P/load (:func:`~.expected.expected_sweep`), on
   the run's mesh at the part's displacement order (:func:`~.runs.at_order`: the run's
   order-1 elements are stiffer, and the gap is to measure making the part, not the order);
2. its **part** is made (:func:`~.part.make_part`: threshold chosen so that the part reaches
   every output, body-fitted remesh, the wetted walls named ``pressure`` by the run's final
   Darcy field at P_in = the run's load, the chambers' seal checked); only this step differs
   by dimension;
3. the part is analysed (:class:`~.part_analysis.PartAnalysis`) with the run's own material
   law (``--model`` names another) for each kind: ``darcy`` (the thresholded design's Darcy
   pressure as the body force −∇p, scaled with P/P_in), ``fixed`` and ``follower`` (the
   pressure on the wetted walls), one progress line per pressure;
4. what would take too long or not fit this machine is refused before anything is meshed,
   with one line giving the estimate of time and memory
   (:func:`~.part_resources.check_resources`);
5. everything is written into ``DIR/analysis/`` (:func:`~.finish.finish`).

``pacto analyse CASE --as-built`` (:mod:`.as_built`) takes the case's own geometry as the part
and runs steps 3-5 on it (:mod:`.finish`; the options of both: :mod:`.analysis_options`).
Files written (2D and 3D alike):

=================  ===========================================================================
``analysis.json``  one layout (:mod:`.report`): run, settings, part, seal, per pressure the
                   expected Δ and each kind's Δ, ports, max |u|, min J, iterations; gaps,
                   warnings, wall time
``analysis.csv``   one row per (kind, pressure)
``analysis.png``   Δ against P: expected and every kind (:func:`~.pictures.plot_sweeps`)
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

import time

from ..errors import InputError
from ..physics.equilibrium import NewtonFailure
from ..threads import compute
from .analysis_options import analysis_params, check_kinds, default_pressures
from .cli_commands import check_threshold
from .expected import expected_sweep, load_path_note, rounded_density, rounded_sweep
from .finish import Subject, finish, say
from .part import Part, make_part
from .part_entries import part_measures
from .part_resources import TIME_LIMIT, check_resources, part_estimate
from .part_stage import PART_MAXH, PART_ORDER
from .report import jsonable
from .runs import at_order, copy_gridfunction, design_delta, load_run, rebuild

#: the kinds of a run's part (``darcy`` needs the run's Darcy field), in this order
KINDS = ("darcy", "fixed", "follower")


# -- a run's part ----------------------------------------------------------------------------
def analyse_run(folder, *, pressures=None, threshold_value=0.5, maxh=None, order=None,
                kinds=KINDS, quiet: bool = False, connect: bool = True, threshold2=0.5,
                model: str | None = None, time_limit: float = TIME_LIMIT,
                contact: bool = False) -> int:
    """``pacto analyse DIR``: the part of a finished run analysed (the module docstring).
    ``order`` and ``maxh`` default those of the run's own part (:mod:`.part_stage`: order 2,
    half the design's element size in 2D, the design's in 3D); ``model`` the part's
    analysis model (default the run's); ``connect`` lower the threshold until the part
    reaches every output (``--keep-threshold``: False); ``contact`` the part's boundaries in
    self-contact.  Returns the exit code (0)."""
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
    say(quiet, f"analyse {run.path}: {run.case.name}, model {run.params.model}, load "
                f"{run.load:g} {run.case.load_unit}, design '{run.design}' after {run.k} "
                f"iterations")
    with compute():
        problem = rebuild(run)
    dim = problem.mesh.dim
    params = analysis_params(run.params, model, order or PART_ORDER[dim])
    maxh = PART_MAXH[dim] * problem.h if maxh is None else float(maxh)
    limits = dict(dim=dim, kinds=kinds, n_pressures=len(pressures), model=params.model,
                  mesh_time_limit=run.params.mesh_time_limit, time_limit=time_limit)
    check_resources(part_estimate(problem, maxh, params.order, kinds), f"--maxh = {maxh:g}",
                    **limits)  # before meshing: the mesh's time and memory, from Σ a ρ̄
    entry, p_final = _rebuilt_entry(run, problem, quiet)
    part = make_part(problem, setup, threshold=threshold_value, maxh=maxh,
                     threshold2=threshold2, connect=connect, pressure=p_final, p_in=run.load,
                     mesh_time_limit=run.params.mesh_time_limit)
    say(quiet, f"  {part.choice['note']}; the part: {part.mesh.ne} elements, "
                f"{part.measure:.4g} {'m²' if dim == 2 else 'm³'}"
                + ("" if part.seal is None else
                   f", {'sealed' if part.sealed else 'NOT SEALED'}"))
    est = part_estimate(problem, maxh, params.order, kinds, mesh=part.mesh)
    seconds = check_resources(est, f"--maxh = {maxh:g}", **limits)  # the part as meshed
    say(quiet, f"  the part at maxh {maxh:g}, order {params.order}: {est.elements:.5g} "
                f"{est.kind}, {est.dofs:.5g} dofs; the analysis about {seconds:.3g} s, "
                f"{est.memory / 1e9:.2g} GB")
    design = _at_part_order(problem, params.order, entry, quiet)
    expected = expected_sweep(design, pressures, run.load, x=run.x)
    say(quiet, "  expected Δ: " + ", ".join(
        f"{r['pressure']:.3g} -> {r['delta']:.4g}" if r["converged"] else
        f"{r['pressure']:.3g} -> failed" for r in expected))
    darcy = _thresholded_darcy(problem, part)
    rounded = rounded_sweep(design, part, pressures, run.load)
    if rounded is not None:
        expected = [dict(e, rounded=r["delta"]) for e, r in zip(expected, rounded)]
    subject = Subject(run.case, params, setup, problem.mesh, part, run.path / "analysis",
                      entry, float(problem.h), expected, (darcy, run.load),
                      part_measures(part))
    subject.contact, subject.time_limit = contact, time_limit
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
    say(quiet, f"  rebuilt: Δ = {'—' if delta is None else format(delta, '.6g')} m at "
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
    return entry, copy_gridfunction(problem.pressure_block.pressure)


def _at_part_order(problem, order, entry, quiet):
    """The run's problem at the part's ``order`` (:func:`~.runs.at_order`), its Δ at the
    run's load into the 'run' ``entry``; the run's problem where that has no equilibrium."""
    design = problem
    if not problem.failure:
        try:
            design = at_order(problem, order)
        except NewtonFailure as err:
            entry["order_note"] = (f"the design has no equilibrium at order {order} ({err}); "
                                   f"the expected Δ is at the run's order")
    entry["expected_order"] = int(design.params.order)
    entry["output_displacement_at_order"] = (entry["output_displacement_rebuilt"]
                                             if design is problem else design_delta(design))
    if design is not problem:
        say(quiet, f"  the design at order {order}: Δ = "
                   f"{entry['output_displacement_at_order']:.6g} m")
    return design


def _thresholded_darcy(problem, part: Part):
    """The Darcy field of the thresholded design (:func:`rounded_density`) at P_in = the
    run's load."""
    rho = rounded_density(problem, part)
    block = problem.pressure_block
    with compute():
        block.forward(rho)
    return copy_gridfunction(block.pressure)

"""``pacto refine RUN``: the part of a finished pressure run (2D or 3D), its shape refined.

What it does for a user: the run's part is made exactly as ``pacto analyse RUN`` makes it
(:func:`~.part.make_part` at threshold 0.5, lowered until the part reaches every output; half
the design's element size; displacement order 2), loaded as the run's own part is (the run's
model, the wall pressure at the load the run reached on the wetted walls ``pressure``, fixed or
following the deformation as the run's ``load_type``, the run's output ports and their
springs), and its boundary is then moved to make the output displacement Δ larger without
adding material (:func:`~pacto_ng.shape.refine.refine`: the volume bounded by the part's own
starting volume, which is what the design promised; every vertex kept in the bounding box of
the run's design domain, so that the part is no larger than the domain the user gave; the
elements kept from folding; with ``--min-wall T``, no wall thinner than T, the descent
steered off that floor, :class:`~pacto_ng.shape.thickness.WallThickness`).  When the moved
mesh cannot move further without folding, the part is remeshed as it stands
(:func:`~pacto_ng.shape.remesh.remesh_moved`: the same polygon, names and ports on fresh
triangles) and the refinement goes on, at most :data:`REMESHES` times.  The clamp, the output
ports and the case's symmetry lines do not move (a symmetry line slides along itself).
Body-fitted motion keeps the part's topology: no element folds and a remesh keeps the polygon,
so a chamber sealed in the part as made stays sealed.

The refined part is then checked: meshed again independently (finer, :data:`CHECK_MAXH`
times the part's element size) and analysed afresh; its Δ there is reported beside the
refinement's (``check``; measured within 0.14 % on the built-in cases, docs/guide.md).

Written into ``RUN/refine/`` (refused when it exists, unless ``--overwrite``, which replaces
these files and nothing else):

=================  ===========================================================================
``history.csv``    one row per accepted shape (step 0 the part as made): step, mesh (0 the
                   part as made, then one more per remesh; a remeshed shape repeats its step
                   with its Δ on the new mesh), delta (m), ratio (Δ/SE, 1/J: held for a
                   mechanism run; NaN otherwise), volume (m³: area times thickness),
                   det (the lowest Jacobian of the mesh's motion since the last remesh),
                   length (the step, m), wall (the thinnest wall, m), merit
``summary.json``   status, Δ before and after, ``thinnest_wall`` (as made, refined, the
                   floor kept and where it came from), ``design_delta`` and ``gap`` (the refined Δ
                   against the design's, as the run's part line gives it; at the run's own
                   loading only), ``ratio`` (Δ/SE before and after, a mechanism run), volume
                   before, after and its bound, the lowest Jacobian, steps, remeshes,
                   ``check`` (the independent remesh: its maxh, elements, Δ and
                   difference), ``sweep`` (with ``--pressures``: the refined part analysed
                   afresh at each pressure), model, load type, load, the part's settings,
                   warnings (the refined part reaching out of the run's design domain beyond
                   round-off: the refinement keeps it in, so none is expected), wall time
``refined.vtu``    the refined part (points at their moved positions, m) with ``u`` (the
                   displacement at the run's load) and ``moved`` (the motion since the last
                   remesh)
``refined.png``    the part's outline before and after the refinement, in metres
``refined.stl``    the refined part as ``pacto export`` writes a part: whole (mirrored across
                   the case's symmetry line), extruded by the thickness, closed, in mm
=================  ===========================================================================

The statuses are those of :func:`~pacto_ng.shape.refine.refine`: ``steps`` (the asked steps
done), ``converged``, ``mesh_quality`` (the mesh would fold after the last remesh allowed)
and ``no_descent``.  Runs without a pressure load or an output port, and runs whose
objective is neither a mechanism's nor an output's, are refused with one line.
"""
from __future__ import annotations

import time

import numpy as np

from ..errors import InputError
from ..physics.equilibrium import NewtonFailure
from ..physics.walls import solid_boundaries
from ..shape import moved_field, refine, remesh_moved, volume
from .finish import say
from .part import part_ports, present_supports
from .part_analysis import PartAnalysis
from .refine_files import write_refinement, write_stl
from .refine_setup import Job, Loading, part_size, refinement, shape_response
from .report import num
from .runs import load_run

#: the refinement's steps when ``--steps`` is not given
STEPS = 20
#: the first trial step of the boundary's motion, in the part's element sizes (maxh): the
#: largest is four times it (:func:`~pacto_ng.shape.refine.refine`), so that a step moves the
#: boundary by a few elements at most and a thin wall is not crossed in one step
STEP_SHARE = 1.0
#: the augmented Lagrangian's starting penalty μ on the relative volume excess and the
#: relative shortfall of Δ/SE (:func:`~pacto_ng.shape.refine.refine`, which stiffens it
#: where a violation persists).  Measured on the default
#: pneunet run, 20 steps: μ = 1000 zig-zags across the Δ/SE floor (steps alternately gain Δ
#: and restore Δ/SE) and gains 6 %; 100: 9.9 %; 10: 15.5 % with Δ/SE 0.17 % and the volume
#: 0.05 % under their bounds; 3: 14.8 %, the volume 0.2 % over
PENALTY = 10.0
#: a step the mesh's quality bounds below this (in the part's element sizes) asks for a
#: remesh: smaller ones make little progress (measured on pa-inverter: four steps of 1e-3 to
#: 4e-6 maxh gained 0.1 % of Δ before the mesh could not move at all)
QUALITY_STEP = 0.125
#: the most remeshes of one refinement (each when the moved mesh would fold)
REMESHES = 5
#: the element size of the independent remesh that checks the refined part's Δ, in the
#: part's element sizes (finer than the refinement's own mesh, and placed independently)
CHECK_MAXH = 0.7
#: the share of the design domain's size beyond which a refined vertex is reported out of
#: the domain (round-off only: the refinement clips the vertices into the domain's box)
OUTSIDE_TOL = 1e-9


def refine_run(folder, *, steps: int = STEPS, quiet: bool = False, overwrite: bool = False,
               loading: Loading = Loading(), pressures=(), min_wall: float | None = None
               ) -> int:
    """``pacto refine RUN``: the run's part made, its shape refined for a larger Δ at no more
    volume (no wall thinner than ``min_wall`` m, if given), the results written into
    ``RUN/refine/`` (the module docstring).  Returns the exit code (0); bad input is an
    InputError (one line, exit 2)."""
    t0 = time.perf_counter()
    if steps < 0:
        raise InputError(f"--steps: must be 0 or more, got {steps}")
    if min_wall is not None and not (np.isfinite(min_wall) and min_wall >= 0):
        raise InputError(f"--min-wall: must be a length in m (0 for no floor), got "
                         f"{min_wall:g}")
    run = load_run(folder, "refine")
    out = run.path / "refine"
    if out.exists() and not overwrite:
        raise InputError(f"refine: '{out}' exists (an earlier refinement): add --overwrite to "
                         f"replace its files")
    part, job = refinement(run, quiet, f"{steps} steps", loading)
    setup, kind, load = job.setup, job.kind, job.load
    bound = volume(part.mesh, job.thickness(part.mesh.dim))
    floor = wall_floor(min_wall)
    space, response, result, remeshes = _refine_remeshing(job, part.mesh, bound, steps, quiet,
                                                          floor["floor"])
    settings = dict(threshold=part.threshold, threshold_note=part.choice.get("note"),
                    maxh=job.maxh, order=job.params.order, elements=part.mesh.ne,
                    part_size=part_size(part.mesh), contact=job.contact)
    summary = _summary(run, result, bound, (job.params.model, kind, load), settings)
    summary["ratio"] = _ratio(response, result) if job.hold_ratio else None
    summary["remeshes"] = remeshes
    # the thinnest wall as made and refined, and the floor kept
    walls = [row.get("wall", np.nan) for row in result.history]
    summary["thinnest_wall"] = ({"part_as_made": walls[0], "refined": walls[-1]} | floor
                                if np.isfinite(walls[0]) else None)
    start = float(np.max(_outside(np.array([v.point for v in part.mesh.vertices]),
                                  job.domain)))
    summary["warnings"] = _leaves(space, job.domain, start)
    summary["sealed"] = part.sealed
    if part.sealed is False:
        summary["warnings"].append(
            "the part as made is not sealed (" + part.seal.message() + "): the refinement "
            "keeps its topology, so the refined part leaks too")
    checked, summary["check"] = _check(job, (space, response), result.delta, quiet)
    summary["sweep"], summary["pressure_maximum"] = (
        _sweep(job, checked, pressures, quiet) if pressures and checked is not None
        else ([], None))
    for line in summary["warnings"]:
        say(quiet, f"  warning: {line}")
    summary["wall_time_s"] = time.perf_counter() - t0
    promise = _promise(run.summary) if loading == Loading() else None
    summary["design_delta"] = promise
    summary["gap"] = None if not promise else (result.delta - promise) / abs(promise)
    write_refinement(out, run, (part.mesh, space, response, result), summary,
                     (job.domain, setup.supports.clamp))
    if checked is not None:
        write_stl(out / "refined.stl", checked[0], job.thickness(part.mesh.dim),
                  run.case.name)
    print(_last_line(summary, result, bound, out), flush=True)
    return 0


def wall_floor(min_wall: float | None) -> dict:
    """The wall floor of a refinement and where it comes from: ``--min-wall T`` (0 or None:
    none); ``{"floor": m or None, "floor_from": text}``."""
    return {"floor": min_wall or None, "floor_from": "--min-wall" if min_wall else "none"}


def _promise(summary: dict) -> float | None:
    """The design's Δ the part is judged against, as the run's part line gives it: the
    design analysed at the part's order (``part.output_displacement_design``), else the
    run's own figure."""
    part = summary.get("part") or {}
    return part.get("output_displacement_design") or summary.get("output_displacement")


def _last_line(summary: dict, result, bound: float, out) -> str:
    """The command's last line: Δ before and after, against the design's promise (at the
    run's own loading), the volume, the status and the independent check."""
    d0, d1, n = summary["delta_before"], summary["delta_after"], summary["remeshes"]
    gap = ("" if summary["gap"] is None else
           f" (the design promised {summary['design_delta']:.4g} m: gap "
           f"{100 * summary['gap']:+.1f} %)")
    walls = summary["thinnest_wall"]
    wall = ("" if not walls else f", thinnest wall {1e3 * walls['part_as_made']:.3g} → "
            f"{1e3 * walls['refined']:.3g} mm")
    return (f"refined: Δ {d0:.4g} → {d1:.4g} m ({100 * summary['gain']:+.1f} %){gap} at volume "
            f"{result.volume:.4g} m³ (bound {bound:.4g} m³){wall}, status {result.status}, {n} "
            f"remesh{'es' if n != 1 else ''}; {_check_text(summary['check'])} — {out}")


def _check_text(check: dict) -> str:
    """The last line's words on the independent check."""
    if not check["made"]:
        return "no independent check (the refined part could not be remeshed or analysed)"
    return (f"on an independent remesh Δ {check['delta']:.4g} m "
            f"({100 * check['difference']:+.2f} %)")


def _refine_remeshing(job: Job, mesh, bound: float, steps: int, quiet: bool,
                      min_wall: float | None = None):
    """``(ShapeSpace, PartResponse, RefineResult, remeshes)``: the refinement of the part on
    ``mesh``; when the mesh would fold (status ``mesh_quality``) the moved part is remeshed
    (:func:`~pacto_ng.shape.remesh.remesh_moved`, at the part's ``maxh``) and the refinement
    goes on with the same objective scale, multiplier and volume bound, at most
    :data:`REMESHES` times.  The result's history spans every mesh (``mesh``: the mesh's
    number, 0 the part as made; the first row on a new mesh repeats the step number)."""
    history, remeshes, done, multipliers, scale, penalty = [], 0, 0, None, None, PENALTY
    floor, previous = None, None
    report = None if quiet else (lambda line: print("  " + line, flush=True))
    while True:
        response, space = shape_response(mesh, job)
        if previous is not None:  # the last mesh's equilibrium, the first guess on this one
            response.start_from(moved_field(previous[0].mesh, previous[0].moved_points(),
                                            previous[1].u))
        try:
            if job.hold_ratio and floor is None:
                response.solve()
                floor = response.value("ratio")
                if not floor > 0:
                    raise InputError(f"refine: the part's Δ/SE is {floor:.4g} at the run's "
                                     f"load: its port moves against the port's direction, "
                                     f"no mechanism to refine")
            result = refine(response, space, volume_max=bound, steps=steps - done,
                            step=STEP_SHARE * job.maxh, penalty=penalty,
                            alpha=1.0 / part_size(mesh) ** 2, bounds=job.domain, scale=scale,
                            multipliers=multipliers, quality_step=QUALITY_STEP * job.maxh,
                            ratio_min=floor, min_wall=min_wall, say=report)
        except NewtonFailure as err:
            if previous is None:
                raise InputError(f"refine: the part has no equilibrium at the run's load on "
                                 f"its starting shape ({err})") from None
            say(quiet, f"  the remeshed part has no equilibrium at the load ({err}): the "
                       f"refinement ends on the last mesh")
            space, response, result = previous
            break
        except ValueError as err:
            raise InputError(str(err)) from None
        scale = abs(result.history[0]["delta"]) if scale is None else scale
        history += [dict(row, step=done + row["step"], mesh=remeshes) for row in result.history]
        done += len(result.history) - 1
        if result.status != "mesh_quality" or remeshes >= REMESHES or done >= steps:
            break
        try:
            mesh = remesh_moved(mesh, space.moved_points(), job.maxh)
        except ValueError as err:
            say(quiet, f"  the moved part could not be remeshed ({err}): stopped")
            break
        remeshes, multipliers, penalty = remeshes + 1, result.multipliers, result.penalties
        previous = (space, response, result)
        say(quiet, f"  remeshed the moved part ({remeshes} of at most {REMESHES}): "
                   f"{mesh.ne} elements")
    result.history = history
    return space, response, result, remeshes


def _ratio(response, result) -> dict:
    """summary.json's ``ratio``: the mechanism ratio Δ/SE of the part as made (the floor the
    refinement holds) and of the refined part (1/J)."""
    first = result.history[0]
    return {"before": first["ratio"], "after": response.value("ratio"), "unit": "1/J"}


def _check(job: Job, refined, delta: float, quiet: bool):
    """``(mesh, entry)``: the refined part (``refined``: its ShapeSpace and PartResponse)
    remeshed independently (at :data:`CHECK_MAXH` times the part's element size, else at the
    part's) and analysed afresh, Newton's load ramped from zero; where that ramp stalls (a
    nonlinear part may reach its equilibrium only along the refinement's path), from the
    refinement's own equilibrium carried onto the new mesh (``start``: ``"ramp"`` or
    ``"refinement"``).  ``entry`` gives that mesh's size and Δ and its relative difference
    from the refinement's own ``delta``.  When Netgen cannot mesh the refined part or it has
    no equilibrium there: ``(None, {"made": False, "why": ...})``, said in one line."""
    space, state = refined
    try:
        mesh, maxh = _remeshed(space, job.maxh)
        response, _ = shape_response(mesh, job)
        try:
            check, start = response.solve(), "ramp"
        except NewtonFailure:
            response.start_from(moved_field(space.mesh, space.moved_points(), state.u))
            check, start = response.solve(), "refinement"
    except (ValueError, NewtonFailure) as err:
        say(quiet, f"  no independent check of the refined part: {err}")
        return None, {"made": False, "why": str(err)}
    entry = {"made": True, "maxh": maxh, "elements": mesh.ne, "delta": check,
             "difference": (check - delta) / abs(delta), "start": start}
    say(quiet, f"  an independent remesh of the refined part ({mesh.ne} elements, maxh "
               f"{maxh:.4g} m{'' if start == 'ramp' else ', from the refinement state'}): "
               f"Δ {check:.6g} m, {100 * entry['difference']:+.2f} % from the refinement's")
    return (mesh, response), entry


def _sweep(job: Job, checked, pressures, quiet: bool) -> tuple[list[dict], dict | None]:
    """The refined part (``checked``: its independent remesh) analysed as ``pacto analyse``
    analyses a part (:class:`~.part_analysis.PartAnalysis`, the refinement's model and load
    type) at each of ``pressures`` in increasing order, loaded from zero and each from the
    last equilibrium, past a pressure maximum where there is one: ``([{"pressure",
    "converged", "delta", "newton_iterations", "past_peak"}], the pressure maximum or
    None)``, one line each."""
    mesh = checked[0]
    ana = PartAnalysis(mesh, job.kind, params=job.params,
                       supports=present_supports(job.setup.supports, mesh),
                       ports=part_ports(job.setup),
                       contact=solid_boundaries(mesh) if job.contact else ())
    sweep = ana.sweep(sorted(pressures), say=None if quiet else (lambda line: say(False, line)))
    return [{"pressure": p.pressure, "converged": bool(p.converged), "delta": num(p.delta),
             "newton_iterations": p.iterations, "past_peak": p.past_peak}
            for p in sweep.points], sweep.peak


def _remeshed(space, maxh: float):
    """``(mesh, its maxh)``: the refined part remeshed at :data:`CHECK_MAXH` × ``maxh``,
    else at ``maxh`` (ValueError when both fail)."""
    try:
        return remesh_moved(space.mesh, space.moved_points(), CHECK_MAXH * maxh), \
            CHECK_MAXH * maxh
    except ValueError:
        return remesh_moved(space.mesh, space.moved_points(), maxh), maxh


def _outside(points, domain) -> np.ndarray:
    """How far each of ``points`` lies out of the box ``domain`` (its lowest and highest
    corner), m."""
    low, high = domain
    return np.max(np.maximum(np.maximum(low - points, points - high), 0.0), axis=1)


def _leaves(space, domain, start: float) -> list[str]:
    """A warning when the refined part reaches out of the run's design domain (``domain``:
    its lowest and highest corner) farther than the part as made did (``start``, m) by more
    than :data:`OUTSIDE_TOL` of the domain's size: the refinement keeps every vertex it
    moves in the domain's box, so this is a check only (a part as made may stick out by the
    remesher's round-off: 3e-9 m on pa-gripper-3d, at a held output vertex)."""
    moved = space.moved_points()
    out = _outside(moved, domain)
    far = float(np.max(out))
    if not far > start + OUTSIDE_TOL * float(np.max(domain[1] - domain[0])):
        return []
    where = ", ".join(f"{c:.3g}" for c in moved[int(np.argmax(out))])
    return [f"the refined part reaches {far:.3g} m out of the run's design domain (at "
            f"({where}) m)"]


def _summary(run, result, bound: float, loading: tuple, settings: dict) -> dict:
    """summary.json's content; ``loading``: the refinement's (model, load type, load)."""
    model, kind, load = loading
    first = result.history[0]
    d0, d1 = float(first["delta"]), float(result.delta)
    return {"run": str(run.path), "case": run.case.name, "status": result.status,
            "delta_before": d0, "delta_after": d1, "gain": (d1 - d0) / abs(d0),
            "volume_before": float(first["volume"]), "volume_after": float(result.volume),
            "volume_bound": bound, "volume_vs_bound": result.volume / bound - 1.0,
            "lowest_det": float(min(h["det"] for h in result.history)),
            "steps": int(result.history[-1]["step"]), "multipliers": result.multipliers,
            "model": model, "load_type": kind, "load": load,
            "load_unit": run.case.load_unit, "units": {"delta": "m", "volume": "m³"},
            "part": settings}

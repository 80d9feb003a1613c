"""``pacto analyse``, ``pacto export`` and ``pacto compare``: from a finished run to a part.

``analyse DIR`` rebuilds the problem of a run folder (``params.json``), takes its final design
(``checkpoint.npz``: ``x``, or ``last_good`` when the run stopped on a Newton failure), and
calls :func:`~pacto_ng.post.report.post_analyse` with the case's supports, output port and
spring, wetting rule and Darcy pressure.  It writes into ``DIR/analysis/``:

=================  ====================================================================
``analysis.json``  per pressure: expected Δ, Δ of the three analyses, max |u|, min J, Newton
                   iterations; areas, wetting, ports, every setting used
``analysis.png``   Δ against pressure: expected, Darcy, fixed and follower pressure
``deformed.png``   undeformed outline over the deformed solid (follower, largest pressure)
``report.md``      the pictures and the numbers together
``design.stl``     the thresholded, remeshed solid extruded by the thickness (watertight)
``remeshed.vtu``   remeshed solid: ``u``, ``p``, ``J``, ``stress``, ``von_mises``
``deformed.vtu``   the same in the deformed configuration
``analysis.csv``   one row per (analysis, pressure) (written by ``post_analyse``)
``post.json``      the summary of ``post_analyse``
=================  ====================================================================

The three Neo-Hookean analyses of the remeshed design (plane strain, the run's E1, ν, t):

* ``darcy`` — thesis §6.1.1, "deformation-independent load analysis": the Darcy pressure of
  the *thresholded* design (element ρ = 1 where at least half of the element lies inside the
  thresholded solid, else 0; the run's Darcy parameters) as the body force ``-∇p``;
* ``fixed`` — the pressure ``P`` on the wetted boundary, deformation independent: the exact
  small-load counterpart of the follower analysis;
* ``follower`` — thesis §6.1.2: the pressure ``P`` on the wetted boundary, following the
  deformation.

**Expected Δ** — what the optimisation predicts: the optimised density design ρ̄ (final x,
last penalty and β) analysed with the optimisation's own model, its Darcy load and output
spring at inlet pressure ``P`` (load factor ``P / load``; Newton with load stepping, warm
started along the sweep).  For a linear run this is exactly the run's Δ scaled linearly with
``P``; for a nonlinear run it is a nonlinear re-analysis at every pressure.
"""
from __future__ import annotations

import json
import math
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..params import InputError, Parameters
from ..threads import compute

KINDS = ("darcy", "fixed", "follower")
EXPECTED_DEFINITION = (
    "the optimised density design (final x, last penalty and beta) re-analysed with the "
    "optimisation's own model, Darcy load and output spring at inlet pressure P (load factor "
    "P/load, Newton with load stepping, warm-started along the sweep); for a linear model this "
    "equals the run's output displacement scaled linearly with P")
DARCY_DEFINITION = (
    "Darcy pressure of the thresholded design (element rho = 1 where at least half of the "
    "element lies inside the thresholded solid, else 0) as the deformation-independent body "
    "force -grad p, interpolated onto the remeshed solid")


# ------------------------------------------------------------------------------------------
# parsing
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


def check_threshold(value, *, allow_volume: bool = False):
    """A threshold in (0, 1), or (with ``allow_volume``) the word ``volume``: the
    volume-preserving threshold of :func:`~pacto_ng.post.threshold.volume_threshold`."""
    if isinstance(value, str):
        if value.strip().lower() == "volume":
            if not allow_volume:
                raise InputError("--threshold: 'volume' is an option of 'pacto analyse' only; "
                                 "give a number in (0, 1)")
            return "volume"
        try:
            value = float(value)
        except ValueError:
            raise InputError(f"--threshold: expected a number in (0, 1)"
                             f"{' or volume' if allow_volume else ''}, got '{value}'") from None
    if not (0.0 < float(value) < 1.0) or not math.isfinite(float(value)):
        raise InputError(f"--threshold: must lie in (0, 1), got {value:g}")
    return float(value)


def default_pressures(load: float, n: int = 5, span: float = 100.0) -> list[float]:
    """``n`` log-spaced pressures from ``load / span`` to the run's ``load``."""
    return [float(v) for v in np.geomspace(load / span, load, n)]


# ------------------------------------------------------------------------------------------
# a finished run
@dataclass
class Run:
    """A finished run folder: its case, parameters, summary and final design."""

    path: Path
    case: object
    params: Parameters
    summary: dict
    x: np.ndarray
    design: str  # "x" or "last_good"
    k: int  # optimisation iterations done

    @property
    def load(self) -> float:
        return float(self.params.load)


def load_run(folder, command: str, case=None) -> Run:
    """Read ``params.json``, ``summary.json`` and ``checkpoint.npz``; InputError if anything
    that a finished run holds is missing."""
    from ..case import case_of_run

    path = Path(folder)
    if not path.is_dir():
        raise InputError(f"{command}: '{folder}' is not a folder")
    try:
        info = json.loads((path / "params.json").read_text())
        if not isinstance(info, dict) or "case" not in info:
            raise ValueError("no case named")
    except (OSError, ValueError):
        raise InputError(f"{command}: '{folder}' holds no run (params.json missing or "
                         f"unreadable)") from None
    if case is None:  # an error in a user's case file is shown as itself
        case = case_of_run(info, command)
    elif case.name != info["case"]:
        raise InputError(f"{command}: '{folder}' is a run of '{info['case']}', not of "
                         f"'{case.name}'")
    try:
        params = case.parameters(info["params"])
    except (KeyError, TypeError) as err:
        raise InputError(f"{command}: '{path / 'params.json'}' has no valid parameters "
                         f"({err})") from None
    if case.analysis_only:
        raise InputError(f"{command}: '{folder}' is an analysis case ({case.name}), not an "
                         f"optimised design")
    try:
        summary = json.loads((path / "summary.json").read_text())
    except (OSError, ValueError):
        raise InputError(f"{command}: '{folder}' holds no finished run (summary.json missing: "
                         f"still running, or stopped before its first result)") from None
    try:
        with np.load(path / "checkpoint.npz", allow_pickle=False) as data:
            use_last_good = summary.get("stopped") == "newton" and "last_good" in data.files
            design = "last_good" if use_last_good else "x"
            x = np.asarray(data[design], dtype=float).copy()
            k = int(data["k"])
    except (OSError, ValueError, KeyError):
        raise InputError(f"{command}: '{folder}' has no readable checkpoint.npz (the final "
                         f"design)") from None
    return Run(path, case, params, summary, x, design, k)


def rebuild(run: Run):
    """The run's problem with its final design analysed at the run's load (as ``run.py`` does
    for summary.json).  Returns the problem; ``problem.values`` hold ρ̄, p and Δ."""
    from ..case import build_problem
    from ..physics.mechanics import NewtonFailure

    problem = build_problem(run.case, run.params)
    if run.x.size != problem.field.n * problem.n_design_fields:
        raise InputError(f"the design in '{run.path}' has {run.x.size} values, the rebuilt "
                         f"problem {problem.field.n * problem.n_design_fields} (mesh changed?)")
    problem.apply_schedule(*run.params.schedule.schedule().values(max(run.k - 1, 0)))
    problem.failure = None
    try:
        problem.chain.forward(x=run.x)
    except NewtonFailure as err:
        # a run stopped by a Newton failure: ρ̄ and the Darcy field are computed before the
        # mechanics (the chain keeps its values as they fill); Δ at the full load is not
        problem.failure = str(err)
        if "rho_bar" not in problem.values and "rho_bar1" not in problem.values:
            raise InputError(f"the final design of '{run.path}' cannot be analysed ({err})") \
                from None
    return problem


# ------------------------------------------------------------------------------------------
def expected_sweep(problem, x, pressures, load) -> list[dict]:
    """Δ of the density design with the optimisation's own model at every pressure (see the
    module docstring).  Leaves the problem at the last pressure."""
    from ..physics.mechanics import NewtonFailure

    mech = problem.mech
    mech.gfu.vec[:] = 0.0
    mech.result = None
    rows, failed = [], False
    with compute():
        for P in pressures:
            if failed:
                rows.append(dict(pressure=P, delta=None, newton_iterations=0, converged=False))
                continue
            mech.target = P / load
            try:
                vals = problem.chain.forward(x=x)
                rows.append(dict(pressure=P, delta=float(vals["delta"]),
                                 newton_iterations=int(mech.result.iterations), converged=True))
            except NewtonFailure as err:
                failed = True
                rows.append(dict(pressure=P, delta=None,
                                 newton_iterations=int(err.result.iterations), converged=False,
                                 load_reached=float(err.result.load_reached) * load))
    return rows


def domain_of(problem, setup):
    """``(shape, exclude)``: the netgen.occ shape the problem's mesh was made from (None for a
    mesh file or structured quads) and, with a shape, the passive void faces to leave out of
    the thresholding (the part is built on the shape's own edges; see
    :func:`~pacto_ng.post.remesh.remesh`)."""
    shape = getattr(problem, "shape", None)
    if shape is None:
        return None, ()
    faces = {f.name for f in shape.faces}
    return shape, tuple(n for n in getattr(setup, "void", ()) if n in faces)


def thresholded_elements(th) -> np.ndarray:
    """Element ρ in {0, 1} of the thresholded design: 1 where at least half of the element's
    area lies inside the clipped solid of :func:`~pacto_ng.post.threshold.threshold` (0 in the
    materials it left out)."""
    from .threshold import _cell_areas, element_materials, mesh_to_pyvista

    grid = mesh_to_pyvista(th.source)
    grid.point_data["rho"] = th.nodal
    grid.cell_data["cid"] = np.arange(grid.n_cells)
    solid = grid.clip_scalar(scalars="rho", value=th.threshold, invert=False)
    inside = np.bincount(np.asarray(solid.cell_data["cid"]), weights=_cell_areas(solid),
                         minlength=grid.n_cells)
    out = (inside >= 0.5 * _cell_areas(grid)).astype(float)
    if th.excluded:
        out[np.isin(element_materials(th.source), list(th.excluded))] = 0.0
    return out


def _copy_gf(gf):
    from ngsolve import GridFunction

    out = GridFunction(gf.space)
    out.vec.data = gf.vec
    return out


def _output_of(setup):
    """The re-analysis Output: the case's port, and the springs on the port's region along
    its direction."""
    from .reanalysis import Output

    ports = setup.ports
    if len(ports) != 1:
        raise InputError(f"analyse: the re-analysis follows one output port; this case has "
                         f"{len(ports)} ({', '.join(p.region for p in ports)}): 'pacto export' "
                         "writes its part")
    port = ports[0]
    d = np.asarray(port.direction, dtype=float)
    d = d / np.linalg.norm(d)
    k = 0.0
    for s in setup.all_springs:
        sd = np.asarray(s.direction, dtype=float)
        sd = sd / np.linalg.norm(sd)
        if s.region == port.region and abs(abs(sd @ d) - 1.0) < 1e-12:
            k += float(s.stiffness)
    return Output(port.region, tuple(map(float, d)), k)


def _say(quiet, msg):
    if not quiet:
        print(msg, flush=True)


#: a part Netgen cannot mesh is retried at thresholds this much lower, this many times
MESH_RETRY_STEP, MESH_RETRIES = 0.005, 4


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


def choose_threshold(mesh, rho, requested, output_region: str, clamp, *,
                     connect: bool = True, exclude=()):
    """The threshold ``pacto analyse`` uses, and why: ``(record, Thresholded at it)``.

    ``requested`` is a number in (0, 1) or ``"volume"`` (the volume-preserving threshold).
    With ``connect``, when the part kept on the clamp at that threshold does not contain the
    output point, the threshold is lowered to the largest value (down to 0.1, to within 0.005)
    at which it does: a joint to the output that is still grey is kept, at the price of the
    grey material around it.  The record says what was asked, what was used, the design's
    material volume and the area of the part at the threshold used.  ``exclude``: materials
    left out of the thresholding (:func:`~pacto_ng.post.threshold.threshold`).
    """
    from .remesh import _source_points
    from .threshold import (connecting_threshold, design_volume, part_contains, threshold,
                            volume_threshold)

    start = volume_threshold(mesh, rho) if requested == "volume" else float(requested)
    port = _source_points(mesh).get(output_region)
    rec = {"requested": requested, "start": start, "used": start, "lowered": False,
           "missed": False, "connect": bool(connect), "design_volume": design_volume(mesh, rho)}
    what = (f"threshold {start:.4g} (volume-preserving)" if requested == "volume"
            else f"threshold {start:g}")
    if port is None or not connect:
        th = threshold(mesh, rho, start, exclude=exclude)
        rec["reaches_output"] = None if port is None else part_contains(th, port, clamp)
        rec["note"] = what + ("" if port is None else
                              (": the part on the clamp contains the output point"
                               if rec["reaches_output"] else
                               ": the part on the clamp does not contain the output point "
                               "(not lowered: --keep-threshold)"))
    else:
        used, th = connecting_threshold(mesh, rho, start, port, clamp, exclude=exclude)
        if used is None:
            rec.update(missed=True, reaches_output=False)
            rec["note"] = (f"{what}: the part on the clamp does not contain the output point, "
                           f"nor at threshold 0.1; analysed at {start:.4g}")
        else:
            rec.update(used=used, lowered=used < start, reaches_output=True)
            rec["note"] = (what + ": the part on the clamp contains the output point"
                           if used == start else
                           f"{what} lowered to {used:.4g}: above it the part on the clamp "
                           f"does not contain the output point (a grey joint)")
    rec["part_area"] = th.area
    return rec, th


def analyse_run(folder, *, pressures=None, threshold_value=0.5, maxh=None,
                order: int = 2, kinds=KINDS, quiet: bool = False, connect: bool = True) -> int:
    """``pacto analyse``: see the module docstring.  Returns the exit code (0)."""
    from .remesh import pressure_sampler
    from .report import post_analyse
    from .threshold import threshold

    threshold_value = check_threshold(threshold_value, allow_volume=True)
    if maxh is not None and not maxh > 0:
        raise InputError(f"--maxh: must be positive, got {maxh:g}")
    if order not in (1, 2, 3):
        raise InputError(f"--order: must be 1, 2 or 3, got {order}")
    bad = [k for k in kinds if k not in KINDS]
    if bad or not kinds:
        raise InputError(f"--kinds: choose from {', '.join(KINDS)} (got {','.join(kinds) or 'none'})")
    run = load_run(folder, "analyse")
    setup = run.case.make_setup(run.params)
    if setup.pressure is None:
        raise InputError(f"analyse: case '{run.case.name}' has no pressure load; the re-analysis "
                         f"applies to pressure cases only ('pacto export {folder}' writes its part)")
    if setup.materials != 1:
        raise InputError(f"analyse: case '{run.case.name}' has two materials; the re-analysis "
                         f"handles one material only ('pacto export {folder}' writes its part)")
    if setup.port is None:
        raise InputError(f"analyse: case '{run.case.name}' has no output port")
    output = _output_of(setup)
    pressures = default_pressures(run.load) if pressures is None else list(pressures)
    t0 = time.perf_counter()
    _say(quiet, f"analyse {run.path}: {run.case.name}, model {run.params.model}, load "
                f"{run.load:g} {run.case.load_unit}, design '{run.design}' after {run.k} iterations")
    with compute():
        problem = rebuild(run)
    p = run.params
    rho = np.asarray(problem.values["rho_bar"], dtype=float).copy()
    maxh = 0.5 * problem.h if maxh is None else float(maxh)
    if problem.failure:
        import sys

        print(f"pacto: warning: the run's own model fails on its final design at the full "
              f"load ({problem.failure}); the expected Δ is recorded where it converges",
              file=sys.stderr)
        delta_run = None
    else:
        delta_run = float(problem.values["delta"])
    block = problem.pressure_block
    p_final = _copy_gf(block.gfp)  # the final Darcy field at P_in = load (the wetting rule)
    _say(quiet, f"  rebuilt: Δ = {_fmt(delta_run, '.6g')} m at {run.load:g} Pa (summary.json: "
                f"{run.summary.get('output_displacement')})")
    # for a run reported at its full load only (else summary.json's Δ is at another load);
    # warned once the analysis is done (a failing analysis ends with its one-line error)
    path_note = (load_path_note(delta_run, run.summary.get("output_displacement"))
                 if run.summary.get("load_factor_reached", 1.0) == 1.0 else None)

    # expected Δ: the optimisation's own model on the density design
    expected = expected_sweep(problem, run.x, pressures, run.load)
    _say(quiet, "  expected Δ: " + ", ".join(
        f"{r['pressure']:.3g} Pa -> {r['delta']:.4g}" if r["converged"] else
        f"{r['pressure']:.3g} Pa -> failed" for r in expected))

    supports = setup.supports
    shape, exclude = domain_of(problem, setup)
    choice, th = choose_threshold(problem.mesh, rho, threshold_value, output.region,
                                  supports.clamp, connect=connect, exclude=exclude)
    threshold_value = choice["used"]
    # (a part that still misses the output is reported once the part is built: the warning on
    # the output port's shift below; a design with no solid on the clamp is an error there)
    _say(quiet, "  " + choice["note"])

    newton = p.newton.settings()
    out_dir = run.path / "analysis"
    ok_exp = [r for r in expected if r["converged"]]
    exp_pair = ([r["pressure"] for r in ok_exp], [r["delta"] for r in ok_exp]) if ok_exp else None
    # Netgen fails on some traced parts (a face left empty); the part a little below the
    # threshold has the same pieces (and still contains the output point: containment only
    # grows as the threshold falls), so a failed mesh is retried at up to MESH_RETRIES
    # thresholds MESH_RETRY_STEP apart
    candidates = [threshold_value - k * MESH_RETRY_STEP for k in range(MESH_RETRIES + 1)]
    candidates = [t for t in candidates if t > 0.0]
    for attempt, thr in enumerate(candidates):
        # the Darcy field of the thresholded design (same block, same P_in = load)
        if attempt:
            th = threshold(problem.mesh, rho, thr, exclude=exclude)
        rho_thr = thresholded_elements(th)
        with compute():
            block.forward(rho_thr)
        p_thr = _copy_gf(block.gfp)
        _say(quiet, f"  threshold {thr:g}, remesh (maxh {maxh:g}), "
                    f"Neo-Hookean sweeps {', '.join(kinds)} at {len(pressures)} pressures ...")
        try:
            res = post_analyse(problem.mesh, rho, out_dir, pressures=pressures, E=p.E1, nu=p.nu,
                               thickness=p.thickness, output=output, clamp=supports.clamp,
                               supports=supports, threshold_value=thr, thresholded=th,
                               maxh=maxh,
                               pressure=p_final, p_in=run.load,
                               wet_boundaries=setup.pressure.inlet, kinds=tuple(kinds),
                               darcy_pressure=p_thr, darcy_p_in=run.load, expected=exp_pair,
                               order=order, newton=newton, domain=shape, exclude=exclude)
            break
        except ValueError as err:
            # no solid on the clamp, nothing solid, no wetted boundary: the design cannot be
            # analysed; a Netgen failure: the next candidate
            msg = str(err)
            if msg.startswith("Netgen could not mesh") and attempt + 1 < len(candidates):
                _say(quiet, f"  {msg.split(';')[0]} at threshold {thr:g}: retried at "
                            f"{candidates[attempt + 1]:g}")
                continue
            if "'pressure' boundary" in msg:
                msg = (f"no boundary of the thresholded part is wetted (threshold "
                       f"{thr:g}): the part kept on the clamp does not border the "
                       f"pressurised region of the run's Darcy field")
            raise InputError(f"analyse: {msg}") from None
    if thr != threshold_value:
        choice["mesh_retries"] = attempt
        choice["note"] += (f"; Netgen could not mesh the part at {threshold_value:.4g}, "
                           f"meshed at {thr:.4g}")
        choice["used"] = thr
        choice["part_area"] = th.area
        threshold_value = thr
    rm = res.remeshed

    # fields: add the Darcy pressure (thresholded design, at the shown pressure) to the VTUs
    shown = res.summary.get("deformed_state")
    p_shown = None
    if shown is not None:
        sw = res.sweeps[shown]
        p_shown = float(sw.pressures[np.flatnonzero(sw.converged)[-1]])
    _add_pressure_field(res.files, rm.mesh, pressure_sampler(p_thr, problem.mesh),
                        (p_shown or run.load) / run.load)

    data = _analysis_dict(run, problem, res, expected, pressures, delta_run, kinds, order,
                          choice, maxh, output, supports, p_shown, rho_thr,
                          time.perf_counter() - t0, path_note)
    (out_dir / "analysis.json").write_text(json.dumps(data, indent=1))
    shift = data["remesh"]["output_port_shift"]
    import sys

    if path_note:
        print(f"pacto: warning: {path_note}", file=sys.stderr)
    if shift is not None and shift > 2.0 * problem.h:
        print(f"pacto: warning: the thresholded part does not reach the output point: its nearest "
              f"vertex is {shift:.3g} m away (Δ is read there; see report.md)", file=sys.stderr)
    from .export import plot_sweeps

    plot_sweeps(out_dir / "analysis.png", [res.sweeps[k] for k in kinds if k in res.sweeps],
                expected=exp_pair, log=True,
                title=f"{run.case.name} — {p.model} design (optimised at {run.load:.3g} Pa)")
    (out_dir / "report.md").write_text(_report_md(data))
    _say(quiet, _short_table(data))
    _say(quiet, f"  written to {out_dir} ({data['wall_time_s']:.1f} s)")
    return 0


def _add_pressure_field(files, mesh, sample, scale):
    """Point data ``p`` (Pa) on remeshed.vtu and deformed.vtu: the thresholded design's Darcy
    pressure at the reference position of every vertex, scaled to the shown pressure."""
    import meshio

    pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    pv_ = sample(pts) * scale
    for key in ("remeshed", "deformed"):
        f = files.get(key)
        if f is None or not Path(f).exists():
            continue
        m = meshio.read(str(f))
        m.point_data["p"] = pv_
        m.write(str(f), file_format="vtu")


def _num(v):
    if v is None:
        return None
    v = float(v)
    return v if math.isfinite(v) else None


def _analysis_dict(run, problem, res, expected, pressures, delta_run, kinds, order, choice, maxh,
                   output, supports, p_shown, rho_thr, wall, path_note=None) -> dict:
    rm, th = res.remeshed, res.thresholded
    p = run.params
    kept = th.polygon_area - rm.dropped_area
    rows = []
    for i, P in enumerate(pressures):
        row = {"pressure": P, "expected": _num(expected[i]["delta"]),
               "expected_converged": expected[i]["converged"],
               "expected_newton_iterations": expected[i]["newton_iterations"]}
        for k in kinds:
            pt = res.sweeps[k].points[i]
            row[k] = {"delta": _num(pt.delta), "max_u": _num(pt.max_u), "min_J": _num(pt.min_j),
                      "newton_iterations": int(pt.iterations), "converged": bool(pt.converged)}
        rows.append(row)
    def gap(row):
        out = {}
        for k in kinds:
            a, e = row[k]["delta"], row["expected"]
            out[k] = None if a is None or e in (None, 0.0) else (a - e) / abs(e)
        return out

    gaps, gaps0 = gap(rows[-1]), gap(rows[0])
    port_new = rm.ports.get(output.region)
    shift = None if port_new is None else float(np.hypot(*np.subtract(port_new[1], port_new[0])))
    return {
        "run": {"dir": str(run.path), "case": run.case.name, "model": p.model, "load": run.load,
                "load_unit": run.case.load_unit, "iterations": run.k, "design": run.design,
                "stopped": run.summary.get("stopped"),
                "output_displacement_summary": run.summary.get("output_displacement"),
                "output_displacement_rebuilt": delta_run, "mesh_h": problem.h,
                "load_path_note": path_note},
        "settings": {"threshold": choice["used"],
                     "threshold_choice": dict(choice), "maxh": maxh,
                     "order": order, "kinds": list(kinds), "E": p.E1, "nu": p.nu,
                     "thickness": p.thickness, "material": "Neo-Hookean, plane strain",
                     "supports": {"clamp": list(supports.clamp), "fix_x": list(supports.fix_x),
                                  "fix_y": list(supports.fix_y)},
                     "supports_used": res.summary.get("supports"),
                     "output": {"region": output.region, "direction": list(output.direction),
                                "spring": output.stiffness},
                     "newton_rtol": p.newton_rtol},
        "definitions": {
            "expected": EXPECTED_DEFINITION, "darcy": DARCY_DEFINITION,
            "fixed": "pressure P on the wetted boundary, deformation independent",
            "follower": "pressure P on the wetted boundary, following the deformation "
                        "(J F^-T N0)",
            "wetting": f"a boundary segment of the remeshed solid is wetted where it lies on the "
                       f"inlet boundary ({'|'.join(res.summary.get('wet_boundaries', []) or [])}) "
                       f"or where the run's final Darcy pressure one source element size "
                       f"outside it is at least 0.5 P_in",
            "gap": "(analysed - expected) / |expected|, at the largest and at the smallest "
                   "pressure (there: the effect of thresholding and remeshing alone)"},
        "areas": {"thresholded": th.area, "polygons": th.polygon_area,
                  "removed_specks": th.removed_area, "dropped_floating": rm.dropped_area,
                  "kept": kept, "remeshed": rm.area,
                  "remeshed_vs_kept": (rm.area - kept) / kept if kept else None,
                  "darcy_elements_solid": float(np.sum(rho_thr * problem.field.areas)
                                                if hasattr(problem.field, "areas") else np.nan)},
        "remesh": {"elements": rm.mesh.ne, "geometry": rm.geometry,
                   "wetted_length": rm.wetted_length, "p_in": rm.p_in,
                   "ports": {k: {"source": list(map(float, a)), "new": list(map(float, b))}
                             for k, (a, b) in rm.ports.items()},
                   "output_port_shift": shift},
        "deformed_state": {"kind": res.summary.get("deformed_state"), "pressure": p_shown},
        "pressures": rows,
        "gap_at_largest_pressure": gaps,
        "gap_at_smallest_pressure": gaps0,
        "wall_time_s": wall,
    }


def _fmt(v, spec=".4g"):
    return "—" if v is None else format(v, spec)


def _short_table(data) -> str:
    kinds = data["settings"]["kinds"]
    head = "  P (Pa)      expected    " + "".join(f"{k:12s}" for k in kinds)
    lines = [head]
    for r in data["pressures"]:
        lines.append(f"  {r['pressure']:<11.4g} {_fmt(r['expected']):11s} " + "".join(
            f"{_fmt(r[k]['delta']):12s}" for k in kinds))
    return "\n".join(lines)


def _report_md(d) -> str:
    run, s, a, rm = d["run"], d["settings"], d["areas"], d["remesh"]
    kinds = s["kinds"]
    L = []
    L.append(f"# Post-analysis of {run['case']} — {run['model']} design, optimised at "
             f"{run['load']:.4g} {run['load_unit']}")
    L.append("")
    L.append(f"Run folder `{run['dir']}`; design `{run['design']}` after {run['iterations']} "
             f"iterations (stopped: {run['stopped']}).  Rebuilt output displacement "
             f"Δ = {_fmt(run['output_displacement_rebuilt'], '.6g')} m "
             f"(summary.json: {_fmt(run['output_displacement_summary'], '.6g')} m).")
    if run.get("load_path_note"):
        L.append("")
        L.append(f"**Warning**: {run['load_path_note']}.")
    L.append("")
    L.append("| run design ρ̄ | run Darcy pressure |")
    L.append("|---|---|")
    L.append("| ![design](../design.png) | ![pressure](../pressure.png) |")
    L.append("")
    L.append("## The part")
    L.append("")
    L.append(f"ρ̄ thresholded at {s['threshold']:g} (iso-line of the area-weighted nodal density) "
             f"and remeshed with Netgen triangles of {s['maxh']:.4g} m ({rm['elements']} "
             f"elements).")
    geo = rm.get("geometry", "traced")
    if geo == "domain":
        L.append("The part runs along the case's own geometry (its curved edges, holes and "
                 "chamber walls, with their names) wherever the solid reaches the domain's "
                 "boundary; inside, its boundary is the traced iso-line.")
    elif geo != "traced":
        L.append(f"The part's boundary is traced from the thresholded polygons: {geo[8:-1]}.")
    ch = s.get("threshold_choice")
    if ch:
        L.append(f"The threshold: {ch['note']}.  Material volume of the design "
                 f"{ch['design_volume']:.6g} m², area of the part at the threshold used "
                 f"{ch['part_area']:.6g} m².")
    L.append("")
    L.append("| area (m²) | value |")
    L.append("|---|---|")
    L.append(f"| thresholded (clipped mesh) | {a['thresholded']:.6g} |")
    L.append(f"| polygons (specks removed: {a['removed_specks']:.3g}) | {a['polygons']:.6g} |")
    L.append(f"| kept (floating pieces dropped: {a['dropped_floating']:.3g}) | {a['kept']:.6g} |")
    L.append(f"| remeshed | {a['remeshed']:.6g} ({100 * a['remeshed_vs_kept']:+.2f} % of kept) |")
    L.append("")
    L.append(f"Wetted (`pressure`) boundary: {rm['wetted_length']:.4g} m.  Rule: "
             f"{d['definitions']['wetting']}.")
    sh = rm["output_port_shift"]
    if sh is not None:
        warn = "" if sh <= 2 * run["mesh_h"] else \
            " **The output point moved more than two element sizes: the solid does not reach it.**"
        L.append(f"The output point `{s['output']['region']}` sits on the nearest vertex of the "
                 f"new mesh, {sh:.3g} m from its place in the run.{warn}")
    L.append(f"Supports on the new mesh: {s['supports_used']}.  Output spring "
             f"{s['output']['spring']:g} N/m along {s['output']['direction']}.")
    L.append("")
    L.append("## Re-analysis (Neo-Hookean, plane strain)")
    L.append("")
    L.append(f"E = {s['E']:g} Pa, ν = {s['nu']:g}, t = {s['thickness']:g} m, displacement order "
             f"{s['order']}.")
    L.append("")
    L.append(f"* **expected** — {d['definitions']['expected']};")
    if "darcy" in kinds:
        L.append(f"* **darcy** (thesis §6.1.1, deformation-independent load) — "
                 f"{d['definitions']['darcy']};")
    if "fixed" in kinds:
        L.append(f"* **fixed** — {d['definitions']['fixed']};")
    if "follower" in kinds:
        L.append(f"* **follower** (thesis §6.1.2) — {d['definitions']['follower']}.")
    L.append("")
    L.append("![analysis](analysis.png)")
    L.append("")
    head = "| P (Pa) | expected Δ (m) | " + " | ".join(f"Δ {k} (m)" for k in kinds) + \
        " | max \\|u\\| (m) | min J | Newton its |"
    L.append(head)
    L.append("|" + "---|" * (4 + len(kinds)))
    ref = "follower" if "follower" in kinds else kinds[-1]
    for r in d["pressures"]:
        its = "/".join(str(r[k]["newton_iterations"]) for k in kinds)
        L.append(f"| {r['pressure']:.4g} | {_fmt(r['expected'])} | " +
                 " | ".join(_fmt(r[k]["delta"]) for k in kinds) +
                 f" | {_fmt(r[ref]['max_u'])} | {_fmt(r[ref]['min_J'])} | {its} |")
    L.append("")
    L.append(f"max |u| and min J of the {ref} analysis; Newton iterations "
             f"{'/'.join(kinds)}; — : not converged.")
    L.append("")
    pct = lambda gaps: ", ".join(f"{k} {_fmt(None if g is None else 100 * g, '+.1f')} %"
                                 for k, g in gaps.items())
    P = [r["pressure"] for r in d["pressures"]]
    L.append(f"Gap to the expected Δ, (analysed − expected)/|expected|: at {P[-1]:.4g} Pa "
             f"{pct(d['gap_at_largest_pressure'])}; at {P[0]:.4g} Pa "
             f"{pct(d['gap_at_smallest_pressure'])} (at a small pressure the gap is what "
             f"thresholding and remeshing change; its growth with the pressure is the "
             f"nonlinearity the optimisation's model missed).")
    L.append("")
    ds = d["deformed_state"]
    if ds["kind"] is not None:
        L.append("## Deformed")
        L.append("")
        L.append(f"The {ds['kind']} analysis at {ds['pressure']:.4g} Pa, true scale, over the "
                 f"undeformed outline:")
        L.append("")
        L.append("![deformed](deformed.png)")
        L.append("")
    L.append("## Files")
    L.append("")
    L.append("`analysis.json` (every number above), `analysis.csv`, `post.json`, `design.stl` "
             "(the part, extruded by t), `remeshed.vtu` / `deformed.vtu` (u, p, J, stress, "
             "von_mises; reference / deformed configuration), `analysis.png`, `deformed.png`.")
    L.append("")
    return "\n".join(L)


# ------------------------------------------------------------------------------------------
# pacto export
EXPORT_FORMATS = ("stl", "vtk", "msh")


def _design_density(problem) -> np.ndarray:
    """ρ̄ of the design; for two materials the total solid ρ̄1."""
    vals = problem.values
    return np.asarray(vals["rho_bar"] if "rho_bar" in vals else vals["rho_bar1"], dtype=float)


def part_of_run(run: Run, threshold_value: float, maxh: float | None):
    """Threshold and remesh the final design of a run (the wetting rule for pressure cases).
    Returns ``(Thresholded, Remeshed, problem)``; InputError when there is no part."""
    from .remesh import remesh
    from .threshold import threshold

    setup = run.case.make_setup(run.params)
    with compute():
        problem = rebuild(run)
    rho = _design_density(problem)
    shape, exclude = domain_of(problem, setup)
    kw = {}
    if setup.pressure is not None and problem.pressure_block is not None:
        kw = dict(pressure=_copy_gf(problem.pressure_block.gfp), p_in=run.load,
                  wet_boundaries=setup.pressure.inlet)
    h = 0.5 * problem.h if maxh is None else maxh
    try:
        th = threshold(problem.mesh, rho, threshold_value, exclude=exclude)
        rm = remesh(th, h, clamp=setup.supports.clamp, domain=shape, **kw)
    except ValueError as err:
        raise InputError(f"{err}") from None
    return th, rm, problem


def _boundary_names(mesh) -> list[str]:
    """The boundary names that have at least one edge (sorted)."""
    from ngsolve import BND

    return sorted({el.mat for el in mesh.Elements(BND)})


def write_msh(path, mesh):
    """Gmsh 2.2 file of a 2D NGSolve mesh through meshio: the triangles (physical ``solid``)
    and every boundary edge as a line whose physical group is its boundary name."""
    import meshio
    from ngsolve import BND

    pts = np.asarray(mesh.ngmesh.Coordinates(), dtype=float)
    tris, quads = [], []
    for el in mesh.ngmesh.Elements2D():
        vs = [v.nr - 1 for v in el.vertices]
        (tris if len(vs) == 3 else quads).append(vs)
    names = _boundary_names(mesh)
    tag = {n: i + 2 for i, n in enumerate(names)}
    lines, ltag = [], []
    for el in mesh.Elements(BND):
        lines.append([v.nr for v in el.vertices])
        ltag.append(tag[el.mat])
    cells, phys = [], []
    if lines:
        cells.append(("line", np.array(lines, dtype=np.int64)))
        phys.append(np.array(ltag, dtype=np.int64))
    for kind, block in (("triangle", tris), ("quad", quads)):
        if block:
            cells.append((kind, np.array(block, dtype=np.int64)))
            phys.append(np.ones(len(block), dtype=np.int64))
    field_data = {"solid": np.array([1, 2])}
    field_data.update({n: np.array([t, 1]) for n, t in tag.items()})
    m = meshio.Mesh(np.c_[pts, np.zeros(len(pts))], cells,
                    cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
                    field_data=field_data)
    meshio.write(str(path), m, file_format="gmsh22", binary=False)
    return m


def export_run(folder, fmt: str, *, out=None, threshold_value=None, maxh=None,
               quiet: bool = False) -> int:
    """``pacto export``: the thresholded, remeshed part of a run as stl | vtk | msh.

    Without ``--threshold``/``--maxh`` the settings of ``DIR/analysis/analysis.json`` are used
    when it exists (the exported part is then the analysed one), else 0.5 and half the run's
    element size.  STL: extruded by the thickness (closed); VTK: the 2D triangles (meshio, from
    the VTU the analysis writes); MSH: Gmsh 2.2 with the boundary names as physical groups.
    """
    from .export import convert, write_stl, write_vtu

    if fmt not in EXPORT_FORMATS:
        raise InputError(f"--format: choose from {', '.join(EXPORT_FORMATS)} (got '{fmt}')")
    if threshold_value is not None:
        check_threshold(threshold_value)
    if maxh is not None and not maxh > 0:
        raise InputError(f"--maxh: must be positive, got {maxh:g}")
    run = load_run(folder, "export")
    prev = run.path / "analysis" / "analysis.json"
    if prev.exists() and (threshold_value is None or maxh is None):
        try:
            s = json.loads(prev.read_text())["settings"]
            threshold_value = s["threshold"] if threshold_value is None else threshold_value
            maxh = s["maxh"] if maxh is None else maxh
        except (ValueError, KeyError):
            pass
    threshold_value = 0.5 if threshold_value is None else threshold_value
    th, rm, problem = part_of_run(run, threshold_value, maxh)
    dst = Path(out) if out else run.path / "export" / f"design.{fmt}"
    if dst.suffix.lower() != f".{fmt}":
        raise InputError(f"--out: '{dst}' must end in .{fmt}")
    try:
        dst.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise InputError(f"--out: cannot create '{dst.parent}' ({err.strerror})") from None
    if fmt == "stl":
        write_stl(dst, rm.mesh, run.params.thickness)
    elif fmt == "msh":
        write_msh(dst, rm.mesh)
    else:
        with tempfile.TemporaryDirectory() as tmp:
            src = Path(tmp) / "remeshed.vtu"
            write_vtu(src, rm.mesh)
            convert(src, dst)
    _say(quiet, f"{dst}: {run.case.name} part, threshold {th.threshold:g}, {rm.mesh.ne} "
                f"triangles, area {rm.area:.6g} m² (thresholded {th.area:.6g}), boundaries "
                f"{', '.join(_boundary_names(rm.mesh))}"
                + (f", extruded by {run.params.thickness:g} m" if fmt == "stl" else "")
                + {"domain": ", on the case's own geometry", "traced": ""}.get(
                    rm.geometry, f"; {rm.geometry}"))
    return 0


# ------------------------------------------------------------------------------------------
# pacto compare
def _design_triangles(vtu):
    """Points (n, 2), triangles (m, 3) with merged duplicate vertices, and the per-triangle
    ρ̄ of a run's design.vtu (NGSolve writes every element with its own vertices)."""
    import pyvista as pv

    g = pv.read(str(vtu))
    if "rho_bar" in g.point_data:
        key = "rho_bar"
    elif "rho_bar1" in g.point_data:
        key = "rho_bar1"
    else:
        raise InputError(f"compare: '{vtu}' has no rho_bar field")
    val = np.asarray(g.point_data[key], dtype=float)
    pts = np.asarray(g.points)[:, :2]
    scale = float(np.ptp(pts, axis=0).max()) or 1.0
    _, first, inv = np.unique(np.round(pts / scale, 9), axis=0, return_index=True,
                              return_inverse=True)
    inv = inv.ravel()
    tris, rho = [], []
    for ctype, conn in g.cells_dict.items():
        conn = np.asarray(conn)
        if conn.shape[1] == 3:
            t = conn
        elif conn.shape[1] == 4:
            t = np.r_[conn[:, [0, 1, 2]], conn[:, [0, 2, 3]]]
        else:
            continue
        tris.append(inv[t])
        rho.append(val[t].mean(axis=1))
    return pts[first], np.vstack(tris), np.concatenate(rho)


def _boundary_segments(vtu):
    import pyvista as pv

    g = pv.read(str(vtu))
    e = g.extract_feature_edges(boundary_edges=True, non_manifold_edges=False,
                                feature_edges=False, manifold_edges=False)
    lines = np.asarray(e.lines).reshape(-1, 3)[:, 1:]
    return np.asarray(e.points)[:, :2][lines]


def run_symmetry(run):
    """The symmetry line of a run's mesh (:func:`~pacto_ng.post.domain.symmetry_line`), from
    the case's mesh rebuilt; None when it has none or cannot be rebuilt."""
    from .domain import symmetry_line

    try:
        from ..case import mesh_for

        meshed = mesh_for(run.case, run.params)
        mesh = meshed.mesh if hasattr(meshed, "mesh") else meshed[0]
        return symmetry_line(mesh)
    except Exception:  # noqa: BLE001 - a picture without its mirror image, not an error
        return None


def _mirrored_design(pts, tri, rho, line):
    """The design triangles with their mirror image about ``line`` appended."""
    if line is None:
        return pts, tri, rho
    n = len(pts)
    return (np.vstack([pts, line.reflect(pts)]), np.vstack([tri, tri[:, ::-1] + n]),
            np.concatenate([rho, rho]))


def _labels(runs) -> list[str]:
    """``case model load`` per run, with the folder name where two would read the same."""
    base = [f"{r.case.name} {r.params.model} {r.load:.3g} {r.case.load_unit}" for r, _ in runs]
    return [b + (f" ({r.path.name})" if base.count(b) > 1 else "")
            for b, (r, _) in zip(base, runs)]


def compare_runs(folders, *, out=None, quiet: bool = False, mirror: bool = True) -> int:
    """``pacto compare``: the designs side by side, their thresholded outlines over each other
    (thesis Fig. 6.7) and, where ``analysis/analysis.json`` exists, their analysis curves in
    one picture (thesis Figs 6.10/6.12).  A run solved on a symmetric half is drawn whole
    (mirrored about its mesh's straight ``symmetry`` boundary) unless ``mirror`` is False."""
    from matplotlib.collections import LineCollection
    from matplotlib.tri import Triangulation

    from .export import _figure

    if len(folders) < 1:
        raise InputError("compare: give at least one run folder")
    runs = []
    for f in folders:
        run = load_run(f, "compare")
        if not (run.path / "design.vtu").exists():
            raise InputError(f"compare: '{f}' has no design.vtu")
        ana = run.path / "analysis" / "analysis.json"
        runs.append((run, json.loads(ana.read_text()) if ana.exists() else None))
    dst = Path(out) if out else Path("compare.png")
    if dst.suffix.lower() != ".png":
        raise InputError(f"--out: '{dst}' must end in .png")
    try:
        dst.parent.mkdir(parents=True, exist_ok=True)
    except OSError as err:
        raise InputError(f"--out: cannot create '{dst.parent}' ({err.strerror})") from None

    n = len(runs)
    has_curves = any(a is not None for _, a in runs)
    colours = ["tab:red", "tab:blue", "tab:green", "tab:orange", "tab:purple", "tab:brown",
               "tab:pink", "tab:gray", "tab:olive", "tab:cyan"]
    lines = [run_symmetry(r) if mirror else None for r, _ in runs]
    designs = [_mirrored_design(*_design_triangles(r.path / "design.vtu"), ln)
               for (r, _), ln in zip(runs, lines)]
    allp = np.vstack([d[0] for d in designs])
    w, h = np.ptp(allp, axis=0)
    aspect = h / max(w, 1e-300)
    labels = _labels(runs)
    ncol = min(n, 3)
    nrow = -(-n // ncol)
    top_h = nrow * (4.2 * aspect + 0.7)
    bottom_h = 4.6
    fig = _figure((12.0, top_h + bottom_h))
    top, bottom = fig.subfigures(2, 1, height_ratios=[top_h, bottom_h])
    for i, ((run, ana), (pts, tri, rho)) in enumerate(zip(runs, designs)):
        ax = top.add_subplot(nrow, ncol, i + 1)
        ax.tripcolor(Triangulation(pts[:, 0], pts[:, 1], tri), facecolors=rho, cmap="gray_r",
                     vmin=0.0, vmax=1.0)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        s = run.summary
        delta = s.get("output_displacement")
        extra = "" if delta is None else \
            f"\nΔ = {delta:.3g} m, volume {s.get('volume_fraction', float('nan')):.3f}"
        ax.set_title(labels[i] + extra, fontsize=9, color=colours[i % 10])
    # outlines over each other (thesis Fig. 6.7)
    ax = bottom.add_subplot(1, 2, 1) if has_curves else bottom.add_subplot(1, 1, 1)
    for i, ((run, ana), (pts, tri, rho)) in enumerate(zip(runs, designs)):
        c = colours[i % 10]
        rem = run.path / "analysis" / "remeshed.vtu"
        if rem.exists():
            segs = _boundary_segments(rem)
            if lines[i] is not None:
                segs = np.concatenate([segs, lines[i].reflect(segs)])
            ax.add_collection(LineCollection(segs, colors=c, linewidths=1.2))
        else:
            t = Triangulation(pts[:, 0], pts[:, 1], tri)
            nod = np.zeros(len(pts))
            cnt = np.zeros(len(pts))
            e1, e2 = pts[tri[:, 1]] - pts[tri[:, 0]], pts[tri[:, 2]] - pts[tri[:, 0]]
            area = 0.5 * np.abs(e1[:, 0] * e2[:, 1] - e1[:, 1] * e2[:, 0])
            for k in range(3):
                np.add.at(nod, tri[:, k], area * rho)
                np.add.at(cnt, tri[:, k], area)
            ax.tricontour(t, nod / np.maximum(cnt, 1e-300), levels=[0.5], colors=[c],
                          linewidths=1.2)
        ax.plot([], [], color=c, label=labels[i])
    ax.set_xlim(allp[:, 0].min(), allp[:, 0].max())
    ax.set_ylim(allp[:, 1].min(), allp[:, 1].max())
    ax.set_aspect("equal")
    ax.set_title("thresholded designs (remeshed outline, else ρ̄ = 0.5)", fontsize=9)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.08), frameon=False)
    if has_curves:
        ax = bottom.add_subplot(1, 2, 2)
        style = {"expected": ("o", "--"), "darcy": ("s", "-"), "fixed": ("x", ":"),
                 "follower": ("^", "-.")}
        allpos = True
        for i, (run, ana) in enumerate(runs):
            if ana is None:
                continue
            c = colours[i % 10]
            P = np.array([r["pressure"] for r in ana["pressures"]])
            series = {"expected": [r["expected"] for r in ana["pressures"]]}
            for k in ana["settings"]["kinds"]:
                series[k] = [r[k]["delta"] for r in ana["pressures"]]
            for k, vals in series.items():
                v = np.array([np.nan if x is None else x for x in vals], dtype=float)
                ok = np.isfinite(v)
                if not ok.any():
                    continue
                allpos &= bool(np.all(v[ok] > 0))
                m, ls = style.get(k, ("+", "-"))
                ax.plot(P[ok], v[ok], marker=m, ls=ls, color=c,
                        mfc="none" if k == "expected" else c)
        for k, (m, ls) in style.items():
            ax.plot([], [], marker=m, ls=ls, color="k", mfc="none" if k == "expected" else "k",
                    label=k)
        ax.set_xscale("log")
        if allpos:
            ax.set_yscale("log")
        ax.set_xlabel("pressure (Pa)")
        ax.set_ylabel("output displacement Δ (m)")
        ax.grid(True, alpha=0.3)
        ax.legend(fontsize=8, title="colour: run", title_fontsize=8)
        ax.set_title("expected (optimisation) and the Neo-Hookean re-analyses", fontsize=9)
    fig.savefig(str(dst), dpi=130)
    if not quiet:
        print(f"{'run':40s} {'case':12s} {'model':11s} {'load':>9s} {'Δ (m)':>11s} "
              f"{'gap darcy':>10s} {'gap follower':>13s}")
        for (run, ana), lab in zip(runs, labels):
            gaps = (ana or {}).get("gap_at_largest_pressure", {})
            g = lambda k: "—" if gaps.get(k) is None else f"{100 * gaps[k]:+.1f} %"
            d = run.summary.get("output_displacement")
            print(f"{str(run.path)[-40:]:40s} {run.case.name:12s} {run.params.model:11s} "
                  f"{run.load:9.3g} {_fmt(d, '11.4g'):>11s} {g('darcy'):>10s} "
                  f"{g('follower'):>13s}")
        print(f"picture: {dst}")
    return 0

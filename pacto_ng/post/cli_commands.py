"""``pacto analyse`` and ``pacto export``: from a finished run to a part (``pacto compare`` is
:mod:`pacto_ng.post.compare`; reading a run folder back, :mod:`pacto_ng.post.runs`).

``analyse DIR`` rebuilds the problem of a run folder (``params.json``), takes its final design
(``checkpoint.npz``: ``x``, or ``last_good`` when the run stopped on a Newton failure), and
calls :func:`~pacto_ng.post.report.post_analyse` with the case's supports, output ports and
springs, wetting rule and Darcy pressure.  Δ is the output as the optimisation defines it,
``Σ_k w_k d_k·u(x_k)`` over the case's output ports (one, or several: a gripper's jaws), and
every port's own ``d_k·u(x_k)`` is recorded beside it.  It writes into ``DIR/analysis/``:

=================  ====================================================================
``analysis.json``  per pressure: expected Δ, Δ and every port's d·u of the three analyses,
                   max |u|, min J, Newton iterations; areas, wetting, ports, every setting used
``analysis.png``   Δ against pressure: expected, Darcy, fixed and follower pressure
``deformed.png``   undeformed outline over the deformed solid (follower, largest pressure)
``report.md``      the pictures and the numbers together
``design.stl``     the thresholded, remeshed solid extruded by the thickness (watertight)
``remeshed.vtu``   remeshed solid: ``u``, ``p``, ``J``, ``stress``, ``von_mises``
``deformed.vtu``   the same in the deformed configuration
``analysis.csv``   one row per (analysis, pressure) (written by ``post_analyse``)
``post.json``      the summary of ``post_analyse``
=================  ====================================================================

The three Neo-Hookean analyses of the remeshed design (plane strain, the run's ν and t, and
its E1, or with two materials each material's own modulus on its part of the mesh):

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
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

from ..files import atomic_path, atomic_write_text
from ..params import InputError
from ..threads import compute
from .export import UNITS as UNITS_OF
from .materials import material_areas
from .post3d import analyse_run_3d, export_run_3d, is_3d
from .report import analysis_dict, fmt_value, report_md, short_table
from .runs import (check_part_mesh, copy_gridfunction, design_density, domain_of,
                   export_destination, load_run, materials_of, part_of_run, rebuild,
                   thresholded_elements)

KINDS = ("darcy", "fixed", "follower")


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


def check_threshold(value, *, allow_volume: bool = False, name: str = "--threshold"):
    """A threshold in (0, 1), or (with ``allow_volume``) the word ``volume``: the
    volume-preserving threshold of :func:`~pacto_ng.post.threshold_choice.volume_threshold`."""
    if isinstance(value, str):
        if value.strip().lower() == "volume":
            if not allow_volume:
                raise InputError(f"{name}: 'volume' is an option of 'pacto analyse' "
                                 f"--threshold only; give a number in (0, 1)")
            return "volume"
        try:
            value = float(value)
        except ValueError:
            raise InputError(f"{name}: expected a number in (0, 1)"
                             f"{' or volume' if allow_volume else ''}, got '{value}'") from None
    if not (0.0 < float(value) < 1.0) or not math.isfinite(float(value)):
        raise InputError(f"{name}: must lie in (0, 1), got {value:g}")
    return float(value)


def default_pressures(load: float, n: int = 5, span: float = 100.0) -> list[float]:
    """``n`` log-spaced pressures from ``load / span`` to the run's ``load``."""
    return [float(v) for v in np.geomspace(load / span, load, n)]


# ------------------------------------------------------------------------------------------
def expected_sweep(problem, x, pressures, load) -> list[dict]:
    """Δ of the density design with the optimisation's own model at every pressure (see the
    module docstring).  Leaves the problem at the last pressure."""
    from ..physics.equilibrium import NewtonFailure

    mech = problem.mech
    warm = mech.state
    mech.set_state(replace(warm, u=np.zeros_like(warm.u), converged=False))
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


def case_ports(setup):
    """The re-analysis's output ports: the case's ports (region, direction, weight: Δ = Σ
    weight · direction · u, as the optimisation reads it), each with the springs of the case
    on its point along its direction as its spring."""
    from ..physics.loads import Port

    out = []
    for port in setup.ports:
        d = np.asarray(port.direction, dtype=float)
        d = d / np.linalg.norm(d)
        k = 0.0
        for s in setup.all_springs:
            sd = np.asarray(s.direction, dtype=float)
            sd = sd / np.linalg.norm(sd)
            if s.region == port.region and abs(abs(sd @ d) - 1.0) < 1e-12:
                k += float(s.stiffness)
        out.append(Port(port.region, tuple(map(float, port.direction)), k, float(port.weight)))
    return tuple(out)


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


def analyse_run(folder, *, pressures=None, threshold_value=0.5, maxh=None,
                order: int = 2, kinds=KINDS, quiet: bool = False, connect: bool = True,
                threshold2=0.5) -> int:
    """``pacto analyse``: see the module docstring.  Returns the exit code (0).

    A two-material run (mm-gripper): ρ̄1 is thresholded as above, ρ̄2 at ``threshold2``
    inside the part (:mod:`~pacto_ng.post.materials`); the part has regions ``soft`` (E1) and
    ``stiff`` (E2) and every analysis uses each region's modulus."""
    from .remesh import pressure_sampler
    from .report import post_analyse
    from .threshold import threshold
    from .threshold_choice import choose_threshold

    threshold_value = check_threshold(threshold_value, allow_volume=True)
    threshold2 = check_threshold(threshold2, name="--threshold2")
    if maxh is not None and not maxh > 0:
        raise InputError(f"--maxh: must be positive, got {maxh:g}")
    if order not in (1, 2, 3):
        raise InputError(f"--order: must be 1, 2 or 3, got {order}")
    bad = [k for k in kinds if k not in KINDS]
    if bad or not kinds:
        raise InputError(f"--kinds: choose from {', '.join(KINDS)} (got {','.join(kinds) or 'none'})")
    run = load_run(folder, "analyse")
    if is_3d(run):
        return analyse_run_3d(run, pressures=pressures, threshold_value=threshold_value,
                              maxh=maxh, order=order, kinds=kinds, threshold2=threshold2,
                              quiet=quiet)
    setup = run.case.make_setup(run.params)
    if setup.pressure is None:
        raise InputError(f"analyse: case '{run.case.name}' has no pressure load; the re-analysis "
                         f"applies to pressure cases only ('pacto export {folder}' writes its part)")
    if setup.port is None:
        raise InputError(f"analyse: case '{run.case.name}' has no output port")
    ports = case_ports(setup)
    pressures = default_pressures(run.load) if pressures is None else list(pressures)
    t0 = time.perf_counter()
    _say(quiet, f"analyse {run.path}: {run.case.name}, model {run.params.model}, load "
                f"{run.load:g} {run.case.load_unit}, design '{run.design}' after {run.k} iterations")
    with compute():
        problem = rebuild(run)
    p = run.params
    rho = design_density(problem).copy()  # ρ̄; with two materials the solid field ρ̄1
    maxh = 0.5 * problem.h if maxh is None else float(maxh)
    # the part's mesh and its Neo-Hookean sweeps (the follower's tangent is unsymmetric)
    check_part_mesh(run, problem, rho, maxh, order=order,
                    solver="umfpack" if "follower" in kinds else "sparsecholesky")
    if problem.failure:
        import sys

        print(f"pacto: warning: the run's own model fails on its final design at the full "
              f"load ({problem.failure}); the expected Δ is recorded where it converges",
              file=sys.stderr)
        delta_run = None
    else:
        delta_run = float(problem.values["delta"])
    block = problem.pressure_block
    p_final = copy_gridfunction(block.gfp)  # the final Darcy field at P_in = load (the wetting rule)
    _say(quiet, f"  rebuilt: Δ = {fmt_value(delta_run, '.6g')} m at {run.load:g} Pa (summary.json: "
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
    choice, th = choose_threshold(problem.mesh, rho, threshold_value,
                                  [port.region for port in ports],
                                  supports.clamp, connect=connect, exclude=exclude)
    threshold_value = choice["used"]
    stiff, E = materials_of(problem, setup, p, threshold2, exclude)
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
        p_thr = copy_gridfunction(block.gfp)
        _say(quiet, f"  threshold {thr:g}, remesh (maxh {maxh:g}), "
                    f"Neo-Hookean sweeps {', '.join(kinds)} at {len(pressures)} pressures ...")
        try:
            res = post_analyse(problem.mesh, rho, out_dir, pressures=pressures, E=E, nu=p.nu,
                               thickness=p.thickness, output=ports, clamp=supports.clamp,
                               supports=supports, threshold_value=thr, thresholded=th,
                               maxh=maxh,
                               pressure=p_final, p_in=run.load,
                               wet_boundaries=setup.pressure.inlet, kinds=tuple(kinds),
                               darcy_pressure=p_thr, darcy_p_in=run.load, expected=exp_pair,
                               order=order, newton=newton, domain=shape, exclude=exclude,
                               stiff=stiff)
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

    data = analysis_dict(run, problem, res, expected, pressures, delta_run, kinds, order,
                          choice, maxh, ports, supports, p_shown, rho_thr,
                          time.perf_counter() - t0, path_note)
    atomic_write_text(out_dir / "analysis.json", json.dumps(data, indent=1))
    import sys

    if path_note:
        print(f"pacto: warning: {path_note}", file=sys.stderr)
    for region, shift in data["remesh"]["port_shifts"].items():
        if shift > 2.0 * problem.h:
            print(f"pacto: warning: the thresholded part does not reach the output point "
                  f"'{region}': its nearest vertex is {shift:.3g} m away (Δ is read there; see "
                  f"report.md)", file=sys.stderr)
    from .export import plot_sweeps

    plot_sweeps(out_dir / "analysis.png", [res.sweeps[k] for k in kinds if k in res.sweeps],
                expected=exp_pair, log=True,
                title=f"{run.case.name} — {p.model} design (optimised at {run.load:.3g} Pa)")
    atomic_write_text(out_dir / "report.md", report_md(data))
    _say(quiet, short_table(data))
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
        with atomic_path(f) as tmp:
            m.write(str(tmp), file_format="vtu")


# ------------------------------------------------------------------------------------------
# pacto export
EXPORT_FORMATS = ("stl", "vtk", "vtu", "msh")
#: ``pacto export``'s length unit when ``--units`` is not given: the STL (for slicers and CAD,
#: which read it in mm) in mm; the analysis files (vtk, vtu, msh) in the solver's SI metres
DEFAULT_UNITS = {"stl": "mm", "vtk": "m", "vtu": "m", "msh": "m"}


def _boundary_names(mesh) -> list[str]:
    """The boundary names that have at least one edge (sorted)."""
    from ngsolve import BND

    return sorted({el.mat for el in mesh.Elements(BND)})


def check_units(units, fmt: str) -> str:
    """``--units``: mm or m (None: :data:`DEFAULT_UNITS` of the format)."""
    from .export import UNITS

    if units is None:
        return DEFAULT_UNITS[fmt]
    if units not in UNITS:
        raise InputError(f"--units: choose from {', '.join(UNITS)} (got '{units}')")
    return units


def write_msh(path, mesh, *, units: str = "m"):
    """Gmsh 2.2 file of a 2D part through meshio: the triangles, whose physical group
    is their material (``solid``; ``soft`` and ``stiff`` for a two-material part), and every
    boundary edge as a line whose physical group is its boundary name (the materials are
    groups 1, 2, ..., the boundaries follow).  ``mesh`` is a 2D NGSolve mesh or a
    :class:`~pacto_ng.post.part2d.PartMesh` (e.g. the whole, mirrored part); coordinates in
    ``units``."""
    import meshio

    from .export import UNITS
    from .part2d import PartMesh, part_mesh

    part = mesh if isinstance(mesh, PartMesh) else part_mesh(mesh)
    mat_groups = part.material_groups
    names = sorted(set(part.edge_names))
    tag = {n: i + 1 + len(mat_groups) for i, n in enumerate(names)}
    cells, phys = [], []
    if len(part.edges):
        cells.append(("line", part.edges))
        phys.append(np.array([tag[n] for n in part.edge_names], dtype=np.int64))
    for (kind, block), idx in zip(part.blocks(), part.block_order()):
        cells.append((kind, block))
        phys.append(part.material[idx].astype(np.int64))
    field_data = dict(mat_groups)
    field_data.update({n: np.array([t, 1]) for n, t in tag.items()})
    pts = part.points / UNITS[units]
    m = meshio.Mesh(np.c_[pts, np.zeros(len(pts))], cells,
                    cell_data={"gmsh:physical": phys, "gmsh:geometrical": phys},
                    field_data=field_data)
    with atomic_path(path) as tmp:
        meshio.write(str(tmp), m, file_format="gmsh22", binary=False)
    return m


def export_run(folder, fmt: str, *, out=None, threshold_value=None, maxh=None,
               quiet: bool = False, threshold2=None, units=None, mirror: bool = True) -> int:
    """``pacto export``: the thresholded, remeshed part of a run as stl | vtk | vtu | msh.

    Without ``--threshold``/``--maxh`` the settings of ``DIR/analysis/analysis.json`` are used
    when it exists (the exported part is then the analysed one), else 0.5 and half the run's
    element size.

    * ``mirror`` (default): a case solved on a symmetric half (a straight ``symmetry``
      boundary) is written whole: the part and its mirror image merged along the line
      (:func:`~pacto_ng.post.part2d.part_mesh`); False: the half as solved.
    * ``units``: ``mm`` or ``m``, default :data:`DEFAULT_UNITS` (mm for STL, m otherwise).
    * STL: the part extruded by the case's thickness (``params.json``), closed, binary, the
      unit in its header.  VTK / VTU: the 2D cells with the run's final state on them
      (:func:`~pacto_ng.post.part2d.part_fields`: ρ̄, u, p, the model's strain and stress; the
      coordinates and u in ``units``, p and stress in Pa).  MSH: Gmsh 2.2 with the boundary
      names as physical groups.
    * A two-material part (``threshold2``: ρ̄2's, default the analysis's, else 0.5) has the
      regions ``soft`` and ``stiff``: the STL is the whole part; the VTK/VTU has cell data
      ``material`` (named in its field data) and ``E``; the MSH the materials as physical
      groups of the triangles.
    """
    from .domain import symmetry_line
    from .part2d import part_fields, part_mesh, write_part_stl, write_part_vtu

    if fmt not in EXPORT_FORMATS:
        raise InputError(f"--format: choose from {', '.join(EXPORT_FORMATS)} (got '{fmt}')")
    units = check_units(units, fmt)
    if threshold_value is not None:
        check_threshold(threshold_value)
    if threshold2 is not None:
        threshold2 = check_threshold(threshold2, name="--threshold2")
    if maxh is not None and not maxh > 0:
        raise InputError(f"--maxh: must be positive, got {maxh:g}")
    run = load_run(folder, "export")
    if is_3d(run):
        return export_run_3d(run, fmt, out=out, threshold_value=threshold_value, quiet=quiet,
                             units=units, mirror=mirror, threshold2=threshold2)
    prev = run.path / "analysis" / "analysis.json"
    if prev.exists() and (threshold_value is None or maxh is None or threshold2 is None):
        try:
            s = json.loads(prev.read_text())["settings"]
            threshold_value = s["threshold"] if threshold_value is None else threshold_value
            maxh = s["maxh"] if maxh is None else maxh
            threshold2 = s.get("threshold2") if threshold2 is None else threshold2
        except (ValueError, KeyError):
            pass
    threshold_value = 0.5 if threshold_value is None else threshold_value
    threshold2 = 0.5 if threshold2 is None else threshold2
    th, rm, problem = part_of_run(run, threshold_value, maxh, threshold2)
    two = rm.materials is not None
    # the whole mechanism: the symmetry line of the run's own mesh (the part may not reach it)
    line = symmetry_line(problem.mesh) if mirror else None
    part = part_mesh(rm.mesh, line)
    dst = export_destination(run, out, fmt)
    t = float(run.params.thickness)
    scale = 1.0 / UNITS_OF[units]
    notes = []
    if mirror and line is None and run.summary.get("symmetric_half_domain"):
        notes.append("not mirrored: the run's symmetry boundary is not a straight line")
    if fmt == "stl":
        write_part_stl(dst, part, t, units=units,
                       header=f"pacto_ng {run.case.name} part, thickness {t * scale:g} {units}"
                              + (", whole (mirrored)" if line is not None else ""))
    elif fmt == "msh":
        write_msh(dst, part, units=units)
    else:
        E = {"soft": run.params.E1, "stiff": run.params.E2} if two else None
        try:
            point, cell, field_notes = part_fields(problem, part)
        except ValueError as err:
            raise InputError(f"export: {err}") from None
        notes += field_notes
        write_part_vtu(dst, part, point_data=point, cell_data=cell, units=units, fmt=fmt, E=E)
        notes.append("fields " + ", ".join([*point, *cell]) + " of the run's final state")
    _say(quiet, f"{dst}: {run.case.name} part"
                + (" (whole: the half and its mirror image)" if line is not None else "")
                + f", threshold {th.threshold:g}, {len(part.elements)} "
                f"{'triangles' if all(len(e) == 3 for e in part.elements) else 'elements'}, "
                f"area {part.area() * scale ** 2:.6g} {units}² ("
                + ("the half: " if line is not None else "")
                + f"remeshed {rm.area:.6g} m², thresholded {th.area:.6g} m²), boundaries "
                f"{', '.join(sorted(set(part.edge_names)))}"
                + (f", extruded by the thickness {t * scale:g} {units}" if fmt == "stl" else "")
                + f"; units {units}"
                + ("; materials " + ", ".join(f"{k} {v:.6g} m²" for k, v in
                                              material_areas(rm.mesh).items())
                   + f" (ρ̄2 at {threshold2:g}, {rm.materials})" if two else "")
                + {"domain": ", on the case's own geometry", "traced": ""}.get(
                    rm.geometry, f"; {rm.geometry}")
                + "".join(f"; {n}" for n in notes))
    return 0

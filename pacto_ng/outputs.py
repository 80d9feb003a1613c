"""What a run writes to its folder: summary.json, history.csv, design.vtu and the pictures.

DIR/summary.json       case, model, parameters, iterations, objective and its history, volume
                       fraction, output displacement, load reached, converged flag, Newton counts,
                       wall time, mesh size and element order
DIR/history.csv        one row per iteration
DIR/design.vtu         x, rho_bar, u (and p) and the model's strain and stress measures
DIR/design.png         the physical density (a half-domain case mirrored: the whole mechanism;
                       3D: the ρ̄ = 0.5 iso-surface and the mid-depth cut, pacto_ng/post/plots3d.py)
DIR/pressure.png       pressure cases: p / P_in with the ρ̄ = 0.5 contour, its title the leak
                       Q/(Kv P_in) of summary.json (3D: on the mid-depth cut)
DIR/materials.png      two-material cases in 2D: where the soft and the stiff material are
DIR/convergence.png    objective and volume against iteration

Each file is written whole or not at all (:mod:`pacto_ng.files`), summary.json last: a folder
with a summary.json holds a finished run's complete results.
"""
from __future__ import annotations

import csv
import dataclasses
import io
import json
from pathlib import Path

import numpy as np

from .delta import output_displacement, output_displacement_at
from .files import atomic_path, atomic_write_text, check_tail
from .filters import HelmholtzFilter
from .measures import strain_stress_measures, tensor_components
from .physics.darcy_leakage import Outflow, leakage
from .physics.darcy_load import Compliance
from .problem import Problem, shown_density
from .responses import StrainEnergy, compliance as compliance_block

#: the columns of history.csv (one row per iteration), then the case's reported responses
HISTORY_COLUMNS = ("iteration", "objective", "volume", "constraint", "change", "penal", "beta",
                   "load", "newton", "load_steps", "design_cuts", "time")


@dataclasses.dataclass(frozen=True)
class Drawn:
    """What a run's pictures draw (:func:`write_pictures`), on one serial mesh: a serial run's
    problem (:func:`drawn`), or a distributed run's fields gathered to rank 0 on the serial
    mesh it meshed (:mod:`pacto_ng.parallel_outputs`).  ``shown``: the density drawn
    per element (ρ̄, or with two materials ρ̄1 (1 + ρ̄2) / 2); ``solid``: the pressure's
    density per element (its ρ̄ = 0.5 contour); ``p_rel``: p / P_in at the vertices;
    ``materials``: (ρ̄1, ρ̄2) of a two-material design; ``areas``: the element areas (volumes
    in 3D)."""

    mesh: object
    name: str
    model: str
    volume: float
    shown: np.ndarray
    solid: np.ndarray | None = None
    p_rel: np.ndarray | None = None
    p_in: float = 0.0
    leak: float | None = None
    materials: tuple | None = None
    areas: np.ndarray | None = None


#: the element densities a run's files hold (the one or the two materials')
DENSITIES = ("rho_bar", "rho_bar1", "rho_bar2")


@dataclasses.dataclass(frozen=True)
class OneMesh:
    """A run's fields on one serial mesh: a serial run's own (:func:`one_mesh`), or a
    distributed run's gathered to rank 0 onto the serial mesh it meshed and kept
    (:mod:`pacto_ng.parallel_outputs`).  ``cells``: element arrays by name in the mesh's
    order (:func:`cell_names`); ``design``: the mask of the design elements; ``areas``: the
    element areas (volumes in 3D); ``p``: the pressure at the mesh's vertices (None: no
    pressure)."""

    mesh: object
    cells: dict
    design: np.ndarray
    areas: np.ndarray
    p: np.ndarray | None = None


def run_summary(problem: Problem, history: list, result, wall: float) -> dict:
    """The figures of summary.json that every run has, serial or on a distributed mesh
    (:mod:`pacto_ng.parallel_outputs`; on a distributed mesh every rank computes them
    together): the case, the parameters, the objective and its history, the volume
    fraction, the greyness, how the run stopped, the wall time and the automatic choices."""
    vals = problem.values
    return {
        "case": problem.case.name,
        "model": problem.params.model,
        "parameters": problem.params.to_dict(),
        "load": problem.params.load,
        "load_unit": problem.case.load_unit,
        "iterations": len(history),
        "objective": float(vals[problem.objective]) if problem.objective in vals else None,
        "objective_name": problem.objective,
        "objective_history": [h["objective"] for h in history],
        "volume_fraction": problem.volume_fraction(),
        "greyness": problem.greyness(),
        "converged": result.converged,
        "stopped": result.stopped,
        "message": result.message,
        "wall_time_s": wall,
        "model_choice": problem.model_choice,
        "load_ramp_choice": problem.load_ramp_choice,
    }


def summary_dict(problem: Problem, history: list, result, wall: float,
                 one: OneMesh | None) -> dict:
    """summary.json of a run: :func:`run_summary` and the figures of the analysis.  On a
    distributed mesh every rank calls it (its figures are reduced over the ranks), and
    ``one``, the element fields on one serial mesh (:func:`one_mesh`; a distributed run's,
    gathered to the rank that writes: None elsewhere), gives the figures made on it: the
    leakage and a two-material design's fractions."""
    p = problem.params
    vals = problem.values
    mech_res = problem.mech.result

    def val(name):
        return float(vals[name]) if name in vals else None

    # an optimisation's Newton iterations per iteration; a single analysis (evaluate): its own
    newton_counts = [h["newton"] for h in history] if history else \
        ([int(mech_res.iterations)] if mech_res else [])
    out = run_summary(problem, history, result, wall)
    out.update({
        "output_displacement": val("delta") if "delta" in vals else output_displacement(problem),
        "output_displacement_at": output_displacement_at(problem),
        "compliance": val("compliance") if "compliance" in vals else compliance(problem),
        "strain_energy": val("se") if "se" in vals else strain_energy(problem),
        "load_reached": (mech_res.load_reached * p.load) if mech_res else None,
        "load_factor_reached": mech_res.load_reached if mech_res else None,
        # the lowest objective of an iterate of the final problem, where it beats the reported
        # design's: {"iteration", "objective"} (null: the reported design is the best seen)
        "best_iterate": result.best,
        "newton_iterations": newton_counts,
        "newton_iterations_total": int(sum(newton_counts)),
        "mesh": {"elements": _elements(problem), "h": problem.h, "order": p.order,
                 "displacement_dofs": problem.mech.ndof,
                 "structured": p.nelx > 0, "nelx": p.nelx, "nely": p.nely, "nelz": p.nelz,
                 "dim": problem.mesh.dim},
        "element_order": p.order,
        "formulation": problem.mech.formulation,
        "darcy_solve": problem.pressure_block is not None,
        "symmetric_half_domain": any(n == "symmetry" for n in problem.mesh.GetBoundaries()),
        # the mechanics adjoints of this process: solved, and skipped because the adjoint was
        # the primal (compliance of design-independent loads on a linear model)
        "adjoint_solves": {"solved": problem.mech.adjoint_solves,
                           "skipped_self_adjoint": problem.mech.adjoint_solves_skipped},
        "solvers": solvers_used(problem),
    })
    out.update(lowest_jacobian(problem))
    out.update(pressure_and_material_summary(problem, one))
    if problem.numbering is not None:
        out["mpi"] = {"ranks": problem.numbering.comm.size,
                      "elements_per_rank": problem.numbering.counts}
    return out


def _elements(problem: Problem) -> int:
    """The number of elements of the run's mesh (on a distributed mesh, of every rank)."""
    return problem.mesh.ne if problem.numbering is None else problem.numbering.ne


def solvers_used(problem: Problem) -> dict:
    """The linear solver of each system (``--set solver``, :mod:`pacto_ng.physics.solvers`):
    the displacement's tangent, the Darcy pressure's and the Helmholtz filter's (None: no
    such system), each as its ``solver_info`` (route, method, preconditioner, iterations)."""
    filters = [b for b in problem.chain.blocks if isinstance(b, HelmholtzFilter)]
    return {"displacement": problem.mech.solver_info,
            "pressure": (problem.pressure_block.solver_info
                         if problem.pressure_block is not None else None),
            "filter": filters[0].solver_info if filters else None}


def lowest_jacobian(problem: Problem) -> dict:
    """Where ``J = det F`` of the last analysed state is lowest: ``lowest_J`` at the
    quadrature points (where the energy is evaluated and Newton's guard is checked) and
    ``lowest_J_corners`` at the vertices, edge midpoints and centroids, each
    ``{"J", "element", "rho_bar", "point"}`` (element index in NGSolve's order, its design
    density, the kind of point).  Both None before any analysis and for the linear model,
    which has no deformation gradient (``det(I + ∇u)`` of a small-strain displacement is
    not a quantity it uses, and its Newton has no guard)."""
    if "u" not in problem.values or problem.params.model == "linear":
        return {"lowest_J": None, "lowest_J_corners": None}
    rho = problem.design_density()
    out = {}
    for key, points in (("lowest_J", "quadrature"), ("lowest_J_corners", "corners")):
        low = problem.mech.lowest_jacobian(points)
        el = low["element"]
        out[key] = {"J": low["J"], "element": el, "point": low["point"],
                    "rho_bar": float(rho[el]) if el >= 0 else None}
        if problem.numbering is not None:  # the least over the ranks, in the serial order
            out[key] = problem.numbering.least(out[key], "J")
    return out


def strain_energy(problem: Problem) -> float | None:
    """The stored strain energy of the last analysed state, for a run whose chain does not
    compute it (None before any analysis)."""
    vals = problem.values
    if "u" not in vals:
        return None
    block = StrainEnergy(problem.mech)
    return block.forward(*(vals[name] for name in block.inputs))


def compliance(problem: Problem) -> float | None:
    """The end compliance ``f·u`` of the last analysed state at full load, for a run whose
    chain does not compute it: the point/edge loads and a fixed Darcy body load, as the
    compliance objective defines it.  None before any analysis, and where no compliance is
    defined (a follower load, whose load vector depends on u; no load at all)."""
    vals = problem.values
    mech = problem.mech
    if "u" not in vals or mech.has_residual_density:
        return None
    if problem.pressure_block is not None:
        block = Compliance(mech, problem.pressure_block)
        return block.forward(*(vals[name] for name in block.inputs))
    if not mech.loads:
        return None
    return compliance_block(mech).forward(vals["u"])


def leak(problem: Problem) -> float | None:
    """``Q/(Kv P_in)`` of the reported design: the Darcy flow out through the zero-pressure
    boundaries (:class:`~pacto_ng.physics.darcy_leakage.Outflow`) of its pressure field.  The
    chain's own value where it has one (``leak_max``: the blueprint's), else an Outflow block
    evaluated once on the final ρ̄ and p; 0 for a set-up without zero-pressure boundaries
    (nothing flows out), None for a case without a pressure or before its pressure is
    solved."""
    vals, blk = problem.values, problem.pressure_block
    if "leak" in vals:
        return float(vals["leak"])
    if blk is None or blk.output not in vals or blk.inputs[0] not in vals:
        return None
    if not blk.zero:
        return 0.0
    return float(Outflow(blk).forward(vals[blk.inputs[0]], vals[blk.output]))


def pressure_and_material_summary(problem: Problem, one: OneMesh | None) -> dict:
    """Pressure cases: ``leak`` (Q/(Kv P_in), :func:`leak`; every rank of a distributed
    mesh), and on the fields of ``one`` (:func:`summary_dict`) ``leakage`` (the largest
    pressure in solid away from the cavity, a fraction of P_in, see
    :func:`pacto_ng.physics.darcy_leakage.leakage`) with its details.  Two materials: the
    volume fractions of :func:`material_fractions`."""
    out = {}
    blk = problem.pressure_block
    if blk is not None:
        out["leak"] = leak(problem)
    if one is None:
        return out
    if blk is not None:
        info = leakage(one.mesh, blk.inlet, one.cells[blk.inputs[0]], one.p, p_in=blk.p_in,
                       delta_s=blk.delta_s, h=problem.h)
        out["leakage"] = info.pop("leakage")
        out["leakage_detail"] = info
    if problem.n_design_fields == 2:
        out["material_fractions"] = material_fractions(one.design, one.areas,
                                                       one.cells["rho_bar1"],
                                                       one.cells["rho_bar2"])
    return out


def material_fractions(design, areas, rho1, rho2) -> dict:
    """A two-material design's volume fractions over its ``design`` elements (a mask, with
    their ``areas``): of the total solid, of material 1 (soft, ``Σ a ρ̄1 (1-ρ̄2)``) and of
    material 2 (stiff, ``Σ a ρ̄1 ρ̄2``)."""
    w = np.where(design, areas, 0.0)
    r1, r2 = np.asarray(rho1), np.asarray(rho2)
    return {"solid": float(w @ r1 / w.sum()),
            "material1_soft": float(w @ (r1 * (1 - r2)) / w.sum()),
            "material2_stiff": float(w @ (r1 * r2) / w.sum())}


def _finite(name, arr):
    if not np.all(np.isfinite(arr)):
        raise RuntimeError(f"{name} has non-finite values: nothing written")


def write_history(target: Path, history: list, problem: Problem) -> None:
    """history.csv (atomically): a row per iteration; written even when no iteration finished
    (a Newton failure in the first one): a header only."""
    keys = list(HISTORY_COLUMNS) + list(problem.reports)
    # every row's columns, in order of appearance: a run resumed from a checkpoint written
    # before a column was added has rows without it (left empty there)
    for row in history:
        keys += [key for key in row if key not in keys]
    buf = io.StringIO(newline="")
    w = csv.DictWriter(buf, fieldnames=keys, restval="")
    w.writeheader()
    w.writerows(history)
    atomic_write_text(target, buf.getvalue())


def write_outputs(path: Path, problem: Problem, x: np.ndarray, history: list, result,
                  wall: float) -> dict:
    """Write the run's results into ``path``; returns the summary (summary.json)."""
    one = one_mesh(problem)
    summ = summary_dict(problem, history, result, wall, one)
    for key in ("objective", "volume_fraction"):
        if summ[key] is not None and not np.isfinite(summ[key]):
            raise RuntimeError(f"{key} is not finite: nothing written")
    write_history(path / "history.csv", history, problem)
    write_vtu(path / "design", problem, x)
    write_pictures(path, drawn(problem, one, summ), history, problem.objective)
    atomic_write_text(path / "summary.json", json.dumps(summ, indent=1))  # last: the run is done
    return summ


def cell_names(problem: Problem) -> tuple[str, ...]:
    """The element fields a run's files and figures read (:class:`OneMesh`): the densities
    of :data:`DENSITIES` the problem has and the pressure's density."""
    block = problem.pressure_block
    names = DENSITIES + ((block.inputs[0],) if block is not None else ())
    return tuple(n for n in dict.fromkeys(names) if n in problem.values)


def one_mesh(problem: Problem) -> OneMesh:
    """The element fields of a serial run's ``problem`` on its mesh (:class:`OneMesh`)."""
    block = problem.pressure_block
    return OneMesh(problem.mesh, {n: np.asarray(problem.values[n]) for n in cell_names(problem)},
                   problem.field.design, problem.field.areas,
                   None if block is None else block.pressure.vec.FV().NumPy()[:problem.mesh.nv])


def drawn(problem: Problem, one: OneMesh, summary: dict) -> Drawn:
    """What the pictures of the run of ``problem`` draw, of its fields on ``one`` mesh and
    its ``summary`` (the volume fraction and the leak)."""
    block = problem.pressure_block
    out = Drawn(one.mesh, problem.case.name, problem.params.model, summary["volume_fraction"],
                shown_density(one.cells), leak=summary.get("leak"), areas=one.areas,
                materials=((one.cells["rho_bar1"], one.cells["rho_bar2"])
                           if problem.n_design_fields == 2 else None))
    if block is None:
        return out
    p_in = block.p_in  # the load factor scales the body force, not p
    return dataclasses.replace(out, solid=one.cells[block.inputs[0]], p_in=p_in,
                               p_rel=one.p / (p_in if p_in != 0 else 1.0))


def write_pictures(path: Path, what: Drawn, history: list, objective: str) -> None:
    """design.png, convergence.png (``objective`` and the volume of ``history``), and
    pressure.png and materials.png where they apply (each written atomically), of ``what``
    (:class:`Drawn`), serial or gathered from a distributed run alike."""
    # the post package loads matplotlib and pyvista at its import (0.5 s): only here
    from .post.plots import convergence_png, density_png, materials_png, pressure_png

    density_png(path / "design.png", what)
    if what.p_rel is not None:
        pressure_png(path / "pressure.png", what)
    if what.materials is not None and what.mesh.dim == 2:
        materials_png(path / "materials.png", what)
    if history:
        convergence_png(path / "convergence.png", history, objective)


def measure_fields(problem: Problem) -> dict[str, np.ndarray]:
    """The model's strain and stress measures (:func:`~pacto_ng.measures.strain_stress_measures`)
    as element means, one array per component (``stress_xy``, ...), over this rank's
    elements."""
    from ngsolve import GridFunction

    out, gf = {}, GridFunction(problem.mech.l2)
    for name, cf in strain_stress_measures(problem).items():
        for (i, j), comp in tensor_components(problem.mesh.dim):
            gf.Set(cf[i, j])  # element mean (P0 projection)
            out[f"{name}_{comp}"] = gf.vec.FV().NumPy().copy()
    return out


def write_vtu(stem: Path, problem: Problem, x: np.ndarray | None):
    """``stem``.vtu (atomically): x, ρ̄, u (and p) and the strain and stress measures."""
    from ngsolve import GridFunction, VTKOutput

    mech = problem.mech
    coefs, names = [], []

    def add_l2(name, arr):
        _finite(name, arr)
        gf = GridFunction(mech.l2)
        gf.vec.FV().NumPy()[:] = arr
        coefs.append(gf)
        names.append(name)

    vals = problem.values
    for key in DENSITIES:
        if key in vals:
            add_l2(key, np.asarray(vals[key]))
    if x is not None and problem.n_design_fields == 1:
        add_l2("x", problem.field.full(x))
    _finite("u", mech.u.vec.FV().NumPy())
    coefs.append(mech.u)
    names.append("u")
    if "p" in vals and problem.pressure_block is not None:
        pg = problem.pressure_block.pressure
        _finite("p", pg.vec.FV().NumPy())
        coefs.append(pg)
        names.append("p")
    for name, arr in measure_fields(problem).items():
        add_l2(name, arr)
    target = Path(stem).with_name(Path(stem).name + ".vtu")
    with atomic_path(target) as tmp:
        VTKOutput(problem.mesh, coefs=coefs, names=names, filename=str(tmp.with_suffix("")),
                  subdivision=0 if problem.params.order == 1 else 1, legacy=False).Do()
        check_tail(tmp, b"</VTKFile>", target)  # VTKOutput does not report a failed write


# ------------------------------------------------------------------------------------------

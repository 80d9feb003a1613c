"""A run and its output folder (the contract users and scripts rely on).

DIR/params.json        case name and every parameter (written first; ``pacto resume`` reads it)
DIR/checkpoint.npz     design, optimiser state, history, warm-start displacement (every iteration)
DIR/summary.json       case, model, parameters, iterations, objective and its history, volume
                       fraction, output displacement, load reached, converged flag, Newton counts,
                       wall time, mesh size and element order
DIR/history.csv        one row per iteration
DIR/design.vtu         x, rho_bar, u (and p) on the mesh
DIR/design.png         the physical density
DIR/pressure.png       pressure cases: p / P_in with the ρ̄ = 0.5 contour (leakage in summary.json)
DIR/materials.png      two-material cases: where the soft and the stiff material are
DIR/convergence.png    objective and volume against iteration
"""
from __future__ import annotations


import csv
import json
import os
import time
from pathlib import Path

import numpy as np

from .case import Case, Problem, build_problem, case_of_run
from .optimize.driver import LoopState, optimize
from .params import InputError, Parameters
from .physics.mechanics import NewtonFailure


#: the columns of history.csv (one row per iteration), then the case's reported responses
HISTORY_COLUMNS = ("iteration", "objective", "volume", "constraint", "change", "penal", "beta",
                   "load", "newton", "load_steps", "time")


def prepare_output(out: str | os.PathLike) -> Path:
    """Create the output folder or fail with a one-line InputError."""
    path = Path(out)
    try:
        path.mkdir(parents=True, exist_ok=True)
        probe = path / ".write-test"
        probe.write_text("")
        probe.unlink()
    except OSError as err:
        raise InputError(f"--out: output folder '{path}' is not writable ({err.strerror})") from None
    return path


def initial_design(problem: Problem) -> np.ndarray:
    p = problem.params
    if p.init_design:
        return design_of_run(p.init_design, problem)
    x0 = p.seed_density if p.seed_density > 0 else p.volfrac
    x = np.full(problem.field.n, x0)
    if problem.n_design_fields == 2:
        x = np.concatenate([x, np.full(problem.field.n, 0.5)])
    return x


def design_of_run(folder: str | os.PathLike, problem: Problem) -> np.ndarray:
    """The design variables x of a run folder's checkpoint, for a run on the same mesh."""
    ckpt = Path(folder) / "checkpoint.npz"
    if not ckpt.is_file():
        raise InputError(f"init_design: no checkpoint.npz in '{folder}'")
    try:
        with np.load(ckpt, allow_pickle=False) as data:
            x = np.asarray(data["x"], dtype=float)
    except (OSError, ValueError, KeyError) as err:
        raise InputError(f"init_design: cannot read '{ckpt}' ({err})") from None
    n = problem.field.n * problem.n_design_fields
    if x.shape != (n,):
        raise InputError(f"init_design: '{ckpt}' holds {x.size} design variables, this run has {n} "
                         "(another case or mesh)")
    if not np.all(np.isfinite(x)):
        raise InputError(f"init_design: '{ckpt}' holds non-finite design variables")
    return np.clip(x, 0.0, 1.0)


def _progress(row: dict, total: int) -> str:
    extra = "".join(f"  {k} {row[k]: .4e}" for k in ("delta",) if k in row)
    return (f"it {row['iteration']:4d}/{total}  obj {row['objective']: .5e}  vol {row['volume']:.4f}"
            f"  change {row['change']:.4f}  newton {row['newton']:3d}  load {row['load']:.3f}"
            f"  p {row['penal']:.2f}  beta {row['beta']:g}{extra}  {row['time']:.2f} s")


# ------------------------------------------------------------------------------------------
def save_checkpoint(path: Path, state: LoopState, problem: Problem) -> None:
    arrays = dict(k=state.k, x=state.x, scale=np.nan if state.scale is None else state.scale,
                  stable=state.stable, history=json.dumps(state.history),
                  u=problem.mech.gfu.vec.FV().NumPy().copy(),
                  warm=bool(problem.mech.result is not None and problem.mech.result.converged),
                  load_cap=state.load_cap)
    if state.last_good is not None:
        arrays["last_good"] = state.last_good
    if state.opt_state is not None:
        for key, val in state.opt_state.items():
            arrays["opt_" + key] = np.asarray(val)
    tmp = path.with_name(path.name + ".tmp.npz")
    np.savez(tmp, **arrays)
    os.replace(tmp, path)


def load_checkpoint(path: Path, problem: Problem) -> LoopState:
    from .physics.newton import NewtonResult

    with np.load(path, allow_pickle=False) as data:
        opt = {key[4:]: (data[key] if data[key].ndim else float(data[key]))
               for key in data.files if key.startswith("opt_")}
        scale = float(data["scale"])
        state = LoopState(k=int(data["k"]), x=data["x"].copy(), opt_state=opt or None,
                          scale=None if np.isnan(scale) else scale,
                          history=json.loads(str(data["history"])), stable=int(data["stable"]),
                          last_good=data["last_good"].copy() if "last_good" in data.files else None,
                          load_cap=float(data["load_cap"]) if "load_cap" in data.files else 1.0)
        u = data["u"]
        if u.size == problem.mech.gfu.vec.size and bool(data["warm"]):
            problem.mech.gfu.vec.FV().NumPy()[:] = u
            problem.mech.result = NewtonResult(True, load_reached=1.0)
    return state


# ------------------------------------------------------------------------------------------
def run_case(case: Case, params: Parameters, out: str | os.PathLike, *, quiet: bool = False,
             resume: bool = False) -> int:
    """Optimise ``case`` with ``params``, writing the output folder.  Returns the exit code:
    0 finished (converged or iteration limit), 1 stopped by a Newton failure.  Runs inside
    NGSolve's task manager (:func:`pacto_ng.threads.compute`)."""
    from .threads import compute

    with compute():
        return _run_case(case, params, out, quiet=quiet, resume=resume)


def _run_case(case: Case, params: Parameters, out: str | os.PathLike, *, quiet: bool = False,
              resume: bool = False) -> int:
    path = prepare_output(out)
    t_start = time.perf_counter()
    if resume and (path / "summary.json").exists():  # a finished run continued: add its time
        try:
            t_start -= float(json.loads((path / "summary.json").read_text())["wall_time_s"])
        except (ValueError, KeyError, TypeError):
            pass
    model_choice = None
    if params.model == "auto":
        from .auto import choose_model

        params, model_choice = choose_model(case, params)
        if not quiet:
            print(f"model auto -> {model_choice['chosen']}: {model_choice['reason']}")
    params = case.resolve(params)  # order 0: the case's order for the (chosen) model
    (path / "params.json").write_text(json.dumps({"case": case.name, "case_file": case.file,
                                                  "params": params.to_dict(),
                                                  "model_choice": model_choice}, indent=1))
    problem = build_problem(case, params)
    problem.model_choice = model_choice
    ckpt = path / "checkpoint.npz"
    if resume:
        if not ckpt.exists():
            raise InputError(f"resume: no checkpoint in '{path}'")
        state = load_checkpoint(ckpt, problem)
        if not quiet:
            print(f"resuming {case.name} at iteration {state.k}")
    else:
        ref = problem.setup.objective_ref
        state = LoopState(k=0, x=initial_design(problem), opt_state=None,
                          scale=10.0 / ref if ref > 0 else None)
    if not quiet:
        print(f"{case.name}: model {params.model}, {problem.mesh.ne} elements, order {params.order}, "
              f"{problem.mech.fes.ndof} displacement dofs, {problem.field.n} design variables")

    def on_iteration(st, row):
        save_checkpoint(ckpt, st, problem)
        if not quiet:
            print(_progress(row, params.iterations), flush=True)

    result = optimize(problem, params.schedule.schedule(), iterations=params.iterations, tol=params.tol,
                      method=params.optimizer, move=params.move, state=state,
                      on_iteration=on_iteration, obj_tol=params.obj_tol,
                      load_adapt=params.load_adapt)
    failed = result.stopped == "newton"
    final_x = state.last_good if failed else state.x
    if final_x is None:
        final_x = state.x
    # final analysis of the design that is reported (the schedule's last values)
    k_last = max(state.k - 1, 0)
    problem.apply_schedule(*params.schedule.schedule().values(k_last))
    u_last, res_last = problem.mech.gfu.vec.CreateVector(), problem.mech.result
    u_last.data = problem.mech.gfu.vec  # the last iteration's equilibrium (a warm start)
    try:
        problem.evaluate(final_x, gradients=False)
    except NewtonFailure as err:
        failed = True
        result.message += f"; the final analysis at the full load failed ({err})"
        last = state.history[-1]["load"] if state.history else 1.0
        if params.load_adapt and last < 1.0:  # report the design at the load it carried
            problem.mech.gfu.vec.data = u_last
            problem.mech.result = res_last
            problem.mech.target = last
            final_x = state.last_good if state.last_good is not None else final_x
            try:
                problem.evaluate(final_x, gradients=False)
                result.message += (f"; the last analysed design is reported at load factor "
                                   f"{last:.4g}")
            except NewtonFailure:
                pass
    wall = time.perf_counter() - t_start
    write_outputs(path, problem, final_x, state.history, result, wall)
    if not quiet or failed:
        print(("run stopped: " if failed else "") + result.message + f" — output in {path}")
    return 1 if failed else 0


def summary_dict(problem: Problem, history: list, result, wall: float) -> dict:
    p = problem.params
    vals = problem.values
    mech_res = problem.mech.result

    def val(name):
        return float(vals[name]) if name in vals else None

    newton_counts = [h["newton"] for h in history]
    out = {
        "case": problem.case.name,
        "model": p.model,
        "parameters": p.to_dict(),
        "load": p.load,
        "load_unit": problem.case.load_unit,
        "iterations": len(history),
        "objective": val(problem.objective),
        "objective_name": problem.objective,
        "objective_history": [h["objective"] for h in history],
        "volume_fraction": problem.volume_fraction(),
        "output_displacement": val("delta"),
        "compliance": val("compliance"),
        "strain_energy": val("se"),
        "load_reached": (mech_res.load_reached * p.load) if mech_res else None,
        "load_factor_reached": mech_res.load_reached if mech_res else None,
        "converged": result.converged,
        "stopped": result.stopped,
        "message": result.message,
        "newton_iterations": newton_counts,
        "newton_iterations_total": int(sum(newton_counts)),
        "wall_time_s": wall,
        "mesh": {"elements": problem.mesh.ne, "h": problem.h, "order": p.order,
                 "displacement_dofs": problem.mech.fes.ndof,
                 "structured": p.nelx > 0, "nelx": p.nelx, "nely": p.nely},
        "element_order": p.order,
        "model_choice": getattr(problem, "model_choice", None),
        "darcy_solve": problem.pressure_block is not None,
        "symmetric_half_domain": any(n == "symmetry" for n in problem.mesh.GetBoundaries()),
        # the mechanics adjoints of this process: solved, and skipped because the adjoint was
        # the primal (compliance of design-independent loads on a linear model)
        "adjoint_solves": {"solved": problem.mech.adjoint_solves,
                           "skipped_self_adjoint": problem.mech.adjoint_solves_skipped},
    }
    out.update(pressure_and_material_summary(problem))
    return out


def pressure_and_material_summary(problem: Problem) -> dict:
    """Pressure cases: ``leakage`` (fraction of P_in, see :func:`pacto_ng.physics.darcy.leakage`)
    and its details.  Two materials: the volume fractions of the total solid, of material 1
    (soft, ``Σ a ρ̄1 (1-ρ̄2)``) and of material 2 (stiff, ``Σ a ρ̄1 ρ̄2``) over the design
    elements."""
    out = {}
    vals = problem.values
    if problem.pressure_block is not None:
        from .physics.darcy import leakage

        blk = problem.pressure_block
        info = leakage(blk, vals[blk.inputs[0]], problem.h)
        out["leakage"] = info.pop("leakage")
        out["leakage_detail"] = info
    if problem.n_design_fields == 2:
        w = np.where(problem.field.design, problem.field.areas, 0.0)
        r1, r2 = np.asarray(vals["rho_bar1"]), np.asarray(vals["rho_bar2"])
        out["material_fractions"] = {"solid": float(w @ r1 / w.sum()),
                                     "material1_soft": float(w @ (r1 * (1 - r2)) / w.sum()),
                                     "material2_stiff": float(w @ (r1 * r2) / w.sum())}
    return out


def _finite(name, arr):
    if not np.all(np.isfinite(arr)):
        raise RuntimeError(f"{name} has non-finite values: nothing written")


def write_outputs(path: Path, problem: Problem, x: np.ndarray, history: list, result, wall: float):
    from .post.plots import convergence_png, density_png, materials_png, pressure_png

    summ = summary_dict(problem, history, result, wall)
    for key in ("objective", "volume_fraction"):
        if summ[key] is not None and not np.isfinite(summ[key]):
            raise RuntimeError(f"{key} is not finite: nothing written")
    (path / "summary.json").write_text(json.dumps(summ, indent=1))
    # written even when no iteration finished (a Newton failure in the first one): a header only
    keys = list(history[0].keys()) if history else list(HISTORY_COLUMNS) + list(problem.reports)
    with open(path / "history.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=keys)
        w.writeheader()
        w.writerows(history)
    write_vtu(path / "design", problem, x)
    density_png(path / "design.png", problem)
    if problem.pressure_block is not None:
        pressure_png(path / "pressure.png", problem, leakage=summ.get("leakage"),
                     leakage_any=summ["leakage_detail"]["leakage_any"])
    if problem.n_design_fields == 2:
        materials_png(path / "materials.png", problem)
    if history:
        convergence_png(path / "convergence.png", history, problem.objective)


def rho_bar_of(problem: Problem) -> np.ndarray:
    vals = problem.values
    if "rho_bar" in vals:
        return np.asarray(vals["rho_bar"])
    return np.asarray(vals["rho_bar1"]) * (1 + np.asarray(vals["rho_bar2"])) / 2.0


def write_vtu(stem: Path, problem: Problem, x: np.ndarray | None):
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
    for key in ("rho_bar", "rho_bar1", "rho_bar2"):
        if key in vals:
            add_l2(key, np.asarray(vals[key]))
    if x is not None and problem.n_design_fields == 1:
        add_l2("x", problem.field.full(x))
    _finite("u", mech.gfu.vec.FV().NumPy())
    coefs.append(mech.gfu)
    names.append("u")
    if "p" in vals and problem.pressure_block is not None:
        pg = problem.pressure_block.gfp
        _finite("p", pg.vec.FV().NumPy())
        coefs.append(pg)
        names.append("p")
    for name, cf in strain_stress_measures(problem).items():
        for (i, j), comp in zip(((0, 0), (1, 1), (0, 1)), ("xx", "yy", "xy")):
            gf = GridFunction(mech.l2)
            gf.Set(cf[i, j])  # element mean (P0 projection)
            add_l2(f"{name}_{comp}", gf.vec.FV().NumPy().copy())
    VTKOutput(problem.mesh, coefs=coefs, names=names, filename=str(stem),
              subdivision=0 if problem.params.order == 1 else 1, legacy=False).Do()


def strain_stress_measures(problem: Problem) -> dict:
    """In-plane 2x2 strain and stress CFs of the analysed state, by model: ``linear``: ε and
    σ; ``gnl``/``neohookean``: Green–Lagrange ``E_GL`` and the second Piola–Kirchhoff ``S``
    (``F⁻¹ ∂φ/∂F`` by automatic differentiation); ``wang``: ``E_W1``, ``E_W2`` (thesis eqs
    5.4–5.5) and ``S`` (eq. 5.3).  design.vtu holds their xx, yy, xy element means."""
    from ngsolve import Grad

    from .physics.materials import first_piola_kirchhoff, green_lagrange, second_piola_kirchhoff

    mech = problem.mech
    G, c = Grad(mech.gfu), mech.coeffs
    model = problem.params.model
    if model == "wang":
        wm = mech.energy  # the WangModel (make_energy passes the model as the energy)
        return {"E_W1": wm.strain_w1(G, c), "E_W2": wm.strain_w2(G, c), "S": wm.stress(G, c)}
    phi = lambda A: mech.energy(A, c)  # noqa: E731
    if model == "linear":
        return {"strain": 0.5 * (G + G.trans), "stress": first_piola_kirchhoff(phi, G)}
    return {"E_GL": green_lagrange(G), "S": second_piola_kirchhoff(phi, G)}


# ------------------------------------------------------------------------------------------
def read_density(path: str, problem: Problem, *, filtered: bool = False) -> tuple[np.ndarray, bool]:
    """The design a file holds, and whether it is design variables (to be filtered and
    projected) rather than physical densities ρ̄.

    Formats (element order: NGSolve's, i.e. ``mesh.Elements()`` and the order of the cells of
    design.vtu):

    * ``.npy``, ``.csv``, ``.txt``: one value per element of the mesh, or for structured quads a
      nely x nelx grid whose row 0 is the top row of elements; ρ̄, or design variables with
      ``--filtered`` (passive elements' values are ignored then);
    * ``checkpoint.npz`` of a run: its design variables ``x`` (one per *design* element, two
      fields stacked for two materials), always filtered and projected, as the run did (with
      the penalty and β of the run's last iteration: :func:`checkpoint_iteration`);
    * ``design.vtu`` of a run: its element field ``rho_bar`` (``x`` with ``--filtered``).
    """
    p = problem.params
    fp = Path(path)
    if not fp.is_file():
        raise InputError(f"--density: file '{path}' does not exist")
    suffix = fp.suffix.lower()
    if suffix == ".npz":
        return _checkpoint_design(fp, problem), True
    try:
        if suffix == ".npy":
            arr = np.load(fp, allow_pickle=False)
        elif suffix in (".csv", ".txt"):
            arr = np.loadtxt(fp, delimiter="," if suffix == ".csv" else None, ndmin=1)
        elif suffix == ".vtu":
            arr = _vtu_element_field(fp, "x" if filtered else "rho_bar", problem.mesh.ne)
        else:
            raise InputError(f"--density: '{path}' must be a .npy, .csv, .txt, .vtu or a "
                             "checkpoint .npz file")
    except InputError:
        raise
    except (OSError, ValueError, KeyError, EOFError) as err:  # unreadable file content
        raise InputError(f"--density: cannot read '{path}' ({type(err).__name__}: {err})") from None
    arr = np.asarray(arr, dtype=float)
    ne = problem.mesh.ne
    if arr.ndim == 2 and p.nelx > 0:
        if arr.shape != (p.nely, p.nelx):
            raise InputError(f"--density: '{path}' is a {arr.shape[0]} x {arr.shape[1]} grid, "
                             f"the mesh is nely x nelx = {p.nely} x {p.nelx}")
        arr = arr[::-1].ravel()
    else:
        arr = arr.ravel()
    if arr.size != ne:
        raise InputError(f"--density: '{path}' holds {arr.size} values, the mesh has {ne} elements")
    if not np.all(np.isfinite(arr)) or arr.min() < 0 or arr.max() > 1:
        raise InputError(f"--density: values in '{path}' must be finite and lie in [0, 1]")
    if filtered:
        arr = arr[problem.field.design_index]
    return arr, filtered


def _checkpoint_design(fp: Path, problem: Problem) -> np.ndarray:
    try:
        with np.load(fp, allow_pickle=False) as data:
            x = np.asarray(data["x"], dtype=float).ravel()
    except (OSError, ValueError, KeyError, EOFError) as err:
        raise InputError(f"--density: '{fp}' is not a readable checkpoint ({type(err).__name__}: "
                         f"{err})") from None
    n = problem.field.n * problem.n_design_fields
    if x.size != n:
        raise InputError(f"--density: checkpoint '{fp}' holds {x.size} design variables, this "
                         f"case and mesh have {n} (another case or mesh)")
    if not np.all(np.isfinite(x)) or x.min() < 0 or x.max() > 1:
        raise InputError(f"--density: design variables in '{fp}' must be finite, in [0, 1]")
    return x


def checkpoint_iteration(fp: str | os.PathLike) -> int:
    """The iteration count ``k`` a checkpoint was written at (its schedule is that of k - 1)."""
    with np.load(fp, allow_pickle=False) as data:
        return int(data["k"])


def _vtu_element_field(fp: Path, name: str, ne: int) -> np.ndarray:
    """An element-constant field of a design.vtu: one value per element (NGSolve writes each
    element's corners as points of their own, and order >= 2 runs as 4 sub-cells each)."""
    import meshio

    m = meshio.read(fp)
    if name not in m.point_data:
        raise InputError(f"--density: '{fp}' has no field '{name}' (fields: "
                         f"{', '.join(m.point_data) or 'none'})")
    cells = np.concatenate([c.data for c in m.cells])
    vals = np.asarray(m.point_data[name], dtype=float).reshape(len(m.points), -1)[:, 0]
    per_cell = vals[cells[:, 0]]
    if per_cell.size % ne:
        raise InputError(f"--density: '{fp}' has {per_cell.size} cells, the mesh has {ne} "
                         "elements (another mesh)")
    return per_cell.reshape(ne, -1).mean(axis=1)


def evaluate_design(case: Case, params: Parameters, density: str, out, *, filtered: bool,
                    quiet: bool = False) -> int:
    """One analysis of a given design (no optimisation); writes summary.json and design.vtu."""
    path = prepare_output(out)
    t0 = time.perf_counter()
    problem = build_problem(case, params)
    arr, filtered = read_density(density, problem, filtered=filtered)
    if problem.n_design_fields != 1 and not Path(density).suffix.lower() == ".npz":
        raise InputError("evaluate: two-material cases need both fields: give the run's "
                         "checkpoint.npz")
    sched = params.schedule.schedule()
    if Path(density).suffix.lower() == ".npz":  # the run's own last penalty and β
        penal, beta, _ = sched.values(max(checkpoint_iteration(density) - 1, 0))
        problem.apply_schedule(penal, beta, 1.0)
    else:
        problem.apply_schedule(params.penal, sched.beta(10 ** 6), 1.0)
    x = None
    try:
        if filtered:
            x = arr
            problem.chain.forward(x=x)
        else:
            rho = arr.copy()
            rho[problem.field.solid] = 1.0
            rho[problem.field.void] = 0.0
            problem.chain.forward(rho_bar=rho)
    except NewtonFailure as err:
        print(f"evaluate: {err}")
        return 1

    class _R:
        converged, stopped, message = True, "evaluated", "single analysis"

    summ = summary_dict(problem, [], _R, time.perf_counter() - t0)
    summ["evaluated_from"] = str(density)
    summ["filtered"] = filtered
    (path / "summary.json").write_text(json.dumps(summ, indent=1))
    write_vtu(path / "design", problem, x)
    if not quiet:
        keys = ("objective", "compliance", "output_displacement", "strain_energy", "volume_fraction")
        print("  ".join(f"{k} {summ[k]:.6g}" for k in keys if summ[k] is not None))
    return 0


def resume_run(out: str | os.PathLike, *, quiet: bool = False, iterations: int | None = None) -> int:
    """Continue the run in ``out`` from its checkpoint; ``iterations`` raises its cap."""
    path = Path(out)
    try:
        info = json.loads((path / "params.json").read_text())
    except (OSError, ValueError):
        raise InputError(f"resume: '{path}' holds no run (params.json missing or unreadable)") from None
    case = case_of_run(info, "resume")
    params = case.parameters(info["params"])
    if iterations is not None:
        if iterations < params.iterations:
            raise InputError(f"iterations: {iterations} is below the run's cap {params.iterations}")
        params = params.replace(iterations=iterations)
    return run_case(case, params, path, quiet=quiet, resume=True)

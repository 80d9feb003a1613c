"""A run and its output folder (the contract users and scripts rely on).

DIR/params.json        case name, case file and every parameter (written first; ``pacto resume``
                       reads it)
DIR/checkpoint.npz     design, optimiser state, history, warm-start displacement (every iteration)

and the results of :mod:`pacto_ng.outputs` (summary.json, history.csv, design.vtu, pictures).
"""
from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .case import Case, Problem, build_problem, case_of_run
from .optimize.driver import LoopState, optimize
from .params import InputError, Parameters
from .physics.equilibrium import NewtonFailure
from .outputs import write_outputs


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
                  u=problem.mech.state, warm=problem.mech.state_converged,
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
            problem.mech.set_state(u, converged=True)
    return state


# ------------------------------------------------------------------------------------------
@dataclass
class Finished:
    """A finished run: its exit code, the problem with the reported design analysed, that
    design, the history and the summary (as written to the run's folder)."""

    exit_code: int
    problem: Problem
    x: np.ndarray
    history: list
    summary: dict


def run_case(case: Case, params: Parameters, out: str | os.PathLike, *, quiet: bool = False,
             resume: bool = False) -> int:
    """Optimise ``case`` with ``params``, writing the output folder.  Returns the exit code:
    0 finished (converged or iteration limit), 1 stopped by a Newton failure."""
    return optimise_case(case, params, out, quiet=quiet, resume=resume).exit_code


def optimise_case(case: Case, params: Parameters, out: str | os.PathLike, *,
                  quiet: bool = False, resume: bool = False) -> Finished:
    """:func:`run_case`, returning the :class:`Finished` run.  Runs inside NGSolve's task
    manager (:func:`pacto_ng.threads.compute`)."""
    from .threads import compute

    with compute():
        return _run_case(case, params, out, quiet=quiet, resume=resume)


def _run_case(case: Case, params: Parameters, out: str | os.PathLike, *, quiet: bool = False,
              resume: bool = False) -> Finished:
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
    # the last iteration's equilibrium (a warm start)
    u_last, res_last = problem.mech.state, problem.mech.result
    try:
        problem.evaluate(final_x, gradients=False)
    except NewtonFailure as err:
        failed = True
        result.message += f"; the final analysis at the full load failed ({err})"
        last = state.history[-1]["load"] if state.history else 1.0
        if params.load_adapt and last < 1.0:  # report the design at the load it carried
            problem.mech.set_state(u_last, converged=res_last is not None and res_last.converged,
                                   result=res_last)
            problem.mech.target = last
            final_x = state.last_good if state.last_good is not None else final_x
            try:
                problem.evaluate(final_x, gradients=False)
                result.message += (f"; the last analysed design is reported at load factor "
                                   f"{last:.4g}")
            except NewtonFailure:
                pass
    wall = time.perf_counter() - t_start
    summary = write_outputs(path, problem, final_x, state.history, result, wall)
    if not quiet or failed:
        print(("run stopped: " if failed else "") + result.message + f" — output in {path}")
    return Finished(1 if failed else 0, problem, final_x, state.history, summary)


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

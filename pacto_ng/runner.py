"""A run and its output folder (the contract users and scripts rely on).

DIR/params.json        case name, case file and every parameter (written once the problem is
                       built, before the first iteration; ``pacto resume`` reads it)
DIR/checkpoint.npz     design, optimiser state, history, warm-start displacement (every iteration)
DIR/.pacto.lock        held while a process writes DIR (a second one is refused)

and the results of :mod:`pacto_ng.outputs` (summary.json, history.csv, design.vtu, pictures;
summary.json last: a folder without it holds no finished run).  Every file is written whole or
not at all (:mod:`pacto_ng.files`): a run killed at any moment, even by ``kill -9``, is
continued by ``pacto resume DIR`` and ends with the design of an uninterrupted run.  A folder
that already holds a run is refused unless resumed or ``overwrite`` removes its files first.
"""
from __future__ import annotations

import json
import os
import sys
import time
import zipfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .auto import choose
from .case import Case, build_problem, read_run_params
from .errors import InputError
from .files import WriteError, atomic_path, atomic_write_text, claim_folder, folder_outputs
from .initial import initial_design
from .optimize.driver import LoopResult, LoopState, best_iterate, optimize
from .parallel import leads, world
from .parallel_outputs import write_distributed_outputs
from .params import Parameters
from .physics.energy import WHEN_NEWTON_FAILS
from .physics.equilibrium import NewtonFailure, WarmState
from .outputs import write_outputs
from .problem import Problem
from .threads import compute


def missing_folders(out: str | os.PathLike) -> list[Path]:
    """``out`` and those of its parent folders that do not exist yet, deepest first: what
    :func:`prepare_output` will create, and :func:`remove_created` removes again."""
    missing, path = [], Path(out).absolute()
    while not path.exists() and path != path.parent:
        missing.append(path)
        path = path.parent
    return missing


def remove_created(folders: list[Path]) -> None:
    """Remove the folders of :func:`missing_folders` that are empty, deepest first (a command
    refused before it wrote anything leaves the file system as it found it)."""
    for folder in folders:
        try:
            folder.rmdir()
        except OSError:  # not empty (or gone): it and its parents stay
            return


def prepare_output(out: str | os.PathLike) -> Path:
    """Create the output folder or fail with a one-line InputError."""
    path = Path(out)
    try:
        path.mkdir(parents=True, exist_ok=True)
        probe = path / f".write-test-{os.getpid()}"
        probe.write_text("")
        probe.unlink()
    except OSError as err:
        raise InputError(f"--out: output folder '{path}' is not writable ({err.strerror})") from None
    return path


def _progress(row: dict, total: int) -> str:
    extra = "".join(f"  {k} {row[k]: .4e}" for k in ("delta",) if k in row)
    if row.get("design_cuts"):
        extra += f"  (design step halved {row['design_cuts']}x: Newton failed on the full one)"
    return (f"it {row['iteration']:4d}/{total}  obj {row['objective']: .5e}  vol {row['volume']:.4f}"
            f"  change {row['change']:.4f}  newton {row['newton']:3d}  load {row['load']:.3f}"
            f"  p {row['penal']:.2f}  beta {row['beta']:g}{extra}  {row['time']:.2f} s")


# ------------------------------------------------------------------------------------------
def save_checkpoint(path: Path, state: LoopState, problem: Problem) -> None:
    """Everything :func:`load_checkpoint` needs to continue exactly (written atomically)."""
    # on a distributed mesh the displacement is rank 0's part (none): no warm start, so that a
    # resume may use another number of ranks
    local = problem.numbering is not None
    arrays = dict(k=state.k, x=state.x, scale=np.nan if state.scale is None else state.scale,
                  stable=state.stable, history=json.dumps(state.history),
                  load_cap=state.load_cap, load_failed_at=state.load_failed_at,
                  beta_cap=state.beta_cap, beta_capped_at=state.beta_capped_at,
                  beta_step=state.beta_step)
    # every mechanics block's warm state: u, warm, ramp_first, then u_1, ... for the robust
    # realisations.  Newton's first increment of its last ramp is part of it: a Neo-Hookean
    # pa-inverter resumed without it ended 5e-4 away from the uninterrupted run
    for i, mech in enumerate(problem.mechanics):
        warm, suffix = mech.state, "" if i == 0 else f"_{i}"
        arrays.update({f"u{suffix}": np.zeros(0) if local else warm.u,
                       f"warm{suffix}": warm.converged and not local,
                       f"ramp_first{suffix}": _nan_if_none(warm.ramp_first)})
    if state.last_good is not None:
        arrays["last_good"] = state.last_good
    if state.opt_state is not None:
        for key, val in state.opt_state.items():
            arrays["opt_" + key] = np.asarray(val)
    with atomic_path(path) as tmp:
        np.savez(tmp, **arrays)


def _nan_if_none(value: float | None) -> float:
    return np.nan if value is None else float(value)


def _checkpoint_k(path: Path) -> int | None:
    """The iterations a checkpoint holds (None without a readable one)."""
    try:
        with np.load(path, allow_pickle=False) as data:
            return int(data["k"])
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile):
        return None


def _restore_warm(data, suffix: str, mech, numbering) -> None:
    """Start ``mech`` from the warm state saved under ``u<suffix>``, ``warm<suffix>`` and
    ``ramp_first<suffix>``; from zero if there is none (a checkpoint written before the robust
    realisations' states were kept, or on a distributed mesh)."""
    ndof = mech.space.ndof
    u = data[f"u{suffix}"] if f"u{suffix}" in data.files else np.zeros(0)
    warm = numbering is None and u.size == ndof and bool(data[f"warm{suffix}"])
    # (a checkpoint written before the ramp's first increment was kept: None)
    key = f"ramp_first{suffix}"
    ramp = float(data[key]) if key in data.files else np.nan
    mech.set_state(WarmState(u if warm else np.zeros(ndof), converged=warm,
                             ramp_first=None if np.isnan(ramp) else ramp))


def load_checkpoint(path: Path, problem: Problem) -> LoopState:
    try:
        with np.load(path, allow_pickle=False) as data:
            opt = {key[4:]: (data[key] if data[key].ndim else float(data[key]))
                   for key in data.files if key.startswith("opt_")}
            scale = float(data["scale"])
            files = data.files
            state = LoopState(k=int(data["k"]), x=data["x"].copy(), opt_state=opt or None,
                              scale=None if np.isnan(scale) else scale,
                              history=json.loads(str(data["history"])),
                              stable=int(data["stable"]),
                              last_good=data["last_good"].copy() if "last_good" in files else None,
                              load_cap=float(data["load_cap"]) if "load_cap" in files else 1.0,
                              load_failed_at=(int(data["load_failed_at"])
                                              if "load_failed_at" in files else -1))
            if "beta_cap" in files:
                state.beta_cap = float(data["beta_cap"])
                state.beta_capped_at = int(data["beta_capped_at"])
                state.beta_step = float(data["beta_step"])
            for i, mech in enumerate(problem.mechanics):
                _restore_warm(data, "" if i == 0 else f"_{i}", mech, problem.numbering)
    except (OSError, ValueError, KeyError, EOFError, zipfile.BadZipFile) as err:
        raise InputError(f"resume: cannot read '{path}' ({type(err).__name__}: {err})") from None
    n = problem.n_design * problem.n_design_fields
    for name, x in (("x", state.x), ("last_good", state.last_good)):
        if x is not None and x.shape != (n,):
            raise InputError(f"resume: '{path}' holds {x.size} design variables ({name}), this "
                             f"run has {n}: a checkpoint of another case or mesh")
    return state


def _stopped_converged(state: LoopState, tol: float, obj_tol: float) -> LoopResult | None:
    """The loop's result when ``state`` is the checkpoint of the iteration at which it stopped
    converged (the run was killed during its final writes): the driver's own test,
    ``stable >= 2`` and a feasible last iteration.  None otherwise (the loop goes on)."""
    if not state.history or state.stable < 2 or state.history[-1]["constraint"] > 1e-3:
        return None
    last = state.history[-1]
    return LoopResult(state, True, "converged",
                      f"converged at iteration {last['iteration']}: change {last['change']:.3g}, "
                      f"objective change over 5 iterations below {obj_tol:g} or design change "
                      f"below {tol:g}")


def _kept(path: Path, saved: int | None, total: int) -> str:
    """What an interrupted or failed run leaves, and how to go on: for one line."""
    if saved is None and not (path / "params.json").exists():
        return "nothing was written yet (the problem was being built): run the command again"
    if saved is None:
        return (f"no iteration was checkpointed; 'pacto resume {path}' starts the run again from "
                "its params.json")
    done = "its final results are not all written" if saved >= total else "continue it"
    return (f"the checkpoint after {saved} of {total} iterations is kept ({done}: "
            f"'pacto resume {path}')")


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
             resume: bool = False, overwrite: bool = False) -> int:
    """Optimise ``case`` with ``params``, writing the output folder.  Returns the exit code:
    0 finished (converged or iteration limit), 1 stopped by a Newton failure.

    A folder that already holds a run (or results) is refused with a one-line InputError
    unless ``resume`` (continue its checkpoint) or ``overwrite`` (remove its files first); so
    is a folder another process is writing."""
    return optimise_case(case, params, out, quiet=quiet, resume=resume,
                         overwrite=overwrite).exit_code


def optimise_case(case: Case, params: Parameters, out: str | os.PathLike, *,
                  quiet: bool = False, resume: bool = False, overwrite: bool = False) -> Finished:
    """:func:`run_case`, returning the :class:`Finished` run.  Runs inside NGSolve's task
    manager (:func:`pacto_ng.threads.compute`)."""
    with compute():
        return _run_case(case, params, out, quiet=quiet, resume=resume, overwrite=overwrite)


class _Progress:
    """Where a run stands, for the line an interrupt or a failed write ends it with."""

    def __init__(self, path: Path, total: int):
        self.path, self.total, self.saved = path, total, None

    def note(self) -> str:
        return _kept(self.path, self.saved, self.total)


def _run_case(case: Case, params: Parameters, out: str | os.PathLike, *, quiet: bool = False,
              resume: bool = False, overwrite: bool = False,
              model_choice: dict | None = None, ramp_choice: dict | None = None) -> Finished:
    if not leads():  # another rank of an MPI run: rank 0 owns the folder
        return _optimise(case, params, Path(out), _Progress(Path(out), params.iterations),
                         quiet=True, resume=resume, model_choice=model_choice,
                         ramp_choice=ramp_choice)
    # a run refused (a bad input, exit code 2) before it wrote anything leaves the file system
    # as it found it: no lock file it made, no folder it made.  (An interrupt keeps the folder
    # and its lock file, as before: its line says what is kept.)
    created = missing_folders(out)
    path = prepare_output(out)
    lock = None
    try:
        if (overwrite and params.init_design
                and Path(params.init_design).resolve() == path.resolve()):
            raise InputError("run --overwrite: init_design is the --out folder, whose "
                             "checkpoint it would remove before reading it: choose another "
                             "--out")
        lock = claim_folder(path, "resume" if resume else "run", overwrite=overwrite,
                            resume=resume)
        progress = _Progress(path, params.iterations)
        if resume:  # what an interrupt before the checkpoint is loaded leaves: the one there
            progress.saved = _checkpoint_k(path / "checkpoint.npz")
        try:
            return _optimise(case, params, path, progress, quiet=quiet, resume=resume,
                             model_choice=model_choice, ramp_choice=ramp_choice)
        except KeyboardInterrupt as err:  # SIGINT, and SIGTERM/SIGHUP through pacto's handlers
            err.pacto_note = progress.note()
            raise
        except WriteError as err:  # a full disk: say what is kept
            err.args = (f"{err.args[0]}; {progress.note()}",)
            raise
    except InputError:
        if lock is not None:
            lock.release(remove=not folder_outputs(path))
        remove_created(created)
        raise
    finally:
        if lock is not None:
            lock.release()


def _optimise(case: Case, params: Parameters, path: Path, progress: _Progress, *, quiet: bool,
              resume: bool, model_choice: dict | None, ramp_choice: dict | None) -> Finished:
    t_start = time.perf_counter() - _time_before(path, resume)
    if params.model == "auto" or params.load_ramp < 0:
        params, model_choice, ramp_choice = _auto_choices(case, params, quiet)
    params = case.resolve(params)  # order 0: the case's order for the (chosen) model
    lead = leads()
    problem = build_problem(case, params, comm=world())
    problem.model_choice = model_choice
    problem.load_ramp_choice = ramp_choice
    # an optimisation: every design assembled one way, from the process's first on (a resumed
    # run would otherwise take the single-analysis way for its first design)
    problem.expect_many_designs()
    ckpt = path / "checkpoint.npz"
    resumed = resume and ckpt.exists()
    if resumed:
        state = load_checkpoint(ckpt, problem)
        progress.saved = state.k
    else:
        state = LoopState.start(initial_design(problem), problem.setup.objective_ref)
    # once the problem is built and the checkpoint read: a run refused while building it, or a
    # resume refused for its checkpoint, leaves the folder as it was
    info = {"case": case.name, "case_file": case.file, "params": params.to_dict(),
            "model_choice": model_choice, "load_ramp_choice": ramp_choice}
    if lead:
        _write_params(path / "params.json", info)
    if not quiet:
        _announce(case, params, problem, state.k if resume else None, resumed)

    def on_iteration(st, row):
        if not lead:
            return
        save_checkpoint(ckpt, st, problem)
        progress.saved = st.k
        if not quiet:
            print(_progress(row, params.iterations), flush=True)

    result = _stopped_converged(state, params.tol, params.obj_tol) if resume else None
    if result is None:
        result = optimize(problem, params.schedule.schedule(), iterations=params.iterations,
                          tol=params.tol, method=params.optimizer, move=params.move, state=state,
                          on_iteration=on_iteration, obj_tol=params.obj_tol,
                          load_adapt=params.load_adapt)
    final_x, failed = _final_analysis(problem, params, state, result)
    if failed and params.model in WHEN_NEWTON_FAILS:
        result.message += "; " + WHEN_NEWTON_FAILS[params.model]
    wall = time.perf_counter() - t_start
    if problem.numbering is None:
        summary = write_outputs(path, problem, final_x, state.history, result, wall)
    else:
        summary = write_distributed_outputs(path, problem, final_x, state.history, result,
                                            wall, write=lead)
    if lead and (not quiet or failed):
        print(("run stopped: " if failed else "") + result.message + f" — output in {path}")
    return Finished(1 if failed else 0, problem, final_x, state.history, summary)


def _time_before(path: Path, resume: bool) -> float:
    """The wall time a finished run that is continued already took (its summary.json's), else
    0: a resumed run's time adds to it."""
    if resume and (path / "summary.json").exists():
        try:
            return float(json.loads((path / "summary.json").read_text())["wall_time_s"])
        except (ValueError, KeyError, TypeError):
            pass
    return 0.0


def _auto_choices(case: Case, params: Parameters, quiet: bool) -> tuple:
    """``(params, model_choice, ramp_choice)`` with the model (``auto``) and the load ramp
    (negative) chosen for the case (:func:`pacto_ng.auto.choose`), said on the terminal."""
    warnings = []
    params, model_choice, ramp_choice = choose(case, params, comm=world(), warnings=warnings)
    if leads():  # sizes and moduli that do not match: said even with --quiet
        for line in warnings:
            print(f"pacto: warning: {line}", file=sys.stderr, flush=True)
    if not quiet and model_choice is not None:
        print(f"model auto -> {model_choice['chosen']}: {model_choice['reason']}")
    if not quiet and ramp_choice is not None and ramp_choice["chosen"] > 0:
        print(f"load ramp -> {ramp_choice['chosen']} iterations: {ramp_choice['reason']}")
    return params, model_choice, ramp_choice


def _announce(case: Case, params: Parameters, problem: Problem, resumed_at: int | None,
              resumed: bool) -> None:
    """The run's first lines: where a resume starts (``resumed_at``: its iteration, None for a
    new run) and the problem's size."""
    if resumed_at is not None:
        print(f"resuming {case.name} at iteration {resumed_at}" if resumed else
              f"resuming {case.name}: no checkpoint yet, starting at iteration 0")
    mixed = " (mixed formulation)" if problem.mech.formulation == "mixed" else ""
    ne = problem.mesh.ne if problem.numbering is None else problem.numbering.ne
    ranks = "" if problem.numbering is None else f" on {problem.numbering.comm.size} ranks"
    print(f"{case.name}: model {params.model}{mixed}, {ne} elements{ranks}, order "
          f"{params.order}, {problem.mech.ndof} displacement dofs, "
          f"{problem.n_design} design variables")


def _final_analysis(problem: Problem, params: Parameters, state: LoopState,
                    result: LoopResult) -> tuple[np.ndarray, bool]:
    """``(final_x, failed)``: the reported design (the last good one after a Newton failure)
    analysed at the schedule's last values; after a failure at the full load, the last
    analysed design at the load it carried.  ``result.message`` and ``result.best`` say what
    was found."""
    failed = result.stopped == "newton"
    final_x = state.last_good if failed else state.x
    if final_x is None:
        final_x = state.x
    # final analysis of the design that is reported (the schedule's last values)
    k_last = max(state.k - 1, 0)
    problem.apply_schedule(*params.schedule.schedule().values(k_last, state.history))
    # the last iteration's equilibrium (a warm start)
    warm_last, res_last = problem.mech.state, problem.mech.result
    try:
        problem.evaluate(final_x, gradients=False)
    except NewtonFailure as err:
        failed = True
        result.message += f"; the final analysis at the full load failed ({err})"
        last = state.history[-1]["load"] if state.history else 1.0
        if params.load_adapt and last < 1.0:  # report the design at the load it carried
            problem.mech.set_state(warm_last, result=res_last)
            problem.mech.target = last
            final_x = state.last_good if state.last_good is not None else final_x
            try:
                problem.evaluate(final_x, gradients=False)
                result.message += (f"; the last analysed design is reported at load factor "
                                   f"{last:.4g}")
            except NewtonFailure:
                pass
    if not failed:
        result.best = best_iterate(state.history, params.schedule.schedule(),
                                   float(problem.values[problem.objective]))
        if result.best is not None:
            result.message += (f"; iteration {result.best['iteration']} had a lower objective "
                               f"({result.best['objective']:.6g}, feasible, at the final "
                               "schedule) than the reported design")
    return final_x, failed


def _write_params(path: Path, info: dict) -> None:
    """params.json, written atomically and only when its content changes (a resume with the
    same parameters leaves the file as it is)."""
    text = json.dumps(info, indent=1)
    try:
        if path.read_text() == text:
            return
    except OSError:
        pass
    atomic_write_text(path, text)


def resume_run(out: str | os.PathLike, *, quiet: bool = False,
               iterations: int | None = None) -> Finished:
    """Continue the run in ``out`` from its checkpoint (a run killed before its first
    checkpoint starts again from its params.json); ``iterations`` raises its cap."""
    path = Path(out)
    info, case, params = read_run_params(path, "resume")
    if iterations is not None:
        if iterations < params.iterations:
            raise InputError(f"iterations: {iterations} is below the run's cap {params.iterations}")
        params = params.replace(iterations=iterations)
    with compute():
        return _run_case(case, params, path, quiet=quiet, resume=True,
                         model_choice=info.get("model_choice"),
                         ramp_choice=info.get("load_ramp_choice"))

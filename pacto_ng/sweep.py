"""A case over a grid of loads and models, one run per point, on Dask (``pacto sweep``).

DIR/<model>-<load>/    one ordinary run folder per grid point (see :mod:`pacto_ng.runner`), named
                       e.g. ``linear-1e5`` or ``neohookean-2.5e5``
DIR/sweep.csv          one row per run: model, load, objective, output displacement, load
                       reached, converged, iterations, wall time, folder (and how it stopped)
DIR/sweep.png          output displacement and objective against load, one line per model

Runs are independent tasks on a ``distributed`` cluster: by default a ``LocalCluster`` of
spawned worker processes with one thread each (NGSolve runs with one thread in every worker),
or an existing cluster given by its scheduler address (its workers must see DIR and have
pacto_ng installed).  A sweep picks up where it stopped: a folder with a finished
``summary.json`` is not run again, a folder with a checkpoint but no summary resumes from the
checkpoint.  Everything but :func:`run_sweep` and :func:`run_one` is a pure function of its
arguments and of the files in DIR, and needs no Dask.
"""
from __future__ import annotations

import csv
import io
import json
import math
import os
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from .errors import InputError
from .files import atomic_path, atomic_write_text
from .params import Parameters

COLUMNS = ("model", "load", "objective", "output_displacement", "load_reached", "converged",
           "iterations", "wall_time_s", "folder", "stopped")
INSTALL_HINT = 'pip install "pacto_ng[cluster]"'


@dataclass(frozen=True)
class SweepRun:
    """One grid point of a sweep.

    Attributes
    ----------
    model : str
        Mechanics model (``linear``, ``gnl``, ``neohookean`` or ``wang``).
    load : float
        Load magnitude in the case's unit.
    folder : str
        Name of the run folder inside the sweep folder (see :func:`folder_name`).
    """

    model: str
    load: float
    folder: str


# -- input ---------------------------------------------------------------------------------
def parse_loads(text: str | None) -> tuple[float, ...]:
    """Loads from a comma-separated list such as ``"1e5,1e6,1e7"``.

    Parameters
    ----------
    text : str or None
        The ``--loads`` argument.

    Returns
    -------
    tuple of float
        The loads in the given order.

    Raises
    ------
    InputError
        If the list is empty, an item is not a number, a load is not positive and finite, or two
        loads share a folder name.
    """
    items = [s.strip() for s in (text or "").split(",")]
    if not any(items):
        raise InputError("--loads: give at least one load, e.g. --loads 1e5,1e6,1e7")
    loads, labels = [], {}
    for item in items:
        try:
            val = float(item)
        except ValueError:
            raise InputError(f"--loads: '{item}' is not a number") from None
        if not (math.isfinite(val) and val > 0):
            raise InputError(f"--loads: loads must be positive and finite (got '{item}')")
        label = load_label(val)
        if label in labels:
            raise InputError(f"--loads: '{item}' repeats '{labels[label]}' (both are {label})")
        labels[label] = item
        loads.append(val)
    return tuple(loads)


def parse_models(text: str | None, default: str) -> tuple[str, ...]:
    """Models from a comma-separated list such as ``"linear,neohookean"``.

    Parameters
    ----------
    text : str or None
        The ``--models`` argument; None means ``default`` alone.
    default : str
        The case's model (after ``--set model=...``).

    Returns
    -------
    tuple of str
        The models in the given order.

    Raises
    ------
    InputError
        If the list is empty, names an unknown model or repeats one.
    """
    from .physics.materials import MODELS

    items = [default] if text is None else [s.strip() for s in text.split(",")]
    if not any(items):
        raise InputError(f"--models: give at least one model ({', '.join(MODELS)})")
    for i, m in enumerate(items):
        if m not in MODELS:
            raise InputError(f"--models: unknown model '{m}' (choose from {', '.join(MODELS)})")
        if m in items[:i]:
            raise InputError(f"--models: '{m}' appears twice")
    return tuple(items)


def load_label(load: float) -> str:
    """Short, stable text of a load for folder names: ``1e5``, ``2.5e5``, ``1e0``, ``5e-1``.

    Six significant digits, mantissa without trailing zeros, exponent without sign padding.
    """
    mant, exp = f"{load:.5e}".split("e")
    mant = mant.rstrip("0").rstrip(".")
    return f"{mant}e{int(exp)}"


def folder_name(model: str, load: float) -> str:
    """Name of the run folder of one grid point, e.g. ``linear-1e5``."""
    return f"{model}-{load_label(load)}"


def sweep_grid(models, loads) -> list[SweepRun]:
    """Every (model, load) pair, models outer, loads in the given order."""
    return [SweepRun(m, float(f), folder_name(m, f)) for m in models for f in loads]


def run_parameters(base: Parameters, run: SweepRun, case=None) -> Parameters:
    """The parameters of one grid point: ``base`` with the run's model and load (and, given the
    case, ``order`` = 0 resolved to the case's order for that model, as ``pacto run`` does)."""
    p = base.with_overrides({"model": run.model, "load": repr(run.load)})
    return case.resolve(p) if case is not None else p


# -- state of the folders ------------------------------------------------------------------
def _read_json(path: Path) -> dict | None:
    try:
        data = json.loads(path.read_text())
    except (OSError, ValueError):
        return None
    return data if isinstance(data, dict) else None


def _as_json(params: Parameters) -> dict:
    return json.loads(json.dumps(params.to_dict()))


def run_status(folder: str | os.PathLike) -> str:
    """What a sweep has to do with a run folder.

    Returns
    -------
    str
        ``"done"`` if it holds a readable ``summary.json`` with an objective, ``"resume"`` if it
        holds a checkpoint (but no finished summary), ``"new"`` otherwise.
    """
    path = Path(folder)
    summ = _read_json(path / "summary.json")
    if summ is not None and "objective" in summ:
        return "done"
    if (path / "checkpoint.npz").is_file():
        return "resume"
    return "new"


def check_same_parameters(folder: str | os.PathLike, params: Parameters, status: str) -> None:
    """Refuse to reuse a finished run or a checkpoint made with other parameters.

    Raises
    ------
    InputError
        Naming the first parameter that differs, if the stored parameters are not ``params``.
    """
    path = Path(folder)
    if status == "done":
        record = _read_json(path / "summary.json") or {}
        stored = record.get("parameters")
    elif status == "resume":
        record = _read_json(path / "params.json") or {}
        stored = record.get("params")
    else:
        return
    stored = dict(stored) if isinstance(stored, dict) else {}
    # the run stores what ``--model auto`` and ``load_ramp=-1`` resolved to; compare what it
    # was asked for
    for name, choice in (("model", "model_choice"), ("load_ramp", "load_ramp_choice")):
        if isinstance(record.get(choice), dict) and "requested" in record[choice]:
            stored[name] = record[choice]["requested"]
    want = _as_json(params)
    if stored == want:
        return
    diff = next((k for k in want if stored.get(k) != want[k]), "parameters")
    raise InputError(f"sweep: '{path}' holds a run with {diff} = {stored.get(diff)!r}, this sweep "
                     f"has {diff} = {want.get(diff)!r}: use another --out or remove that folder")


# -- results -------------------------------------------------------------------------------
def table_row(out: str | os.PathLike, run: SweepRun, error: str | None = None) -> dict:
    """One row of sweep.csv from the run's ``summary.json``.

    A run without a summary (it raised, or never ran) is a row with ``converged = False`` and
    ``stopped = "error"`` (or ``"missing"`` when no error is known).
    """
    summ = _read_json(Path(out) / run.folder / "summary.json")
    row = {"model": run.model, "load": run.load, "folder": run.folder}
    if summ is None or "objective" not in summ:
        row.update(objective=None, output_displacement=None, load_reached=None, converged=False,
                   iterations=None, wall_time_s=None, stopped="error" if error else "missing")
        return row
    stopped = summ.get("stopped")
    factor = summ.get("load_factor_reached")
    if isinstance(factor, (int, float)) and factor < 1 - 1e-9:
        stopped = "newton"  # also when only the final analysis of the design failed
    row.update(objective=summ.get("objective"), output_displacement=summ.get("output_displacement"),
               load_reached=summ.get("load_reached"),
               converged=bool(summ.get("converged")) and stopped != "newton",
               iterations=summ.get("iterations"), wall_time_s=summ.get("wall_time_s"),
               stopped=stopped, objective_name=summ.get("objective_name"))
    return row


def collect_table(out: str | os.PathLike, runs, errors: dict | None = None) -> list[dict]:
    """Rows of sweep.csv for ``runs`` (grid order); ``errors`` maps folder -> error text."""
    errors = errors or {}
    return [table_row(out, r, errors.get(r.folder)) for r in runs]


def _cell(val):
    if val is None:
        return ""
    if isinstance(val, bool):
        return "true" if val else "false"
    if isinstance(val, float):
        return repr(val)
    return val


def write_csv(path: str | os.PathLike, rows: list[dict]) -> None:
    """Write the table (``COLUMNS``; empty cells for missing values, converged as true/false)."""
    buf = io.StringIO(newline="")
    w = csv.writer(buf)
    w.writerow(COLUMNS)
    for row in rows:
        w.writerow([_cell(row.get(c)) for c in COLUMNS])
    atomic_write_text(path, buf.getvalue())


def plot_sweep(path: str | os.PathLike, rows: list[dict], title: str = "",
               load_unit: str = "") -> None:
    """Output displacement and objective against load (log x), one line per model.

    Runs that did not reach their load (Newton failure) are drawn as open markers at the values
    they report; a quantity the case does not compute is stated in its panel.
    """
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    fig = Figure(figsize=(10, 4))
    FigureCanvasAgg(fig)
    axes = fig.subplots(1, 2)
    models = list(dict.fromkeys(r["model"] for r in rows))
    for ax, key, label in ((axes[0], "output_displacement", "output displacement"),
                           (axes[1], "objective", "objective")):
        pts = [r for r in rows if isinstance(r.get(key), (int, float)) and math.isfinite(r[key])]
        for i, m in enumerate(models):
            mine = sorted((r for r in pts if r["model"] == m), key=lambda r: r["load"])
            if not mine:
                continue
            color = f"C{i}"
            ax.plot([r["load"] for r in mine], [r[key] for r in mine], "-o", color=color, label=m)
            bad = [r for r in mine if r.get("stopped") in ("newton", "error")]
            if bad:
                ax.plot([r["load"] for r in bad], [r[key] for r in bad], "o", ms=11,
                        mfc="none", color="k", label=f"{m}: load not reached")
        ax.set_xscale("log")
        if pts and all(r[key] > 0 for r in pts):
            ax.set_yscale("log")
        if not pts:
            ax.text(0.5, 0.5, f"no {label} in this case", ha="center", va="center",
                    transform=ax.transAxes)
        else:
            ax.legend(fontsize=8)
        names = sorted({r["objective_name"] for r in pts if r.get("objective_name")})
        ax.set_xlabel(f"load ({load_unit})" if load_unit else "load")
        ax.set_ylabel(f"{label} ({', '.join(names)})" if key == "objective" and names else label)
        ax.grid(True, which="both", alpha=0.3)
    if title:
        fig.suptitle(title)
    fig.tight_layout()
    with atomic_path(path) as tmp:
        fig.savefig(tmp, dpi=110)


def _fmt(val, spec=".4e"):
    return "n/a" if val is None else format(val, spec)


_STOPPED = {"converged": "converged", "iterations": "iteration limit",
            "newton": "Newton failure: load not reached"}


def progress_line(i: int, n: int, row: dict, how: str) -> str:
    """One line for a finished run, e.g. ``[2/4] linear-1e5 (new): objective 5.5e+10, ...``."""
    if row["stopped"] in ("error", "missing"):
        return f"[{i}/{n}] {row['folder']} ({how}): FAILED, no summary"
    return (f"[{i}/{n}] {row['folder']} ({how}): objective {_fmt(row['objective'])}, output "
            f"displacement {_fmt(row['output_displacement'])}, load reached "
            f"{_fmt(row['load_reached'], 'g')} of {row['load']:g}, {row['iterations']} iterations "
            f"({_STOPPED.get(row['stopped'], row['stopped'])}), "
            f"{_fmt(row['wall_time_s'], '.1f')} s")


# -- execution -----------------------------------------------------------------------------
def run_one(case_name: str, params: dict, folder: str, resume: bool) -> dict:
    """One run on a Dask worker (NGSolve with one thread).

    Parameters
    ----------
    case_name : str
        Case to run (looked up on the worker): a built-in case's name or a case file's path.
    params : dict
        ``Parameters.to_dict()`` of the run.
    folder : str
        Absolute output folder of the run.
    resume : bool
        Continue from the folder's checkpoint; otherwise the folder is the sweep's own and
        holds no finished run nor a checkpoint (:func:`run_status`): what a run killed before
        its first checkpoint left there is removed first.

    Returns
    -------
    dict
        ``exit_code`` (0 finished, 1 Newton failure) and ``output`` (what the run printed).
    """
    import contextlib
    import io
    import os

    from .case import get_case
    from .runner import run_case

    os.environ["PACTO_THREADS"] = "1"  # one NGSolve thread per worker (run_case sets it)
    buf = io.StringIO()
    with contextlib.redirect_stdout(buf):
        case = get_case(case_name)
        code = run_case(case, case.parameters(params), folder, quiet=True,
                        resume=resume, overwrite=not resume)
    return {"exit_code": int(code), "output": buf.getvalue().strip()}


def require_distributed():
    """Import ``distributed`` or fail with a one-line InputError saying how to install it."""
    try:
        import distributed
    except ImportError:
        raise InputError("sweep needs dask.distributed, which is not installed: "
                         f"{INSTALL_HINT}") from None
    return distributed


def _connect(distributed, scheduler, n_workers):
    """A client and a description of the cluster (a new LocalCluster unless ``scheduler``)."""
    import logging

    import dask

    if scheduler:
        try:
            client = distributed.Client(scheduler, timeout="10s")
        except (OSError, TimeoutError, ValueError) as err:
            raise InputError(f"--scheduler: cannot connect to '{scheduler}' ({err})") from None
        workers = client.scheduler_info().get("workers", {})
        if any(w.get("nthreads", 1) > 1 for w in workers.values()):
            print("pacto sweep: warning: some workers run several threads; NGSolve runs are safest "
                  "one per process (start workers with --nthreads 1)", file=sys.stderr)
        return client, None, f"scheduler {scheduler} ({len(workers)} workers)"
    # spawned processes (the distributed default, forced here): forking a process that already
    # holds NGSolve's thread pool is not safe; one thread per worker, one run per worker
    with dask.config.set({"distributed.worker.multiprocessing-method": "spawn"}):
        cluster = distributed.LocalCluster(n_workers=n_workers, threads_per_worker=1,
                                           processes=True, dashboard_address=None,
                                           silence_logs=logging.ERROR)
    client = distributed.Client(cluster)
    return client, cluster, f"a local cluster of {n_workers} worker process(es)"


def run_sweep(case, base: Parameters, models, loads, out: str | os.PathLike, *,
              scheduler: str | None = None, workers: int | None = None,
              quiet: bool = False) -> int:
    """Run ``case`` at every (model, load) of the grid on Dask and write sweep.csv/.png.

    Parameters
    ----------
    case : Case
        An optimisation case.
    base : Parameters
        Parameters shared by every run (model and load are set per run).
    models, loads : sequence
        The grid (see :func:`parse_models`, :func:`parse_loads`).
    out : path
        Sweep folder.
    scheduler : str, optional
        Address of an existing Dask scheduler; default a new LocalCluster.
    workers : int, optional
        Worker processes of the LocalCluster (default: the machine's cores, at most one per
        run to do).
    quiet : bool
        No progress lines.

    Returns
    -------
    int
        0 if every run finished, 1 if some stopped on a Newton failure or raised.
    """
    from .runner import prepare_output

    distributed = require_distributed()
    if case.analysis_only:
        raise InputError(f"sweep: '{case.name}' is an analysis case; sweeps run optimisations")
    if workers is not None and workers < 1:
        raise InputError(f"--workers: must be >= 1 (got {workers})")
    if workers is not None and scheduler:
        raise InputError("--workers: only for the local cluster (a scheduler has its own workers)")
    root = prepare_output(out).resolve()
    runs = sweep_grid(models, loads)
    params = {r.folder: run_parameters(base, r, case) for r in runs}
    status = {r.folder: run_status(root / r.folder) for r in runs}
    for r in runs:
        check_same_parameters(root / r.folder, params[r.folder], status[r.folder])
    todo = [r for r in runs if status[r.folder] != "done"]
    t0 = time.perf_counter()
    errors, codes, done_now = {}, {}, 0
    n = len(runs)
    how = {"new": "new", "resume": "resumed from checkpoint"}
    header = (f"sweep {case.name}: {n} runs ({len(models)} models x {len(loads)} loads), "
              f"{n - len(todo)} already done, {len(todo)} to run")
    if not todo and not quiet:
        print(f"{header} — output in {root}", flush=True)
    if todo:
        n_workers = workers or os.cpu_count() or 1
        client, cluster, where = _connect(distributed, scheduler, min(n_workers, len(todo)))
        try:
            if not quiet:
                print(f"{header} on {where} — output in {root}", flush=True)
            futures = {}
            for r in todo:
                fut = client.submit(run_one, case.file or case.name, params[r.folder].to_dict(),
                                    str(root / r.folder), status[r.folder] == "resume",
                                    pure=False, key=f"pacto-{r.folder}-{time.time_ns()}")
                futures[fut] = r
            for fut in distributed.as_completed(futures):
                r = futures[fut]
                try:
                    codes[r.folder] = fut.result()["exit_code"]
                except Exception as exc:  # raised on the worker, or the worker died
                    errors[r.folder] = f"{type(exc).__name__}: {exc}"
                    codes[r.folder] = 1
                done_now += 1
                row = table_row(root, r, errors.get(r.folder))
                if not quiet:
                    line = progress_line(n - len(todo) + done_now, n, row, how[status[r.folder]])
                    if r.folder in errors:
                        line += f" ({errors[r.folder]})"
                    print(line, flush=True)
        finally:
            client.close()
            if cluster is not None:
                cluster.close()
    rows = collect_table(root, runs, errors)
    write_csv(root / "sweep.csv", rows)
    plot_sweep(root / "sweep.png", rows, f"{case.name}: sweep over load", case.load_unit)
    failed = [r["folder"] for r in rows if r["stopped"] in ("newton", "error", "missing")]
    if not quiet or failed:
        msg = f"{len(todo)} runs in {time.perf_counter() - t0:.1f} s" if todo else "nothing to run"
        if failed:
            msg += f"; load not reached in {', '.join(failed)}"
        print(f"sweep: {msg} — {root / 'sweep.csv'}, {root / 'sweep.png'}")
    return 1 if failed or any(codes.values()) else 0

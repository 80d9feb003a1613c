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
checkpoint.  This module runs the sweep; its grid and the state of its folders are
:mod:`pacto_ng.sweep_plan`, its table and picture :mod:`pacto_ng.sweep_table` (pure functions of
their arguments and of the files in DIR, no Dask).
"""
from __future__ import annotations

import contextlib
import io
import logging
import os
import sys
import time

from .case import get_case
from .errors import InputError
from .params import Parameters
from .runner import prepare_output, run_case
from .sweep_plan import check_same_parameters, run_parameters, run_status, sweep_grid
from .sweep_table import collect_table, plot_sweep, progress_line, table_row, write_csv

INSTALL_HINT = 'pip install "pacto_ng[cluster]"'


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
    errors, codes = {}, {}
    n = len(runs)
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
            errors, codes = _run_on_cluster(distributed, client, case, todo, params, status,
                                            root, n, quiet)
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


def _run_on_cluster(distributed, client, case, todo, params, status, root, n: int,
                    quiet: bool) -> tuple[dict, dict]:
    """The runs ``todo`` as tasks on the cluster, a progress line as each ends (``n``: the
    grid's runs).  Returns ``(errors, codes)`` by folder: what a run that raised (on the
    worker, or the worker died) raised, and every run's exit code."""
    how = {"new": "new", "resume": "resumed from checkpoint"}
    errors, codes = {}, {}
    futures = {}
    for r in todo:
        fut = client.submit(run_one, case.file or case.name, params[r.folder].to_dict(),
                            str(root / r.folder), status[r.folder] == "resume",
                            pure=False, key=f"pacto-{r.folder}-{time.time_ns()}")
        futures[fut] = r
    done_now = 0
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
    return errors, codes

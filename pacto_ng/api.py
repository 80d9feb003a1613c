"""Run a case from Python (scripts, notebooks) and get the result as an object.

>>> import pacto_ng as pn
>>> result = pn.run("mbb", iterations=5, nelx=30, nely=10)      # doctest: +SKIP
>>> result.summary["objective"], result.rho_bar.shape            # doctest: +SKIP
>>> result = pn.run("my_case.py", out="output/mine")             # doctest: +SKIP
>>> again = pn.load_result("output/mine")                        # doctest: +SKIP

:func:`run` takes a built-in case's name, a case file's path or a :class:`~pacto_ng.case.Case`
built in the script itself, and any parameter as a keyword (the names of ``pacto run
--show-parameters``).  It writes the same output folder as ``pacto run`` and returns a
:class:`Result`: the design, the fields, the history and the summary.  :func:`load_result`
reads a finished run folder back (e.g. one written by ``pacto run``).  A walk-through from
geometry to STL: docs/tutorial.md.
"""
from __future__ import annotations

import csv
import os
import tempfile
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from .case import Case, get_case
from .errors import InputError
from .gradcheck import check_case
from .params import Parameters
from .problem import Problem
from .runner import optimise_case
from .threads import compute


@dataclass
class Result:
    """A finished run.

    Attributes
    ----------
    folder : Path
        The run's output folder (summary.json, history.csv, design.vtu, pictures, checkpoint).
    exit_code : int
        0 finished (converged or at the iteration cap), 1 stopped by a Newton failure (the last
        good design is reported).
    summary : dict
        summary.json: objective, volume fraction, output displacement, load reached, ...
    history : list of dict
        history.csv, one row per iteration.
    x : numpy.ndarray
        The reported design variables (one per design element; two fields stacked for
        two-material cases).
    problem : Problem
        The case's problem with the reported design analysed: ``problem.mesh``,
        ``problem.values`` (``rho_bar``, ``p``, ``u``, responses), ``problem.mech.u`` (the
        displacement), ``problem.pressure_block.pressure`` (the pressure, pressure cases).
    """

    folder: Path
    exit_code: int
    summary: dict
    history: list
    x: np.ndarray
    problem: Problem

    @property
    def rho_bar(self) -> np.ndarray:
        """Physical element densities ρ̄ of the reported design (NGSolve's element order)."""
        vals = self.problem.values
        return np.asarray(vals["rho_bar"] if "rho_bar" in vals else vals["rho_bar1"])

    @property
    def objective(self) -> float:
        """The final objective of summary.json (the value the optimiser minimised, e.g. the
        compliance, or -Δ/SE for a mechanism)."""
        return float(self.summary["objective"])

    @property
    def mesh(self):
        """The ``ngsolve.Mesh`` of the run."""
        return self.problem.mesh

    @property
    def displacement(self):
        """The displacement ``GridFunction`` of the reported design at the reported load."""
        return self.problem.mech.u

    @property
    def pressure(self):
        """The Darcy pressure ``GridFunction`` (``None`` for cases without a pressure load)."""
        blk = self.problem.pressure_block
        return None if blk is None else blk.pressure


def case_parameters(case: Case, settings: dict) -> Parameters:
    """The case's defaults with ``settings`` (parameter name -> value) applied, as
    ``--set NAME=VALUE`` would.  Giving ``maxh`` alone switches a quad case to triangles."""
    known = set(Parameters.names())
    for name in settings:
        if name not in known:
            raise InputError(f"{name}: unknown parameter (see 'pacto run CASE --show-parameters')")
    changes = {k: str(v) for k, v in settings.items()}
    if "maxh" in settings and "nelx" not in settings:
        changes.update(nelx="0", nely="0", nelz="0")
    return case.defaults.with_overrides(changes)


def run(case: Case | str | os.PathLike, out: str | os.PathLike | None = None, *,
        quiet: bool = True, overwrite: bool = False, part: bool = True, **settings) -> Result:
    """Optimise a case and return its :class:`Result`.

    Parameters
    ----------
    case : Case, str or path
        A :class:`~pacto_ng.case.Case`, a built-in case's name (``pacto cases``) or the path of
        a case file that defines ``CASE``.
    out : str or path, optional
        Output folder (default: a new temporary folder).
    quiet : bool
        No line per iteration (default True).
    overwrite : bool
        Remove an earlier run's files in ``out`` first (default False: a folder that holds a
        run is refused with an InputError, as by ``pacto run``).
    part : bool
        End with the part made, checked and analysed (docs/guide.md, "The part"; default True);
        False leaves it to :func:`pacto_ng.post.analyse.analyse_run` (``pacto analyse DIR``).
    **settings
        Any parameter by name, e.g. ``model="neohookean"``, ``load=1e5``, ``iterations=50``,
        ``maxh=0.002`` (default: the case's; ``iterations`` is 100 unless the case sets it).

    Returns
    -------
    Result
        The finished run, its reported design analysed (``exit_code`` 1 when a Newton failure
        stopped it: the last good design).

    Raises
    ------
    InputError
        Bad input (an unknown parameter, a value out of range, a name the geometry lacks, an
        error in a case file), with a one-line message.

    Examples
    --------
    >>> result = run("my_case.py", out="output/mine", iterations=10)   # doctest: +SKIP
    >>> result.objective, result.summary["volume_fraction"]             # doctest: +SKIP
    """
    # the post package loads matplotlib and pyvista at its import (0.5 s on ``import pacto_ng``)
    from .post.part_stage import finish_run

    if not isinstance(case, Case):
        case = get_case(os.fspath(case))
    params = case_parameters(case, settings)
    folder = Path(out) if out is not None else Path(tempfile.mkdtemp(prefix=f"pacto-{case.name}-"))
    done = optimise_case(case, params, folder, quiet=quiet, overwrite=overwrite)
    summary = (finish_run(folder, done.problem, done.summary, quiet=quiet) if part else
               done.summary)
    return Result(folder, done.exit_code, summary, done.history, done.x, done.problem)


def check_gradients(case: Case | str | os.PathLike, *, seed: int = 0, quiet: bool = True,
                    **settings) -> float:
    """Check the adjoint gradients of a case's chain against finite differences, as ``pacto
    check-gradients`` does, and return the worst relative error.

    Every value the optimiser sees (objective, constraints) and every reported response is
    differentiated along random directions on a random design (a coarse mesh unless
    ``settings`` give ``maxh`` or ``nelx``); 1e-5 is the command's pass tolerance.

    Examples
    --------
    >>> check_gradients("my_case.py") < 1e-5                              # doctest: +SKIP
    """
    if not isinstance(case, Case):
        case = get_case(os.fspath(case))
    params = case_parameters(case, settings)
    explicit = any(k in settings for k in ("maxh", "nelx", "nely", "nelz"))
    return check_case(case, params, seed=seed, quiet=quiet, explicit_mesh=explicit)


def load_result(folder: str | os.PathLike, *, case: Case | None = None,
                exit_code: int | None = None) -> Result:
    """The :class:`Result` of a finished run folder (its final design analysed again).

    Parameters
    ----------
    folder : str or path
        A run's output folder (``pacto run ... --out DIR`` or :func:`run`'s ``out``).
    case : Case, optional
        The run's case: needed for a case built in a script or notebook (a run folder finds
        only built-in cases and case files again); an InputError if the folder is another
        case's.
    exit_code : int, optional
        The run's exit code (default: 1 if summary.json says a Newton failure stopped it,
        else 0).

    Raises
    ------
    InputError
        The folder holds no finished run, or its case (file) is not found.
    """
    from .post.runs import load_run, rebuild  # the post package: see run()

    folder = Path(folder)
    run_ = load_run(folder, "load_result", case=case)
    with compute():
        problem = rebuild(run_)
    with open(folder / "history.csv", newline="") as fh:
        # (a column added after a resumed run's first rows is empty there: NaN)
        history = [{k: float(v) if v != "" else float("nan") for k, v in row.items()}
                   for row in csv.DictReader(fh)]
    code = exit_code if exit_code is not None else (1 if run_.summary.get("stopped") == "newton"
                                                     else 0)
    return Result(folder, code, run_.summary, history, run_.x, problem)
